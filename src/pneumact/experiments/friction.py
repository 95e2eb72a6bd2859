"""The classic friction experiments of Canudas de Wit, Olsson, Åström & Lischinsky (1995).

"A new model for control of systems with friction", IEEE TAC 40(3), 419-425: the
experiments that show what the LuGre model reproduces, run on a ``FrictionRig`` (a mass
with friction, driven by a force, a velocity or a spring):

- ``steady-state``: a staircase of constant velocities gives the friction-velocity curve
  (Stribeck curve), compared with the model's analytic steady state.
- ``presliding``: a slow force triangle below the break-away force gives the hysteretic
  force-displacement loop of presliding, with initial stiffness sigma0.
- ``frictional-lag``: a sinusoidal velocity that never reverses gives a friction-velocity
  loop that opens as the frequency grows (friction lags the velocity).
- ``break-away``: force ramps at several rates; the break-away force (the peak friction
  before the body has slid 0.1 mm) falls from Fs towards Fc as the force rate grows
  (the paper's "varying break-away force").
- ``stick-slip``: a spring pulled at constant speed drags the mass in periodic stick-slip.

Each builder returns a ``RigSetup`` (rig drive, ``Experiment``, optional initial state and
marked times); ``run_friction_test`` runs one experiment and derives its table.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..errors import ExperimentError
from ..models.friction import FrictionModel, LuGre
from ..models.rig import FrictionRig
from ..simulation.result import Result
from ..simulation.simulate import simulate
from ..simulation.solvers import Rodas4, Solver
from .actuator import Experiment
from .signals import PiecewiseLinear, Ramp, Sine

KINDS = ("steady-state", "presliding", "frictional-lag", "break-away", "stick-slip")

#: Steady-state sweep: speeds of the staircase, used with both signs [m/s].
STEADY_STATE_SPEEDS = tuple(np.geomspace(1e-5, 1e-1, 25))
#: Frictional lag: v(t) = mean + amplitude·sin(2π f t) stays in the Stribeck region
#: (vs = 1 mm/s for canudas1995) and never reverses; frequencies [Hz]. The loop opens as
#: ω·τ grows (τ = g(v)/(sigma0·v), the bristle time constant, ≈ 28 ms at the lowest speed
#: of canudas1995); far above ω·τ ≈ 1 the bristle can no longer follow and the loop
#: flattens again (≈ 5 Hz here), so the default frequencies stay below that.
LAG_MEAN_VELOCITY = 2.5e-3
LAG_AMPLITUDE = 2.0e-3
LAG_FREQUENCIES = (0.25, 1.0, 4.0)
#: Break-away: force rates [N/s] of the ramps F(t) = rate·t, each ramped up to 2·Fs.
BREAK_AWAY_RATES = (0.01, 0.1, 1.0, 3.0, 10.0, 30.0)
#: Break-away displacement [m]: the body has broken away when it has moved this far
#: (0.1 mm, about 7·Fs/sigma0 for canudas1995: beyond the presliding range).
BREAK_AWAY_DISPLACEMENT = 1e-4
#: Stick-slip: default duration [s]; velocity above which the body counts as slipping
#: (in units of vs) when slip onsets are detected.
STICK_SLIP_DURATION = 20.0
SLIP_VELOCITY_MULTIPLE = 10.0


@dataclass(frozen=True, eq=False)
class RigSetup:
    """What one friction experiment applies to the ``FrictionRig``.

    ``drive`` is the rig drive ("force", "velocity", "position" or "spring"),
    ``experiment`` the drive signal over time, ``initial_state`` the [x, v, z] start (None:
    the rig's default, at rest with relaxed bristles) and ``marks`` times of interest
    (e.g. the ends of the steady-state plateaus).
    """

    drive: str
    experiment: Experiment
    initial_state: np.ndarray | None = None
    marks: tuple[float, ...] = ()


@dataclass(eq=False)
class FrictionTestResult:
    """Outcome of one friction experiment.

    ``result`` is the simulation (for multi-run experiments a representative run: the
    slowest force rate of break-away, the fastest frequency of frictional lag; every run is
    in ``runs``, keyed by rate or frequency). ``table`` holds the derived numbers with SI
    units in the column names, or None.
    """

    kind: str
    result: Result
    table: pd.DataFrame | None
    drive_quantity: str
    runs: dict[float, Result] = field(default_factory=dict)


def default_solver(params) -> Rodas4:
    """Rodas4 with rtol 1e-7 and absolute tolerances scaled to the presliding range.

    The rig has no natural state scales, so ``atol`` is set from Fs/sigma0 (bristle and
    position) and Fs/sqrt(sigma0·m) (velocity, the presliding oscillation).
    """
    z_scale = params["Fs"] / params["sigma0"]
    v_scale = params["Fs"] / math.sqrt(params["sigma0"] * params["m"])
    return Rodas4(rtol=1e-7, atol={"position": 1e-8 * z_scale, "velocity": 1e-8 * v_scale,
                                   "bristle": 1e-8 * z_scale})


# -- builders ------------------------------------------------------------------------------
def steady_state_experiment(params, speeds: Sequence[float] = STEADY_STATE_SPEEDS,
                            settle: float = 15.0, min_hold: float = 5e-3,
                            link: float = 1e-3) -> RigSetup:
    """Velocity staircase -max(speeds) … -min(speeds), +min(speeds) … +max(speeds).

    Each plateau is held ``settle`` bristle time constants g(v)/(sigma0·|v|) (at least
    ``min_hold`` s), plateaus are linked by ramps of ``link`` s. ``marks`` are the plateau
    ends, where the friction has settled to its steady state.
    """
    speeds = np.sort(np.abs(np.asarray(speeds, dtype=float)))
    if speeds.size == 0 or speeds[0] <= 0 or not np.all(np.isfinite(speeds)):
        raise ExperimentError(f"steady-state: speeds must be finite and > 0, got {speeds}")
    if not (settle > 0 and min_hold > 0 and link > 0):
        raise ExperimentError(f"steady-state: settle = {settle}, min_hold = {min_hold} s, "
                              f"link = {link} s must all be > 0")
    velocities = np.concatenate([-speeds[::-1], speeds])
    g = params["Fc"] + (params["Fs"] - params["Fc"]) * np.exp(
        -((speeds / params["vs"]) ** params["delta"]))
    tau = np.concatenate([(g / speeds)[::-1], g / speeds]) / params["sigma0"]
    times: list[float] = []
    values: list[float] = []
    ends: list[float] = []
    t = 0.0
    for v, tau_v in zip(velocities, tau, strict=True):
        if times:
            t += link
        times.append(t)
        values.append(v)
        t += max(settle * tau_v, min_hold)
        times.append(t)
        values.append(v)
        ends.append(t)
    exp = Experiment(PiecewiseLinear(times, values), "velocity", t, n_points=4001,
                     name="steady-state")
    return RigSetup("velocity", exp, marks=tuple(ends))


def presliding_experiment(params, amplitude: float = 0.9, duration: float = 5.0,
                          n_points: int = 5001) -> RigSetup:
    """Slow force triangle 0 → +A → −A → +A with A = ``amplitude``·Fs (below break-away).

    All three legs have the same force rate; the whole test lasts ``duration`` s.
    """
    if not 0 < amplitude < 1:
        raise ExperimentError(f"presliding: amplitude = {amplitude} (fraction of Fs) must "
                              "be in (0, 1): the force has to stay below break-away")
    if not duration > 0:
        raise ExperimentError(f"presliding: duration = {duration} s, must be > 0")
    a = amplitude * params["Fs"]
    drive = PiecewiseLinear([0.0, duration / 5, 3 * duration / 5, duration], [0.0, a, -a, a])
    return RigSetup("force", Experiment(drive, "force", duration, n_points=n_points,
                                        name="presliding"))


def frictional_lag_experiment(params, frequency: float, mean: float = LAG_MEAN_VELOCITY,
                              amplitude: float = LAG_AMPLITUDE, periods: float = 5.0,
                              friction: FrictionModel | None = None,
                              samples_per_period: int = 400) -> RigSetup:
    """Velocity v(t) = mean + amplitude·sin(2π·frequency·t) for ``periods`` periods.

    The bristle starts at its steady state for ``mean`` so the loop settles within the
    first period; ``marks`` is the start of the last period.
    """
    if not frequency > 0:
        raise ExperimentError(f"frictional-lag: frequency = {frequency} Hz, must be > 0")
    if not (0 <= amplitude < abs(mean)):
        raise ExperimentError(f"frictional-lag: need 0 <= amplitude < |mean| so the "
                              f"velocity never reverses; got mean = {mean} m/s, amplitude = "
                              f"{amplitude} m/s")
    if not periods >= 2:
        raise ExperimentError(f"frictional-lag: periods = {periods}, must be >= 2 (the last "
                              "one is analysed after the start-up)")
    friction = LuGre() if friction is None else friction
    t_end = periods / frequency
    z0 = (float(friction.steady_state(mean, params)[0]) - params["sigma2"] * mean) / \
        params["sigma0"]
    exp = Experiment(Sine(amplitude, frequency, offset=mean), "velocity", t_end,
                     n_points=round(periods * samples_per_period) + 1,
                     name=f"frictional-lag {frequency:g} Hz")
    return RigSetup("velocity", exp, np.array([0.0, mean, z0]), (t_end - 1.0 / frequency,))


def break_away_experiment(params, rate: float, final_force: float | None = None,
                          n_points: int = 20001) -> RigSetup:
    """Force ramp F(t) = rate·t from rest up to ``final_force`` (default 2·Fs)."""
    if not rate > 0:
        raise ExperimentError(f"break-away: force rate = {rate} N/s, must be > 0")
    final = 2.0 * params["Fs"] if final_force is None else float(final_force)
    if not final > 0:
        raise ExperimentError(f"break-away: final_force = {final} N, must be > 0")
    duration = final / rate
    return RigSetup("force", Experiment(Ramp(0.0, final, duration), "force", duration,
                                        n_points=n_points, name=f"break-away {rate:g} N/s"))


def stick_slip_experiment(params, duration: float = STICK_SLIP_DURATION,
                          samples_per_second: int = 1000) -> RigSetup:
    """The spring's free end moves at ``v_drive`` from t = 0; mass at rest, spring relaxed."""
    if not duration > 0:
        raise ExperimentError(f"stick-slip: duration = {duration} s, must be > 0")
    v_drive = params["v_drive"]
    exp = Experiment(Ramp(0.0, v_drive * duration, duration), "spring", duration,
                     n_points=round(duration * samples_per_second) + 1,
                     name="stick-slip")
    return RigSetup("spring", exp)


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


def break_away_force(result: Result, threshold: float = BREAK_AWAY_DISPLACEMENT,
                     ) -> tuple[float, float]:
    """(peak friction, applied force) of a force-ramp run at break-away [N].

    Break-away is when the displacement first exceeds ``threshold`` [m]. The peak friction
    force up to that moment is the static friction the contact delivered (Canudas et al.
    1995 report it falling with the force rate); the applied force at that moment also
    contains the force that accelerated the mass, so it rises again at fast rates.
    Both are nan if the body never moves that far.
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


# -- runners -------------------------------------------------------------------------------
def _run(setup: RigSetup, params, friction, solver, t_eval=None) -> Result:
    rig = FrictionRig(params, friction, drive=setup.drive)
    return simulate(rig, setup.experiment, solver, t_eval=t_eval, y0=setup.initial_state)


def _no_duration(kind: str, t_end) -> None:
    if t_end is not None:
        raise ExperimentError(f"{kind}: t_end = {t_end} s cannot be set: the duration follows "
                              "from the velocities (steady-state) or force rates (break-away)")


def _check_duration(kind: str, t_end) -> None:
    if t_end is not None and not (math.isfinite(t_end) and t_end > 0):
        raise ExperimentError(f"{kind}: t_end = {t_end} s, must be finite and > 0")


def _steady_state(params, friction, t_end, solver) -> FrictionTestResult:
    _no_duration("steady-state", t_end)
    setup = steady_state_experiment(params)
    ends = np.asarray(setup.marks)
    t_eval = np.union1d(setup.experiment.output_times(), ends)
    result = _run(setup, params, friction, solver, t_eval)
    at_end = np.searchsorted(result.time, ends)
    v = result["drive_velocity"][at_end]
    table = pd.DataFrame({
        "velocity [m/s]": v,
        "friction [N]": result["friction"][at_end],
        "steady-state friction [N]": friction.steady_state(v, params),
    })
    return FrictionTestResult("steady-state", result, table, "velocity")


def _presliding(params, friction, t_end, solver) -> FrictionTestResult:
    _check_duration("presliding", t_end)
    setup = presliding_experiment(params, duration=5.0 if t_end is None else t_end)
    result = _run(setup, params, friction, solver)
    table = pd.DataFrame({"force [N]": result["drive_force"],
                          "position [m]": result["position"]})
    return FrictionTestResult("presliding", result, table, "force")


def _frictional_lag(params, friction, t_end, solver) -> FrictionTestResult:
    _check_duration("frictional-lag", t_end)
    runs: dict[float, Result] = {}
    parts = []
    for f in LAG_FREQUENCIES:
        periods = 5.0 if t_end is None else t_end * f
        setup = frictional_lag_experiment(params, f, periods=periods, friction=friction)
        result = _run(setup, params, friction, solver)
        runs[f] = result
        last = result.time >= setup.marks[0] - 1e-12 * setup.experiment.t_end
        v = result["drive_velocity"][last]
        parts.append(pd.DataFrame({
            "frequency [Hz]": f,
            "time [s]": result.time[last],
            "velocity [m/s]": v,
            "friction [N]": result["friction"][last],
            "steady-state friction [N]": friction.steady_state(v, params),
        }))
    return FrictionTestResult("frictional-lag", runs[max(runs)], pd.concat(parts,
                              ignore_index=True), "velocity", runs)


def _break_away(params, friction, t_end, solver) -> FrictionTestResult:
    _no_duration("break-away", t_end)
    runs: dict[float, Result] = {}
    forces = []
    for rate in BREAK_AWAY_RATES:
        result = _run(break_away_experiment(params, rate), params, friction, solver)
        runs[rate] = result
        forces.append(break_away_force(result))
    peak, applied = (list(col) for col in zip(*forces, strict=True))
    table = pd.DataFrame({"force rate [N/s]": list(BREAK_AWAY_RATES),
                          "break-away force [N]": peak,
                          "applied force at break-away [N]": applied})
    return FrictionTestResult("break-away", runs[min(runs)], table, "force", runs)


def _stick_slip(params, friction, t_end, solver) -> FrictionTestResult:
    _check_duration("stick-slip", t_end)
    setup = stick_slip_experiment(params, STICK_SLIP_DURATION if t_end is None else t_end)
    return FrictionTestResult("stick-slip", _run(setup, params, friction, solver), None,
                              "spring")


_RUNNERS: dict[str, Callable[..., FrictionTestResult]] = {
    "steady-state": _steady_state,
    "presliding": _presliding,
    "frictional-lag": _frictional_lag,
    "break-away": _break_away,
    "stick-slip": _stick_slip,
}


def run_friction_test(kind: str, params, friction: FrictionModel | None = None,
                      t_end: float | None = None,
                      solver: Solver | None = None) -> FrictionTestResult:
    """Run one of the classic friction experiments (``KINDS``) on a ``FrictionRig``.

    ``t_end`` sets the duration of presliding, stick-slip and of each frictional-lag run;
    steady-state and break-away durations follow from their velocities and force rates.
    The default solver is ``default_solver(params)``.
    """
    if kind not in _RUNNERS:
        raise ExperimentError(f"friction test kind = {kind!r}; allowed: {', '.join(KINDS)}")
    friction = LuGre() if friction is None else friction
    solver = default_solver(params) if solver is None else solver
    return _RUNNERS[kind](params, friction, t_end, solver)
