"""Solver strategies: small objects naming the compiled integrator and its tolerances."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError


@dataclass(frozen=True)
class Solver:
    """Adaptive integrator settings.

    ``atol`` is a number for every state, a mapping state name -> value, or None for
    ``rtol`` × the typical magnitude of each state (stroke, p_atm, Fs/σ0, ...).
    """

    rtol: float = 1e-6
    atol: float | Mapping[str, float] | None = None
    h_init: float = 1e-5
    h_max: float = math.inf
    max_steps: int = 5_000_000
    kernel_function = "integrate_rodas4"
    explicit = False

    def __post_init__(self):
        if not (np.isfinite(self.rtol) and 1e-14 <= self.rtol < 1):
            raise ParameterError(f"solver rtol = {self.rtol}: must be in [1e-14, 1)")
        if not self.h_init > 0:
            raise ParameterError(f"solver h_init = {self.h_init}: must be > 0")
        if not self.h_max > 0:
            raise ParameterError(f"solver h_max = {self.h_max}: must be > 0")

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
        if not self.atol > 0:
            raise ParameterError(f"solver atol = {self.atol}: must be > 0")
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


@dataclass(frozen=True)
class DormandPrince(Solver):
    """Explicit Dormand-Prince 5(4); fine for non-stiff set-ups (no bristle stiffness)."""

    kernel_function = "integrate_dopri5"
    explicit = True
