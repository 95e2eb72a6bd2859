"""Forward parameter sensitivities d(signal)/d(parameter) along a simulation.

The sensitivities are integrated with the state inside the compiled RODAS4 loop, reusing
its Jacobian and LU factors (see ``integrate_rodas4_sens``); the derived outputs
(friction, pressure, flows) get theirs by the chain rule at the output times. For
identification they are the columns of the least-squares Jacobian; for local sensitivity
analysis ``relative()`` gives θ·∂y/∂θ, comparable across parameters.
"""

from __future__ import annotations

import time as _time
from collections.abc import Sequence
from dataclasses import dataclass

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
    """The simulation and, per signal, an array (n_time × n_parameters) of ∂signal/∂θ."""

    result: Result
    parameters: list[str]
    values: np.ndarray
    sensitivities: dict[str, np.ndarray]

    def __getitem__(self, signal: str) -> np.ndarray:
        return self.sensitivities[signal]

    def relative(self, signal: str) -> np.ndarray:
        """θ·∂signal/∂θ: the change of the signal per relative change of each parameter."""
        return self.sensitivities[signal] * self.values[None, :]

    def to_pandas(self) -> pd.DataFrame:
        """Long table: time, signal, parameter, sensitivity (SI units of signal/parameter)."""
        frames = []
        for name, arr in self.sensitivities.items():
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


def _initial_sensitivity(model, experiment, names: list[str]) -> np.ndarray:
    """∂y0/∂θ of the static-equilibrium start, by central differences."""
    base = model.params
    cols = []
    for name in names:
        value = base[name]
        step = 1e-6 * (abs(value) if value != 0 else 1.0)
        ys = []
        for sign in (1.0, -1.0):
            changed = type(model).__new__(type(model))
            for f in model.__dataclass_fields__:
                object.__setattr__(changed, f, getattr(model, f))
            object.__setattr__(changed, "params", base.replace({name: value + sign * step}))
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
    s0 = _initial_sensitivity(model, experiment, names)
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
    k = np.clip(np.searchsorted(bp, t_out, side="right") - 1, 0, bp.size - 2)
    ts_out = 0.5 * (bp[k] + bp[k + 1])
    d_out = np.empty((t_out.size, kernel.NOUT, len(names)))
    kernel.output_sensitivities(t_out, ts_out, y_out, s_out, prm, pidx, sig, ptr, d_out)
    result = Result.from_kernel(kernel, model, experiment, solver, t_out, y_out, out, info,
                                wall)
    sens: dict[str, np.ndarray] = {}
    for i, name in enumerate(kernel.STATE_NAMES):
        sens[name] = s_out[:, i, :].copy()
    for i, name in enumerate(kernel.OUTPUT_NAMES):
        if name == "drive":
            name = f"drive_{experiment.quantity}"
        if name not in sens and name in result.signals:
            sens[name] = d_out[:, i, :].copy()
    return SensitivityResult(result, names, prm[pidx].copy(), sens)
