"""Solver strategies: small objects naming the compiled integrator and its tolerances."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..checks import check_int, check_positive, check_range
from ..errors import ParameterError


def _real_or_inf(name: str, value, where: str) -> float:
    """A number > -inf: inf allowed (no limit), NaN not."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Real) or math.isnan(value):
        check_positive(name, value, where=where, error=ParameterError)  # raises
    return float(value)


#: the step limit of a run unless one is given: this many, or STEPS_PER_SEGMENT per
#: interval between input breakpoints if that is more (a long measured input: a 2-hour
#: record at 1 kHz has 7.2 million intervals, each needing at least one step)
DEFAULT_MAX_STEPS = 5_000_000
STEPS_PER_SEGMENT = 50


@dataclass(frozen=True)
class Solver:
    """Adaptive integrator settings.

    ``atol`` is a number for every state, a mapping state name -> value, or None for
    ``rtol`` × the typical magnitude of each state (stroke, p_atm, Fs/σ0, ...).
    ``max_steps`` limits the accepted steps of one run; None (the default) follows the
    input: DEFAULT_MAX_STEPS, or STEPS_PER_SEGMENT per interval between its breakpoints.
    """

    rtol: float = 1e-6
    atol: float | Mapping[str, float] | None = None
    h_init: float = 1e-5
    h_max: float = math.inf
    max_steps: int | None = None
    kernel_function = "integrate_rodas4"
    #: the same integrator writing the states only (the batch engine's, where it keeps
    #: no derived output)
    states_function = "integrate_rodas4_states"
    explicit = False

    def __post_init__(self):
        where = type(self).__name__
        check_range("rtol", self.rtol, 1e-14, 1.0, high_open=True, where=where,
                    error=ParameterError)
        check_positive("h_init", self.h_init, unit="s", where=where, error=ParameterError)
        h_max = _real_or_inf("h_max", self.h_max, where)
        if not h_max > 0:
            raise ParameterError(f"{where}: h_max = {h_max:g} s: must be > 0")
        if self.max_steps is not None:
            check_int("max_steps", self.max_steps, minimum=1, where=where,
                      error=ParameterError)
        atol = self.atol
        if atol is not None and not isinstance(atol, Mapping):
            check_positive("atol", atol, where=where, error=ParameterError)
        elif isinstance(atol, Mapping):
            for name, value in atol.items():
                check_positive(f"atol[{name!r}]", value, where=where, error=ParameterError)

    def step_limit(self, n_segments: int) -> int:
        """The step limit of a run whose input has ``n_segments`` intervals."""
        if self.max_steps is not None:
            return int(self.max_steps)
        return max(DEFAULT_MAX_STEPS, STEPS_PER_SEGMENT * int(n_segments))

    def atol_vector(self, state_names: tuple[str, ...], scales: np.ndarray) -> np.ndarray:
        if self.atol is None:
            return self.rtol * np.asarray(scales, dtype=float)
        if isinstance(self.atol, Mapping):
            unknown = set(self.atol) - set(state_names)
            if unknown:
                raise ParameterError(
                    f"solver atol names unknown state(s) {sorted(unknown)}; states: "
                    f"{', '.join(state_names)}"
                )
            base = self.rtol * np.asarray(scales, dtype=float)
            return np.array([self.atol.get(n, b) for n, b in zip(state_names, base,
                                                                  strict=True)])
        return np.full(len(state_names), float(self.atol))

    def atol_overrides(self, state_names: tuple[str, ...]) -> np.ndarray:
        """Per state: the absolute tolerance the user fixed, or 0 where the default
        rule (rtol × the state's typical magnitude) applies (the batch loop's input)."""
        if self.atol is None:
            return np.zeros(len(state_names))
        return self.atol_vector(state_names, np.zeros(len(state_names)))


@dataclass(frozen=True)
class Rodas4(Solver):
    """Rosenbrock RODAS4 (L-stable, order 4) with the analytic Jacobian; the default."""

    kernel_function = "integrate_rodas4"
    states_function = "integrate_rodas4_states"


@dataclass(frozen=True)
class DormandPrince(Solver):
    """Explicit Dormand-Prince 5(4); fine for non-stiff set-ups (no bristle stiffness)."""

    kernel_function = "integrate_dopri5"
    states_function = "integrate_dopri5_states"
    explicit = True
