"""Forward parameter sensitivities d(signal)/d(parameter) along a simulation.

The sensitivities are integrated with the state inside the compiled RODAS4 loop, reusing
its Jacobian and LU factors (see ``integrate_rodas4_sens``); the derived outputs
(friction, pressure, flows) get theirs by the chain rule at the output times. For
identification they are the columns of the least-squares Jacobian; for local sensitivity
analysis ``relative()`` gives θ·∂y/∂θ, comparable across parameters.
"""

from __future__ import annotations

import dataclasses
import functools
import time as _time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..errors import ParameterError, SolverError
from ..models.friction import FRICTION_SENS
from ..parameters.spec import INDEX, SPECS
from .result import Result
from .simulate import STATUS_TEXT, prepare
from .solvers import Rodas4


@dataclass(eq=False)
class SensitivityResult:
    """The simulation and, per signal, an array (n_time × n_parameters) of ∂signal/∂θ.

    State sensitivities come from the integration; those of derived outputs (friction,
    pressure of a source, flows) are computed by the chain rule on first access only.
    """

    result: Result
    parameters: list[str]
    values: np.ndarray
    sensitivities: dict[str, np.ndarray]
    _derived: dict[str, Callable[[], np.ndarray]] = field(default_factory=dict, repr=False)

    @property
    def signals(self) -> list[str]:
        return list(self.sensitivities) + [n for n in self._derived
                                           if n not in self.sensitivities]

    def __getitem__(self, signal: str) -> np.ndarray:
        if signal not in self.sensitivities:
            if signal not in self._derived:
                raise KeyError(f"no sensitivity of {signal!r}; signals: "
                               f"{', '.join(self.signals)}")
            self.sensitivities[signal] = self._derived[signal]()
        return self.sensitivities[signal]

    def relative(self, signal: str) -> np.ndarray:
        """θ·∂signal/∂θ: the change of the signal per relative change of each parameter."""
        return self[signal] * self.values[None, :]

    def to_pandas(self) -> pd.DataFrame:
        """Long table: time, signal, parameter, sensitivity (SI units of signal/parameter)."""
        frames = []
        for name in self.signals:
            arr = self[name]
            for k, par in enumerate(self.parameters):
                frames.append(pd.DataFrame({
                    "time": self.result.time, "signal": name, "parameter": par,
                    "sensitivity": arr[:, k],
                    "unit": f"{self.result.units[name]}/({SPECS[par].unit or '1'})",
                }))
        return pd.concat(frames, ignore_index=True)


def _check_names(parameters: Sequence[str]) -> list[str]:
    import difflib

    names = list(parameters)
    if not names:
        raise ParameterError("sensitivities: give at least one parameter name")
    for name in names:
        if name not in INDEX:
            close = difflib.get_close_matches(name, INDEX, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise ParameterError(f"sensitivities: unknown parameter '{name}'{hint}")
    return names


def _initial_sensitivity(model, experiment, names: list[str], n_state: int) -> np.ndarray:
    """∂y0/∂θ of the static-equilibrium start, by central differences."""
    base = model.params
    cols = []
    for name in names:
        if name not in model.initial_state_parameters:
            cols.append(np.zeros(n_state))
            continue
        value = base[name]
        step = 1e-6 * (abs(value) if value != 0 else 1.0)
        ys = []
        for sign in (1.0, -1.0):
            changed = dataclasses.replace(model, params=base.replace({name: value + sign * step}))
            ys.append(changed.initial_state(experiment.drive, experiment.t_start))
        cols.append((ys[0] - ys[1]) / (2 * step))
    return np.column_stack(cols)


def simulate_sensitivities(model, experiment, parameters: Sequence[str], solver=None, *,
                           t_eval=None) -> SensitivityResult:
    """Simulate and integrate ∂y/∂θ for ``parameters`` (names of the parameter catalogue).

    Only the RODAS4 solver carries sensitivities.
    """
    solver = Rodas4() if solver is None else solver
    if solver.kernel_function != "integrate_rodas4":
        raise ParameterError(
            f"sensitivities need the Rodas4 solver, got {type(solver).__name__}"
        )
    names = _check_names(parameters)
    kernel, prm, sig, ptr, bp, t_out, y0, atol = prepare(model, experiment, solver, t_eval)
    pidx = np.array([INDEX[n] for n in names], dtype=np.int64)
    pfast = np.array([FRICTION_SENS.index(n) if n in FRICTION_SENS else -1 for n in names],
                     dtype=np.int64)
    s0 = _initial_sensitivity(model, experiment, names, y0.size)
    y_out = np.empty((t_out.size, kernel.NSTATE))
    out = np.empty((t_out.size, kernel.NOUT))
    s_out = np.empty((t_out.size, kernel.NSTATE, len(names)))
    info = np.zeros(8)
    start = _time.perf_counter()
    y_end = kernel.integrate_rodas4_sens(y0, prm, sig, ptr, bp, t_out, solver.rtol, atol,
                                         solver.h_init, solver.h_max, solver.max_steps,
                                         y_out, out, info, pidx, pfast, s0,
                                         s_out)
    wall = _time.perf_counter() - start
    if info[0] != 0:
        raise SolverError(f"Rodas4 with sensitivities failed at t = {info[1]:.9g} s: "
                          f"{STATUS_TEXT.get(int(info[0]), 'unknown failure')}; state {y_end}")
    result = Result.from_kernel(kernel, model, experiment, solver, t_out, y_out, out, info,
                                wall)
    sens: dict[str, np.ndarray] = {}
    for i, name in enumerate(kernel.STATE_NAMES):
        sens[name] = s_out[:, i, :].copy()
    derived: dict[str, Callable[[], np.ndarray]] = {}
    all_outputs: list[np.ndarray] = []

    def output_column(i: int) -> np.ndarray:
        if not all_outputs:  # one pass computes every output's sensitivity
            k = np.clip(np.searchsorted(bp, t_out, side="right") - 1, 0, bp.size - 2)
            ts_out = 0.5 * (bp[k] + bp[k + 1])
            d_out = np.empty((t_out.size, kernel.NOUT, len(names)))
            kernel.output_sensitivities(t_out, ts_out, y_out, s_out, prm, pidx, sig, ptr,
                                        d_out)
            all_outputs.append(d_out)
        return all_outputs[0][:, i, :].copy()

    for i, name in enumerate(kernel.OUTPUT_NAMES):
        if name == "drive":
            name = f"drive_{experiment.quantity}"
        if name not in sens and name in result.signals:
            derived[name] = functools.partial(output_column, i)
    return SensitivityResult(result, names, prm[pidx].copy(), sens, derived)
