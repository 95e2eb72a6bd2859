"""The classic friction experiments of Canudas de Wit, Olsson, Åström & Lischinsky (1995).

"A new model for control of systems with friction", IEEE TAC 40(3), 419-425: the
experiments that show what the LuGre model reproduces, run on a ``FrictionRig`` (a mass
with friction, driven by a force, a velocity or a spring). Each experiment is a small
settings object (every field has a default and is checked on creation) that builds the
rig set-ups it needs; ``pneumact.analysis.friction_tests.run_friction_test`` runs them
and derives their tables, and the command line offers every field as an option.

- ``SteadyState``: a staircase of constant velocities gives the friction-velocity curve.
- ``Presliding``: a slow force triangle below break-away gives the hysteretic
  force-displacement loop of presliding, with initial stiffness sigma0.
- ``FrictionalLag``: a sinusoidal velocity that never reverses gives a friction-velocity
  loop that opens as the frequency grows (friction lags the velocity).
- ``BreakAway``: force ramps at several rates; the break-away force (the peak friction
  before the body has slid a threshold distance) falls from Fs towards Fc as the rate
  grows.
- ``StickSlip``: a spring pulled at constant speed drags the mass in periodic stick-slip.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import ClassVar

import numpy as np

from ..core.signals import PiecewiseLinear, Ramp, Sine
from ..errors import ExperimentError
from .actuator import Experiment

__all__ = ["FRICTION_TESTS", "BreakAway", "FrictionTest", "FrictionalLag", "Presliding",
           "RigSetup", "SteadyState", "StickSlip", "friction_test"]


@dataclass(frozen=True, eq=False)
class RigSetup:
    """What one run of a friction experiment applies to the ``FrictionRig``.

    ``drive`` is the rig drive ("force", "velocity", "position" or "spring"),
    ``experiment`` the drive signal over time, ``initial_state`` the start by state name
    (None: at rest with relaxed friction states), ``key`` the run's label in a multi-run experiment
    (rate, frequency), ``marks`` times of interest (e.g. the ends of steady plateaus).
    """

    drive: str
    experiment: Experiment
    initial_state: Mapping[str, float] | None = None
    key: float | None = None
    marks: tuple[float, ...] = ()


def _positive(test: str, **values) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise ExperimentError(f"{test}: {name} = {value:g}, must be a finite number > 0")


@dataclass(frozen=True)
class FrictionTest:
    """Base of the friction experiments: solver tolerances shared by all of them.

    ``rtol`` is the relative tolerance; absolute tolerances are ``atol_factor`` times the
    presliding range Fs/sigma0 (bristle and position) and its velocity Fs/sqrt(sigma0·m).
    """

    rtol: float = field(default=1e-7, metadata={"help": "relative tolerance of the solver"})
    atol_factor: float = field(default=1e-8, metadata={
        "help": "absolute tolerances as a fraction of the presliding range"})
    kind: ClassVar[str]
    help: ClassVar[str]

    def __post_init__(self):
        _positive(self.kind, rtol=self.rtol, atol_factor=self.atol_factor)
        self.check()

    def check(self) -> None:
        """Raise ExperimentError for a setting out of its range."""

    def setups(self, params, friction) -> list[RigSetup]:
        raise NotImplementedError

    def settings(self) -> dict[str, object]:
        """Field name -> value, every setting of the experiment."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class SteadyState(FrictionTest):
    """Velocity staircase −max(speeds) … −min(speeds), +min(speeds) … +max(speeds).

    Each plateau is held ``settle`` bristle time constants g(v)/(sigma0·|v|) (at least
    ``min_hold`` s); plateaus are linked by ramps of ``link`` s. The friction at each
    plateau's end is compared with the model's analytic steady state.
    """

    speeds: tuple[float, ...] = field(
        default=tuple(np.geomspace(1e-5, 1e-1, 25).tolist()),
        metadata={"help": "plateau speeds [m/s], each run in both directions"})
    settle: float = field(default=15.0, metadata={
        "help": "plateau length in bristle time constants g(v)/(sigma0·v)"})
    min_hold: float = field(default=5e-3, metadata={"help": "shortest plateau [s]"})
    link: float = field(default=1e-3, metadata={"help": "ramp between plateaus [s]"})
    n_points: int = field(default=4001, metadata={"help": "output points"})
    kind: ClassVar[str] = "steady-state"
    help: ClassVar[str] = "friction against a staircase of constant velocities"

    def check(self) -> None:
        speeds = np.asarray(self.speeds, dtype=float)
        if speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0):
            raise ExperimentError(f"steady-state: speeds = {list(self.speeds)}; every speed "
                                  "must be a finite number > 0 [m/s]")
        _positive(self.kind, settle=self.settle, min_hold=self.min_hold, link=self.link)
        _check_points(self.kind, self.n_points)

    def setups(self, params, friction) -> list[RigSetup]:
        speeds = np.sort(np.abs(np.asarray(self.speeds, dtype=float)))
        velocities = np.concatenate([-speeds[::-1], speeds])
        # the law's time constant at each speed (none for a static map)
        per_speed = friction.relaxation_length(speeds, params) / speeds
        tau = np.concatenate([per_speed[::-1], per_speed])
        times: list[float] = []
        values: list[float] = []
        ends: list[float] = []
        t = 0.0
        for v, tau_v in zip(velocities, tau, strict=True):
            if times:
                t += self.link
            times.append(t)
            values.append(v)
            t += max(self.settle * tau_v, self.min_hold)
            times.append(t)
            values.append(v)
            ends.append(t)
        exp = Experiment(PiecewiseLinear(times, values), "velocity", t,
                         n_points=self.n_points, name="steady-state")
        return [RigSetup("velocity", exp, marks=tuple(ends))]


@dataclass(frozen=True)
class Presliding(FrictionTest):
    """Slow force triangle 0 → +A → −A → +A with A = ``amplitude``·Fs (below break-away);
    all three legs have the same force rate, the test lasts ``t_end`` s."""

    amplitude: float = field(default=0.9, metadata={
        "help": "force amplitude as a fraction of Fs (below 1: no break-away)"})
    t_end: float = field(default=5.0, metadata={"help": "length of the test [s]"})
    n_points: int = field(default=5001, metadata={"help": "output points"})
    kind: ClassVar[str] = "presliding"
    help: ClassVar[str] = "force-displacement loop below break-away (stiffness sigma0)"

    def check(self) -> None:
        if not 0 < self.amplitude < 1:
            raise ExperimentError(f"presliding: amplitude = {self.amplitude} (fraction of Fs) "
                                  "must be in (0, 1): the force has to stay below break-away")
        _positive(self.kind, t_end=self.t_end)
        _check_points(self.kind, self.n_points)

    def setups(self, params, friction) -> list[RigSetup]:
        a, d = self.amplitude * params["Fs"], self.t_end
        drive = PiecewiseLinear([0.0, d / 5, 3 * d / 5, d], [0.0, a, -a, a])
        return [RigSetup("force", Experiment(drive, "force", d, n_points=self.n_points,
                                             name="presliding"))]


@dataclass(frozen=True)
class FrictionalLag(FrictionTest):
    """Velocity v(t) = mean + amplitude·sin(2π·f·t) for each frequency f, ``periods``
    periods long, never reversing. The bristle starts at its steady state for ``mean``;
    the last period is analysed. The loop opens as ω·τ grows (τ = g(v)/(sigma0·v), about
    28 ms at the lowest speed of canudas1995) and flattens again far above ω·τ ≈ 1."""

    frequencies: tuple[float, ...] = field(default=(0.25, 1.0, 4.0), metadata={
        "help": "velocity frequencies [Hz], one run each"})
    mean: float = field(default=2.5e-3, metadata={"help": "mean velocity [m/s]"})
    amplitude: float = field(default=2.0e-3, metadata={
        "help": "velocity amplitude [m/s], below |mean|"})
    periods: float = field(default=5.0, metadata={"help": "periods per run (>= 2)"})
    samples_per_period: int = field(default=400, metadata={"help": "output points per period"})
    kind: ClassVar[str] = "frictional-lag"
    help: ClassVar[str] = "friction-velocity loops under sinusoidal velocity"

    def check(self) -> None:
        freqs = np.asarray(self.frequencies, dtype=float)
        if freqs.size == 0 or not np.all(np.isfinite(freqs)) or np.any(freqs <= 0):
            raise ExperimentError(f"frictional-lag: frequencies = {list(self.frequencies)}; "
                                  "every frequency must be a finite number > 0 [Hz]")
        if not (0 <= self.amplitude < abs(self.mean)):
            raise ExperimentError(
                f"frictional-lag: need 0 <= amplitude < |mean| so the velocity never "
                f"reverses; got mean = {self.mean} m/s, amplitude = {self.amplitude} m/s")
        if not self.periods >= 2:
            raise ExperimentError(f"frictional-lag: periods = {self.periods}, must be >= 2 "
                                  "(the last one is analysed after the start-up)")
        _check_points(self.kind, self.samples_per_period)

    def setups(self, params, friction) -> list[RigSetup]:
        steady = friction.steady_states(self.mean, params)[0]
        start = {"position": 0.0, "velocity": self.mean,
                 **dict(zip(friction.state_names, steady.tolist(), strict=True))}
        runs = []
        for f in self.frequencies:
            t_end = self.periods / f
            exp = Experiment(Sine(self.amplitude, f, offset=self.mean), "velocity", t_end,
                             n_points=round(self.periods * self.samples_per_period) + 1,
                             name=f"frictional-lag {f:g} Hz")
            runs.append(RigSetup("velocity", exp, start, float(f),
                                 (t_end - 1.0 / f,)))
        return runs


@dataclass(frozen=True)
class BreakAway(FrictionTest):
    """Force ramps F(t) = rate·t from rest up to ``final_force`` (default 2·Fs) at each
    rate; break-away is when the body has moved ``threshold`` (beyond presliding)."""

    rates: tuple[float, ...] = field(default=(0.01, 0.1, 1.0, 3.0, 10.0, 30.0), metadata={
        "help": "force rates [N/s], one ramp each"})
    final_force: float | None = field(default=None, metadata={
        "help": "force at the end of each ramp [N] (default 2·Fs)"})
    threshold: float = field(default=1e-4, metadata={
        "help": "displacement that counts as break-away [m]"})
    n_points: int = field(default=20001, metadata={"help": "output points per ramp"})
    kind: ClassVar[str] = "break-away"
    help: ClassVar[str] = "break-away force against the force rate"

    def check(self) -> None:
        rates = np.asarray(self.rates, dtype=float)
        if rates.size == 0 or not np.all(np.isfinite(rates)) or np.any(rates <= 0):
            raise ExperimentError(f"break-away: rates = {list(self.rates)}; every force rate "
                                  "must be a finite number > 0 [N/s]")
        if self.final_force is not None:
            _positive(self.kind, final_force=self.final_force)
        _positive(self.kind, threshold=self.threshold)
        _check_points(self.kind, self.n_points)

    def setups(self, params, friction) -> list[RigSetup]:
        final = 2.0 * params["Fs"] if self.final_force is None else float(self.final_force)
        return [RigSetup("force", Experiment(Ramp(0.0, final, final / rate), "force",
                                             final / rate, n_points=self.n_points,
                                             name=f"break-away {rate:g} N/s"), key=float(rate))
                for rate in self.rates]


@dataclass(frozen=True)
class StickSlip(FrictionTest):
    """The free end of a spring (stiffness k_drive) moves at ``v_drive`` (default: the
    parameter set's) from t = 0; the mass starts at rest with the spring relaxed."""

    t_end: float = field(default=20.0, metadata={"help": "length of the test [s]"})
    v_drive: float | None = field(default=None, metadata={
        "help": "speed of the spring's free end [m/s] (default: the set's v_drive)"})
    samples_per_second: int = field(default=1000, metadata={"help": "output points per s"})
    kind: ClassVar[str] = "stick-slip"
    help: ClassVar[str] = "a mass dragged through a spring at constant speed"

    def check(self) -> None:
        _positive(self.kind, t_end=self.t_end)
        if self.v_drive is not None:
            _positive(self.kind, v_drive=self.v_drive)
            from ..parameters import catalogue

            broken = catalogue()["v_drive"].violation(float(self.v_drive))
            if broken:
                raise ExperimentError(f"{self.kind}: v_drive = {self.v_drive:g} m/s: {broken}")
        _check_points(self.kind, self.samples_per_second)

    def setups(self, params, friction) -> list[RigSetup]:
        v_drive = params["v_drive"] if self.v_drive is None else float(self.v_drive)
        exp = Experiment(Ramp(0.0, v_drive * self.t_end, self.t_end), "spring",
                         self.t_end,
                         n_points=round(self.t_end * self.samples_per_second) + 1,
                         name="stick-slip")
        return [RigSetup("spring", exp)]


def _check_points(test: str, n: int) -> None:
    if int(n) != n or n < 2:
        raise ExperimentError(f"{test}: output grid = {n} points, must be an integer >= 2")


#: kind -> settings class, in the order of the paper's discussion.
FRICTION_TESTS: Mapping[str, type[FrictionTest]] = {
    cls.kind: cls for cls in (SteadyState, Presliding, FrictionalLag, BreakAway, StickSlip)}


def friction_test(kind: str, **settings) -> FrictionTest:
    """The settings object of experiment ``kind`` ("steady-state", ...) with ``settings``."""
    cls = FRICTION_TESTS.get(kind)
    if cls is None:
        raise ExperimentError(f"friction test kind = {kind!r}; allowed: "
                              f"{', '.join(FRICTION_TESTS)}")
    names = {f.name for f in fields(cls)}
    unknown = sorted(set(settings) - names)
    if unknown:
        raise ExperimentError(f"{kind}: unknown setting(s) {unknown}; allowed: "
                              f"{', '.join(sorted(names))}")
    return cls(**settings)
