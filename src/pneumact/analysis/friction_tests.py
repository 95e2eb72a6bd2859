"""Running and analysing the classic friction experiments (``experiments.friction``).

``run_friction_test(test, params, friction)`` simulates every rig set-up of a test and
derives its table: the friction-velocity curve against the analytic steady state, the
presliding loop, the frictional-lag loops, the break-away force against the force rate.
The helpers (first crossing, break-away force, slip onsets, lag-loop width) work on any
``Result`` of a friction rig.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ExperimentError
from ..experiments.friction import (
    BreakAway,
    FrictionalLag,
    FrictionTest,
    Presliding,
    RigSetup,
    SteadyState,
    StickSlip,
    friction_test,
)
from ..io.report import ResultVocabulary
from ..models.friction import FrictionModel, LuGre
from ..models.rig import FrictionRig
from ..simulation.result import Result
from ..simulation.simulate import simulate
from ..simulation.solvers import Rodas4

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["FrictionTestResult", "break_away_force", "first_crossing", "lag_loop_width",
           "run_friction_test", "slip_onsets", "solver_for"]


@dataclass(eq=False)
class FrictionTestResult(ResultVocabulary):
    """Outcome of one friction experiment.

    ``to_pandas()``: the derived numbers (``table``; the signals when there are none),
    ``"signals"``: the representative run's signals; ``plot()``: the axes that suit the
    experiment (``plotting.plot_friction_test``); ``write(folder)``: the tables, the
    figure and report.html.

    ``result`` is the simulation (for multi-run experiments a representative run: the
    slowest force rate of break-away, the fastest frequency of frictional lag; every run is
    in ``runs``, keyed by rate or frequency). ``table`` holds the derived numbers with SI
    units in the column names, or None. ``test`` is the settings object that was run.
    """

    kind: str
    result: Result
    table: pd.DataFrame | None
    drive_quantity: str
    runs: dict[float, Result] = field(default_factory=dict)
    test: FrictionTest | None = None

    report_title = "Friction experiment"
    figure_name = "friction_test"

    def tables(self) -> dict[str, pd.DataFrame]:
        tables = {} if self.table is None else {"results": self.table}
        tables["signals"] = self.result.to_pandas()
        return tables

    def report_text(self) -> str:
        return f"{self.kind} experiment ({self.test!r}), driven by {self.drive_quantity}."

    def plot(self) -> Figure:
        """The axes that suit this experiment (``plotting.plot_friction_test``)."""
        from ..plotting import plot_friction_test

        return plot_friction_test(self, self.kind)


def solver_for(test: FrictionTest, params, friction: FrictionModel | None = None) -> Rodas4:
    """Rodas4 at the test's rtol, absolute tolerances scaled to the law's presliding range.

    The rig has no natural state scales, so atol is ``atol_factor`` × the presliding range
    (position and every friction state; Fs/σ0 for LuGre) and × range·√(stiffness/m)
    (velocity, the presliding oscillation). A static map has neither: its regularisation
    speed v_reg scales the velocity, and v_reg × 10 ms the position.
    """
    friction = LuGre() if friction is None else friction
    stiffness = friction.presliding_stiffness(params)
    if stiffness > 0.0:
        x_scale = friction.presliding_range(params)
        v_scale = x_scale * math.sqrt(stiffness / params["m"])
    else:
        v_scale = params["v_reg"]
        x_scale = 1e-2 * v_scale
    f = test.atol_factor
    atol = {"position": f * x_scale, "velocity": f * v_scale}
    atol.update({name: f * x_scale for name in friction.state_names})
    return Rodas4(rtol=test.rtol, atol=atol)


# -- analysis ------------------------------------------------------------------------------
def first_crossing(time: np.ndarray, values: np.ndarray, level: float) -> float:
    """First time ``values`` reaches ``level`` from below (linear between samples); nan if
    never."""
    above = np.flatnonzero(values >= level)
    if above.size == 0:
        return math.nan
    i = int(above[0])
    if i == 0:
        return float(time[0])
    v0, v1 = values[i - 1], values[i]
    return float(time[i - 1] + (level - v0) / (v1 - v0) * (time[i] - time[i - 1]))


def break_away_force(result: Result, threshold: float = 1e-4) -> tuple[float, float]:
    """(peak friction, applied force) of a force-ramp run at break-away [N].

    Break-away is when the displacement first exceeds ``threshold`` [m]. The peak friction
    force up to that moment is the static friction the contact delivered (Canudas et al.
    1995 report it falling with the force rate); the applied force at that moment also
    contains the force that accelerated the mass. Both are nan if the body never moves
    that far.
    """
    t = first_crossing(result.time, result["position"], threshold)
    if math.isnan(t):
        return math.nan, math.nan
    i = int(np.searchsorted(result.time, t, side="right"))
    peak = max(float(np.max(result["friction"][:i])),
               float(np.interp(t, result.time, result["friction"])))
    return peak, float(np.interp(t, result.time, result["drive_force"]))


def slip_onsets(result: Result, slip_velocity: float) -> np.ndarray:
    """Times where the velocity rises through ``slip_velocity`` (start of each slip)."""
    v = result["velocity"]
    idx = np.flatnonzero((v[:-1] < slip_velocity) & (v[1:] >= slip_velocity))
    t0, t1 = result.time[idx], result.time[idx + 1]
    return t0 + (slip_velocity - v[idx]) / (v[idx + 1] - v[idx]) * (t1 - t0)


def lag_loop_width(velocity: np.ndarray, friction: np.ndarray, n_grid: int = 101) -> float:
    """Largest friction difference between the accelerating and decelerating branches of
    one period of a friction-velocity loop, over their common velocity range [N]."""
    i_lo, i_hi = int(np.argmin(velocity)), int(np.argmax(velocity))
    v = np.roll(velocity, -i_lo)
    f = np.roll(friction, -i_lo)
    k = (i_hi - i_lo) % velocity.size
    up_v, up_f = v[: k + 1], f[: k + 1]
    down_v, down_f = v[k:][::-1], f[k:][::-1]
    lo = max(up_v.min(), down_v.min())
    hi = min(up_v.max(), down_v.max())
    grid = np.linspace(lo, hi, n_grid)[1:-1]
    up = np.interp(grid, *_monotone(up_v, up_f))
    down = np.interp(grid, *_monotone(down_v, down_f))
    return float(np.max(np.abs(up - down)))


def _monotone(v, f):
    order = np.argsort(v, kind="stable")
    v, f = v[order], f[order]
    keep = np.concatenate([[True], np.diff(v) > 0])
    return v[keep], f[keep]


# -- per-kind tables -----------------------------------------------------------------------
def _steady_state_table(test, params, friction, runs):
    (setup, result), = runs
    ends = np.asarray(setup.marks)
    at_end = np.searchsorted(result.time, ends)
    v = result["drive_velocity"][at_end]
    return pd.DataFrame({"velocity [m/s]": v, "friction [N]": result["friction"][at_end],
                         "steady-state friction [N]": friction.steady_force(v, params)})


def _presliding_table(test, params, friction, runs):
    (_, result), = runs
    return pd.DataFrame({"force [N]": result["drive_force"],
                         "position [m]": result["position"]})


def _lag_table(test, params, friction, runs):
    parts = []
    for setup, result in runs:
        last = result.time >= setup.marks[0] - 1e-12 * setup.experiment.t_end
        v = result["drive_velocity"][last]
        parts.append(pd.DataFrame({
            "frequency [Hz]": setup.key, "time [s]": result.time[last], "velocity [m/s]": v,
            "friction [N]": result["friction"][last],
            "steady-state friction [N]": friction.steady_force(v, params)}))
    return pd.concat(parts, ignore_index=True)


def _break_away_table(test, params, friction, runs):
    forces = [break_away_force(result, test.threshold) for _, result in runs]
    return pd.DataFrame({"force rate [N/s]": [setup.key for setup, _ in runs],
                         "break-away force [N]": [f[0] for f in forces],
                         "applied force at break-away [N]": [f[1] for f in forces]})


_TABLES = {SteadyState: _steady_state_table, Presliding: _presliding_table,
           FrictionalLag: _lag_table, BreakAway: _break_away_table, StickSlip: None}
#: which run stands for a multi-run test: the slowest force rate, the fastest frequency
_REPRESENTATIVE = {BreakAway: min, FrictionalLag: max}


def _run(setup: RigSetup, params, friction, solver) -> Result:
    rig = FrictionRig(params, friction, drive=setup.drive)
    t_eval = None
    if setup.marks and setup.drive == "velocity" and setup.key is None:  # plateau ends
        t_eval = np.union1d(setup.experiment.output_times(), np.asarray(setup.marks))
    return simulate(rig, setup.experiment, solver, t_eval=t_eval, y0=setup.initial_state)


def run_friction_test(test: FrictionTest | str, params, friction: FrictionModel | None = None,
                      solver=None, **settings) -> FrictionTestResult:
    """Run one classic friction experiment on a ``FrictionRig`` and derive its table.

    ``test`` is a settings object (``SteadyState(speeds=...)``) or a kind name with
    ``settings`` as keywords; the solver defaults to ``solver_for(test, params, friction)``.
    """
    if isinstance(test, str):
        test = friction_test(test, **settings)
    elif settings:
        raise ExperimentError(f"{test.kind}: give settings either in the test object or as "
                              f"keywords, not both ({', '.join(settings)})")
    friction = LuGre() if friction is None else friction
    if test.kind != "stick-slip" and not max(params["Fs"], params["Fc"]) > 0:
        raise ExperimentError(f"{test.kind}: the test measures friction, but parameter set "
                              f"'{getattr(params, 'name', 'custom')}' has none (Fc = Fs = "
                              "0); give a set with friction (stick-slip runs without)")
    solver = solver_for(test, params, friction) if solver is None else solver
    runs = [(setup, _run(setup, params, friction, solver))
            for setup in test.setups(params, friction)]
    tabulate = _TABLES[type(test)]
    table = None if tabulate is None else tabulate(test, params, friction, runs)
    keyed = {setup.key: result for setup, result in runs if setup.key is not None}
    pick = _REPRESENTATIVE.get(type(test))
    result = keyed[pick(keyed)] if pick is not None else runs[0][1]
    return FrictionTestResult(test.kind, result, table, runs[0][0].experiment.quantity,
                              keyed, test)
