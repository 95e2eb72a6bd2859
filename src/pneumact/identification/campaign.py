"""Bench campaigns for the identification procedure (section III.2), designed and simulated.

A campaign is a list of tests, each an ``Experiment`` with a kind the staged procedure
knows (``sweep``, ``ramp``, ``presliding``) and a sample rate. ``design_campaign`` sizes
the tests for an actuator from a rough prior (datasheet geometry, guessed spring and
friction, and how far off the guesses may be), and ``CampaignPlan.to_pandas()`` prints
them as a table a technician can run on a real bench. ``synthetic_campaign`` simulates a
campaign on any parameter set and adds realistic measurement effects (pressure and
position noise, position quantisation, a position-sensor lag, a seed), giving ``Record``
objects: the basis of the known-answer tests and of ``pneumact campaign``.

How the tests are driven, and why:

- ``sweep`` and ``ramp`` go through the pressure regulator (the paper's EPC) on a
  pressure set-point, and record the chamber pressure and the set-point: the chamber
  damps the mechanics, so the actuator slides steadily even at 0.1 mm/s. Driven by an
  ideal pressure source it would stick-slip below about 6·vs (σ2 + g'(v) < 0 with
  δ = 1), and eq. 12 would have no steady data there.
- ``presliding`` prescribes fast pressure steps (as a fast solenoid valve gives) after
  a stop and a partial reversal, so that the stuck mode rings: slow excitation shows
  the stiffness σ0 only, never the damping σ1.

Every corner of a set-point lies on the test's sampling grid: a bench controller changes
its set-point at its own samples, and a corner between two logged samples would be cut
by the record the identification reads.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ExperimentError
from ..experiments import Experiment, PiecewiseLinear
from ..io.records import PRESSURE_SIGNAL, Record
from ..io.report import ResultVocabulary
from ..models.actuator import CHAMBER_PRESSURE
from ..models.sensors import first_order_lag
from ..models.valves import PRESSURE_INPUT  # the regulator's and the source's input
from ..plotting import tight_layout

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["BenchFamily", "BenchTest", "CampaignPlan", "Noise", "add_noise", "design_campaign",
           "paper_campaign", "read_plan", "regulator_reach", "synthetic_campaign"]

KINDS = ("sweep", "ramp", "presliding")


@dataclass(frozen=True)
class BenchTest:
    """One bench test: what is applied, through which valve, sampled how fast."""

    name: str
    kind: str
    experiment: Experiment
    valve: str  # "regulator" or "source"
    sample_rate: float

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ExperimentError(f"bench test {self.name!r}: kind = {self.kind!r}; allowed: "
                                  f"{', '.join(KINDS)}")


@dataclass(frozen=True)
class Noise:
    """What the bench's sensors make of the actuator: white noise (standard deviations,
    SI), the position sensor's resolution [m] (0: none) and first-order lag [s] (0:
    none), the pressure and position sensors' offsets [Pa, m] (0: none), and the rate the
    bench logs at [Hz] (0: each test's own; a rate above a test's own changes nothing)."""

    pressure: float = 20.0
    position: float = 1e-6
    resolution: float = 1e-6
    lag: float = 0.0
    pressure_offset: float = 0.0
    position_offset: float = 0.0
    sample_rate: float = 0.0

    def __post_init__(self):
        for item in fields(self):  # offsets of either sign; the rest >= 0
            value, signed = getattr(self, item.name), item.name.endswith("_offset")
            if not np.isfinite(value) or (value < 0 and not signed):
                raise ExperimentError(f"Noise.{item.name} = {value}; must be finite"
                                      f"{'' if signed else ' and >= 0'}")

    def apply(self, rng: np.random.Generator, pressure: np.ndarray, position: np.ndarray,
              time: np.ndarray | None = None):
        """(pressure, position) as the sensors read them: the position through the lag,
        each with its offset and white noise, the position rounded to the resolution."""
        if self.lag > 0:
            if time is None:
                raise ExperimentError("Noise.apply: a sensor lag needs the sample times")
            position = first_order_lag(time, position, self.lag)
        pressure = pressure + self.pressure_offset
        position = position + self.position_offset
        pressure = pressure + rng.normal(0.0, self.pressure, pressure.shape)
        position = position + rng.normal(0.0, self.position, position.shape)
        if self.resolution > 0:
            position = np.round(position / self.resolution) * self.resolution
        return pressure, position

    def sampled(self, record: Record) -> Record:
        """``record`` as the bench logs it: resampled at ``sample_rate`` where that is
        slower than the record's own rate."""
        if not self.sample_rate or self.sample_rate >= 1 / float(np.median(np.diff(
                record.time))):
            return record
        return record.resample(1 / self.sample_rate)


def _log_uniform_or_none(rng: np.random.Generator, none: float,
                         span: tuple[float, float]) -> float:
    """0 with probability ``none``, else log-uniform in ``span``."""
    if rng.uniform() < none:
        return 0.0
    return float(np.exp(rng.uniform(np.log(span[0]), np.log(span[1]))))


@dataclass(frozen=True)
class BenchFamily:
    """Ranges of what real benches add (issue 38): a pressure-sensor offset uniform in
    ±``pressure_offset`` [Pa]; a position-sensor lag [s], resolution [m] and a logging
    rate [Hz], each absent with its probability in ``absent`` and log-uniform in its
    range otherwise. ``draw(n, seed)`` (or ``sample(rng)``) gives ``Noise`` objects:
    with the default white noise, and a resolution no finer than the default's."""

    pressure_offset: float = 2e3
    lag: tuple[float, float] = (5e-4, 2e-2)
    resolution: tuple[float, float] = (2e-6, 5e-5)
    sample_rate: tuple[float, float] = (100.0, 1000.0)
    absent: Mapping[str, float] = field(default_factory=lambda: {
        "lag": 1 / 3, "resolution": 1 / 3, "sample_rate": 1 / 2})

    def sample(self, rng: np.random.Generator) -> Noise:
        """One bench, drawn with ``rng``."""
        offset = float(rng.choice([-1, 1]) * rng.uniform(0, self.pressure_offset))
        lag = _log_uniform_or_none(rng, self.absent["lag"], self.lag)
        resolution = _log_uniform_or_none(rng, self.absent["resolution"], self.resolution)
        rate = _log_uniform_or_none(rng, self.absent["sample_rate"], self.sample_rate)
        return Noise(resolution=max(resolution, Noise().resolution), lag=lag,
                     pressure_offset=offset, sample_rate=rate)

    def draw(self, n: int, seed: int = 0) -> list[Noise]:
        """``n`` benches, reproducible by ``seed``."""
        rng = np.random.default_rng(seed)
        return [self.sample(rng) for _ in range(n)]


def _piecewise(points: Sequence[tuple[float, float]], rate: float) -> PiecewiseLinear:
    """A set-point from (duration of the segment [s], value at its end [Pa]) pairs,
    starting from the first value, with every corner on the sampling grid (a bench
    controller changes its set-point at its own samples; a corner between two samples
    would be cut by the logged record)."""
    times, values = [0.0], [points[0][1]]
    for duration, value in points[1:]:
        times.append(times[-1] + max(round(duration * rate), 1) / rate)
        values.append(value)
    return PiecewiseLinear(times, values)


def _test(name, kind, points, valve, rate) -> BenchTest:
    drive = _piecewise(points, rate)
    t_end = float(drive.breakpoints()[-1])
    n = round(t_end * rate) + 1
    experiment = Experiment(drive, PRESSURE_INPUT.name, t_end, n_points=n, name=name)
    return BenchTest(name, kind, experiment, valve, rate)


def paper_campaign(params, speeds: Sequence[float] = (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3,
                                                      1e-2, 2e-2, 3e-2, 4e-2),
                   sweep_period: float = 60.0) -> list[BenchTest]:
    """The tests of the paper's procedure, sized from ``params`` (spring, preload, area):

    - one quasi-static sweep 100 → 20 → 100 kPa over ``sweep_period`` (step a);
    - per speed [m/s], a ramp pair at the pressure rate that moves the spring at that
      speed (k·v/A_d), in both directions, from mid-stroke (steps b and c); the default
      regulator reaches about 50 mm/s, so faster ramps would not slide steadily;
    - one presliding test: stop at mid-stroke, reverse by the friction band, then small
      fast steps that stay below break-away (step d).
    """
    p_atm, area, k, f0 = (params[n] for n in ("p_atm", "A_d", "k", "F0"))
    friction = params["Fs"] if "Fs" in params else 3.0
    high, low = p_atm, p_atm - (f0 + 0.9 * k * 0.02) / area
    low = max(low, 0.2 * p_atm)
    tests = [_test("sweep", "sweep", [(0, high), (1.0, high), (sweep_period / 2, low),
                                      (sweep_period / 2, high), (1.0, high)],
                   "regulator", 100.0)]
    mid = p_atm - (f0 + k * 0.005) / area  # 5 mm
    band = 2.0 * friction / area
    for v in speeds:
        rate = k * v / area
        travel = min(11e-3, max(0.6e-3, 3.0 * v))  # steady part long enough at any speed
        span = k * travel / area + band
        ramp = span / rate
        sample_rate = float(np.clip(400.0 / ramp, 1000.0, 2000.0))
        tests.append(_test(f"ramp_{v * 1e3:g}mm_s", "ramp",
                           [(0, high), (0.5, high), (1.5, mid), (0.5, mid), (ramp, mid - span),
                            (0.5, mid - span), (ramp, mid), (0.5, mid)],
                           "regulator", sample_rate))
    step = 0.35 * friction / area
    points = [(0, high), (0.2, high), (1.5, mid), (0.3, mid), (0.02, mid + band / 2),
              (0.3, mid + band / 2)]
    for sign in (1, -2, 2, -2, 1):
        points += [(0.005, points[-1][1] + sign * step), (0.15, points[-1][1] + sign * step)]
    tests.append(_test("presliding", "presliding", points, "source", 5000.0))
    return tests


# --------------------------------------------------------------------------- design
#: The relative uncertainty of a guess a plan is designed for, unless told (issue 18: ±50 %).
DEFAULT_SPREAD = 0.5
#: Ramps per campaign, log-spaced in speed.
RAMP_SPEEDS = 10
#: Lowest ramp speed [m/s]: below it a regulator-driven diaphragm seldom slides steadily.
MIN_RAMP_SPEED = 5e-5
#: Eq. 13 needs the Stribeck term below this fraction of Fc at its slowest speed.
STRIBECK_NEGLIGIBLE = 2e-3
#: Fraction of the chamber's largest pressure rate a regulator ramp may ask for (the rest
#: is the regulator's margin to track it).
REGULATOR_MARGIN = 0.5
#: The sweep's speed: this share of what the regulator follows (``regulator_reach``).
#: Sliding that a break-away starts stops again when the spring-mass swing the drop from
#: Fs to Fc sets off, (Fs − Fc)/√(k·m) less its damping, outruns the sweep: a sweep at
#: three times the highest plausible vs (before) stick-slipped on heavy, lightly damped
#: actuators (3.6 kg, 1.2 kN/m, Fs − Fc = 2.5 N: jumps of 2.2 mm every 2 s at 0.2 mm/s),
#: and the joint fit started from it missed every record by 100-400 noise deviations.
#: Measured (``bench_identify_family.py --validation --actuators 20``): the wide family
#: 31.9 → 41.9 % identified (through drawn benches 23.8 → 33.8 %), the default family
#: 66.2 → 72.5 %, none wrong; the runs a third shorter.
SWEEP_REACH = 0.5
#: Presliding steps: this fraction of the prior's Fs/A_d. After the reversal by the lowest
#: plausible Fs/A_d, the friction swings within ±0.85·Fs whatever the true Fs within
#: ±50 % of the prior: below break-away.
PRESLIDING_STEP = 0.35
#: The reversal before the steps is at most this fraction of the guessed Fs/A_d, however
#: well Fs is known: the friction at the stop is the sliding level Fc (Fs/Fc up to 2), and
#: a reversal by 0.9·Fs from it sent a second round's steps (designed for Fs ±10 %) into
#: breaking away backwards (93 µm of sliding on a family actuator).
MAX_REVERSAL = 0.5


@dataclass(frozen=True)
class CampaignPlan(ResultVocabulary):
    """The tests of a designed campaign and why each is there (see ``design_campaign``).

    ``to_pandas()``: one row per test; ``plot()``: each test's drive against time;
    ``write(folder)``: plan.csv, drives.png and report.html."""

    report_title = "Identification campaign"
    figure_name = "drives"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"plan": self.to_pandas()}

    def report_text(self) -> str:
        return " ".join(self.notes)

    def plot(self) -> Figure:
        """Each test's drive (kPa abs) against time, a panel per test."""
        import matplotlib.pyplot as plt

        n = max(1, len(self.tests))
        fig, axes = plt.subplots(n, 1, squeeze=False, figsize=(7.0, 1.6 * n + 0.8))
        for ax, test in zip(axes[:, 0], self.tests, strict=False):
            drive = test.experiment.drive
            times = np.asarray(drive.breakpoints(), dtype=float)
            ax.plot(times, drive(times) * 1e-3, "C0-")
            ax.set_ylabel("kPa abs")
            ax.set_title(f"{test.name}: {self.purposes.get(test.name, test.kind)}",
                         fontsize=8)
            ax.grid(True, alpha=0.3)
        axes[-1, 0].set_xlabel("time [s]")
        tight_layout(fig)
        return fig

    tests: list[BenchTest]
    purposes: dict[str, str]
    speeds: dict[str, float]  # test -> target sliding speed [m/s]
    prior: object
    spread: float  # the widest of the guesses' relative uncertainties
    notes: list[str]
    spreads: dict[str, float] = field(default_factory=dict)  # per parameter, if given

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """One row per test, in the units a bench technician sets: kPa, kPa/s, mm/s, s,
        Hz."""
        if name not in (None, "plan"):
            raise ExperimentError(f"to_pandas: name = {name!r}; allowed: plan")
        rows = []
        for test in self.tests:
            drive = test.experiment.drive
            times = np.asarray(drive.breakpoints(), dtype=float)
            values = drive(times)
            rates = np.abs(np.diff(values) / np.diff(times))
            rows.append({
                "test": test.name, "kind": test.kind,
                "valve": "regulator" if test.valve == "regulator" else "fast valve",
                "from [kPa abs]": values[0] * 1e-3,
                "lowest [kPa abs]": values.min() * 1e-3,
                "highest [kPa abs]": values.max() * 1e-3,
                "ramp rate [kPa/s]": float(np.median(rates[rates > 0])) * 1e-3
                if test.kind != "presliding" else np.nan,
                "expected speed [mm/s]": self.speeds.get(test.name, np.nan) * 1e3,
                "duration [s]": float(times[-1] - times[0]),
                "sample rate [Hz]": test.sample_rate,
                "purpose": self.purposes[test.name]})
        return pd.DataFrame(rows).set_index("test")

    def breakpoints(self, test: str) -> pd.DataFrame:
        """The set-point of one test as (time [s], pressure [kPa abs]) corners."""
        chosen = next(t for t in self.tests if t.name == test)
        times = np.asarray(chosen.experiment.drive.breakpoints(), dtype=float)
        return pd.DataFrame({"time [s]": times,
                             "pressure [kPa abs]": chosen.experiment.drive(times) * 1e-3})


#: The files of a written plan (``pneumact campaign --plan``): the table, and the
#: set-point corners of each test.
PLAN_TABLE = "plan.csv"
SETPOINT_FILE = "setpoint_{}.csv"


def read_plan(folder: str | PathLike[str]) -> list[BenchTest]:
    """The bench tests of a plan written by ``pneumact campaign --plan`` (plan.csv and
    one setpoint_<test>.csv per test), to run on another parameter set
    (``synthetic_campaign(truth, read_plan(folder))``): a plan designed from a prior,
    tested on the truth."""
    root = Path(folder)
    if not (root / PLAN_TABLE).is_file():
        raise ExperimentError(f"read_plan: {root} has no {PLAN_TABLE}; write a plan with "
                              "pneumact campaign --plan --out FOLDER")
    table = _read_csv(root / PLAN_TABLE)
    missing = [c for c in ("test", "kind", "valve", "sample rate [Hz]") if c not in table]
    if missing:
        raise ExperimentError(f"read_plan: {root / PLAN_TABLE} lacks the column(s) "
                              f"{', '.join(missing)}")
    tests = []
    for _, row in table.iterrows():
        name, kind, valve = str(row["test"]), str(row["kind"]), str(row["valve"])
        path = root / SETPOINT_FILE.format(name)
        if not path.is_file():
            raise ExperimentError(f"read_plan: the plan names test {name!r} but {path} is "
                                  "missing")
        corners = _read_csv(path)
        if list(corners.columns[:2]) != ["time [s]", "pressure [kPa abs]"]:
            raise ExperimentError(f"read_plan: {path} must have the columns 'time [s]' and "
                                  "'pressure [kPa abs]'")
        times = corners["time [s]"].to_numpy(float)
        values = corners["pressure [kPa abs]"].to_numpy(float) * 1e3
        rate = float(row["sample rate [Hz]"])
        if not (rate > 0 and np.all(np.diff(times) > 0) and np.all(values > 0)):
            raise ExperimentError(f"read_plan: {path}: times must increase, pressures be "
                                  f"absolute (> 0) and the sample rate ({rate}) > 0")
        t_end = float(times[-1])
        drive = PiecewiseLinear(times, values)
        tests.append(BenchTest(name, kind, Experiment(drive, PRESSURE_INPUT.name, t_end,
                                                      n_points=round(t_end * rate) + 1,
                                                      name=name),
                               "regulator" if valve == "regulator" else "source", rate))
    return tests


def _read_csv(path: Path) -> pd.DataFrame:
    try:
        return pd.read_csv(path)
    except (ValueError, OSError, UnicodeDecodeError) as exc:
        raise ExperimentError(f"read_plan: cannot read {path}: {exc}") from None


#: The guesses a plan is designed around (each with a relative uncertainty, its spread).
GUESSED = ("F0", "k", "Fc", "sigma2", "Fs", "vs", "sigma0", "sigma1")


def _spreads(spread: float | Mapping[str, float]) -> dict[str, float]:
    """The relative uncertainty of each guess in ``GUESSED``: one for all, or one per
    name (``DEFAULT_SPREAD`` for those a mapping lacks), each in [0, 1)."""
    if isinstance(spread, Mapping):
        unknown = sorted(set(spread) - set(GUESSED))
        if unknown:
            raise ExperimentError(f"design_campaign: spread names {', '.join(unknown)}; "
                                  f"allowed: {', '.join(GUESSED)}")
        given = {n: spread.get(n, DEFAULT_SPREAD) for n in GUESSED}
    else:
        given = dict.fromkeys(GUESSED, spread)
    for name, value in given.items():
        if not (isinstance(value, (int, float)) and 0 <= value < 1):
            label = "spread" if not isinstance(spread, Mapping) else f"spread[{name!r}]"
            raise ExperimentError(f"design_campaign: {label} = {value!r}; must be in [0, 1) "
                                  "(the guess's relative uncertainty)")
    return {name: float(value) for name, value in given.items()}


def regulator_reach(params) -> float:
    """Fastest steady sliding speed [m/s] a regulator ramp can ask for: a share
    ``REGULATOR_MARGIN`` of the chamber's largest pressure rate (choked flow through the
    smaller valve area into the rest volume), moving the spring k·v/A_d."""
    gamma, r, temp = params["gamma"], params["R"], params["T"]
    choked = (2 / (gamma + 1)) ** ((gamma + 1) / (2 * (gamma - 1)))
    area = min(params["A_res"], params["A_atm"])
    flow = area * params["p_atm"] * np.sqrt(gamma / (r * temp)) * choked
    rate = r * temp * flow / params["V0"]  # Pa/s, isothermal
    return float(REGULATOR_MARGIN * rate * params["A_d"] / params["k"])


def design_campaign(prior, spread: float | Mapping[str, float] = 0.5,
                    ramps: int = RAMP_SPEEDS, sweep_period: float | None = None, *,
                    slowest: float | None = None, suffix: str = "") -> CampaignPlan:
    """Tests that let the identification pin down every parameter of an actuator known
    roughly as ``prior`` (each spring and friction value within ±``spread``):

    - a quasi-static sweep from p_atm to the pressure that draws the diaphragm to 90 % of
      its stroke (x_max) and back (F0, k), at ``SWEEP_REACH`` of the speed the regulator
      follows (``regulator_reach``), the stroke in no less than 2 s each way;
    - ``ramps`` ramp pairs, both directions from mid-stroke, at log-spaced steady speeds
      from a third of the lowest plausible vs (at least ``MIN_RAMP_SPEED``) up to where
      the Stribeck term of the highest plausible vs and Fs − Fc falls below
      ``STRIBECK_NEGLIGIBLE``·Fc (eq. 13), capped by what the regulator can follow;
    - a presliding test: a stop at mid-stroke, a reversal by the lowest plausible
      Fs/A_d (the friction unloads towards zero without breaking away backwards), then
      fast steps of ``PRESLIDING_STEP``·Fs/A_d (Fs at its lowest), each rising in
      a fifth of the stuck-mode period (0.5 to 2 ms, a fast solenoid valve) and held
      for ten decay times, sampled at 20 points per stuck period and 10 per rise (the
      rebuilt input must resolve each step's corners).

    ``spread`` is one relative uncertainty for every guess, or one per parameter of
    ``GUESSED`` (a mapping; the names it lacks take ``DEFAULT_SPREAD``): a second round
    knows some values better than others (``PaperIdentification.next_round``).
    ``slowest`` [m/s] sets the slowest ramp instead of vs/3 (above the speeds where a
    first round's ramps stick-slipped); ``suffix`` is appended
    to every test's name (a second round's records must not take a first round's names).
    """
    spreads = _spreads(spread)
    if ramps < 3:
        raise ExperimentError(f"design_campaign: ramps = {ramps}; need at least 3")
    if slowest is not None and not (np.isfinite(slowest) and slowest > 0):
        raise ExperimentError(f"design_campaign: slowest = {slowest}; must be a speed > 0 "
                              "[m/s]")

    def lo(name: str) -> float:
        return 1.0 - spreads[name]

    def hi(name: str) -> float:
        return 1.0 + spreads[name]

    p_atm, area, k, f0 = (prior[n] for n in ("p_atm", "A_d", "k", "F0"))
    x_max, m = prior["x_max"], prior["m"]
    fc, fs, vs, delta = (prior[n] for n in ("Fc", "Fs", "vs", "delta"))
    floor = prior["p_res"] + 0.05 * (p_atm - prior["p_res"])  # the regulator's reach
    reach = regulator_reach(prior)
    purposes, speeds = {}, {}

    # sweep: 90 % of the stroke, at a share of the regulator's reach
    low = max(p_atm - (f0 + 0.9 * k * x_max + fs * hi("Fs")) / area, floor)
    sweep_speed = SWEEP_REACH * reach
    travel = ((p_atm - low) * area - f0) / k
    period = sweep_period or max(2 * travel / sweep_speed, 4.0)
    rate = 1000.0 if period < 200 else 100.0
    sweep = "sweep" + suffix
    tests = [_test(sweep, "sweep", [(0, p_atm), (1.0, p_atm), (period / 2, low),
                                    (period / 2, p_atm), (1.0, p_atm)], "regulator", rate)]
    purposes[sweep] = "F0, k (stage a): both branches over 90 % of the stroke"
    speeds[sweep] = 2 * travel / period

    # ramps: around the plausible vs, up to where eq. 13 holds
    amplitude = (fs - fc) * hi("Fs")
    eq13 = vs * hi("vs") * max(np.log(max(amplitude / (STRIBECK_NEGLIGIBLE * fc * lo("Fc")),
                                         1.0)), 1.0) ** (1 / delta)
    if slowest is None:
        slowest = max(vs * lo("vs") / 3, MIN_RAMP_SPEED)
    fastest = reach  # a wide speed range above vs is what separates σ2 from Fc
    notes = []
    if fastest < 2 * eq13:
        notes.append(f"eq. 13 wants steady sliding up to {2 * eq13 * 1e3:.3g} mm/s, the "
                     f"regulator follows ramps up to about {reach * 1e3:.3g} mm/s: Fc and "
                     "σ2 then rest on the joint fit of eq. 12")
    if fastest <= 3 * slowest:
        raise ExperimentError(f"design_campaign: the regulator follows ramps up to "
                              f"{reach * 1e3:.3g} mm/s, too close to the slowest useful "
                              f"ramp {slowest * 1e3:.3g} mm/s (vs/3) for a speed sweep")
    mid = p_atm - (f0 + k * 0.3 * x_max) / area  # 30 % of the stroke
    band = 2.0 * fs * hi("Fs") / area
    for v in np.geomspace(slowest, fastest, ramps):
        v = float(f"{v:.2g}")
        pressure_rate = k * v / area
        ramp_travel = min(0.5 * x_max, max(0.03 * x_max, 3.0 * v))
        span = min(k * ramp_travel / area + band, mid - floor)
        duration = span / pressure_rate
        sample_rate = float(np.clip(400.0 / duration, 500.0, 2000.0))
        name = f"ramp_{v * 1e3:g}mm_s{suffix}"
        tests.append(_test(name, "ramp",
                           [(0, p_atm), (0.5, p_atm), (1.5, mid), (0.5, mid),
                            (duration, mid - span), (0.5, mid - span), (duration, mid),
                            (0.5, mid)], "regulator", sample_rate))
        speeds[name] = v
        role = "Fs, vs (eq. 12)" if v < eq13 else "Fc, σ2 (eq. 13)"
        purposes[name] = f"{role}: steady sliding at {v * 1e3:.3g} mm/s both ways"

    # presliding: fast small steps below break-away after a stop
    period_stuck = 2 * np.pi * np.sqrt(m / (k + prior["sigma0"] * hi("sigma0")))
    rise = float(np.clip(period_stuck / 5, 5e-4, 2e-3))
    damping = prior["sigma1"] * lo("sigma1") + prior["sigma2"] * lo("sigma2")
    stiffness = k + prior["sigma0"] * lo("sigma0")
    decay = max(2 * m / damping, damping / stiffness) if damping > 0 else 1.0
    hold = float(np.clip(10 * decay, 0.1, 1.0))
    sample_rate = float(np.clip(max(20 / period_stuck, 10 / rise), 2000.0, 20000.0))
    step = PRESLIDING_STEP * fs / area
    # unloads the friction towards 0 whatever Fs within the spread; never by more than
    # half the guessed Fs: the friction at the stop is Fc, as low as half of Fs
    reversal = fs * min(lo("Fs"), MAX_REVERSAL) / area
    points = [(0, p_atm), (0.2, p_atm), (1.5, mid), (0.3, mid), (0.02, mid + reversal),
              (0.3, mid + reversal)]
    for sign in (1, -2, 2, -2, 1):
        points += [(rise, points[-1][1] + sign * step), (hold, points[-1][1] + sign * step)]
    tests.append(_test("presliding" + suffix, "presliding", points, "source", sample_rate))
    purposes["presliding" + suffix] = (f"σ0, σ1 (stage d): steps of {step * 1e-3:.3g} kPa in "
                              f"{rise * 1e3:.2g} ms, held {hold:.2g} s, below break-away")
    return CampaignPlan(tests, purposes, speeds, prior, max(spreads.values()), notes,
                        spreads)


def synthetic_campaign(params, tests: Sequence[BenchTest] | None = None,
                       noise: Noise | None = None, seed: int = 0, friction=None,
                       chamber=None, solver=None) -> list[Record]:
    """Simulate each bench test on ``params`` (LuGre friction unless ``friction``, an
    isothermal chamber unless ``chamber``; default tests ``design_campaign(params)``) and
    return measured-like records: chamber pressure [Pa abs] and position [m] (and the
    regulator's set-point [Pa abs], as commanded, for the regulator-driven tests) with
    ``noise`` (default ``Noise()``; ``Noise(0, 0, 0)`` for exact data), reproducible by
    ``seed``. The simulation runs at rtol 1e-9 unless ``solver``: a campaign stands for
    measurements, which carry no integration error. Each record's ``meta`` holds its
    kind and the truth's parameter set name."""
    from ..models import Actuator, Isothermal, LuGre, PressureRegulator, PressureSource
    from ..simulation import Rodas4, simulate

    tests = design_campaign(params).tests if tests is None else list(tests)
    friction = LuGre() if friction is None else friction
    chamber = Isothermal() if chamber is None else chamber
    solver = Rodas4(rtol=1e-9) if solver is None else solver
    records = []
    for test in tests:
        if test.valve == "regulator":
            model = Actuator(params, friction=friction, valve=PressureRegulator(),
                             chamber=chamber)
        else:  # the pressure is prescribed: no chamber law applies
            model = Actuator(params, friction=friction, valve=PressureSource())
        result = simulate(model, test.experiment, solver)
        signals = {PRESSURE_SIGNAL: result[CHAMBER_PRESSURE], "position": result["position"]}
        if test.valve == "regulator":  # the bench logs what it commanded, too
            signals["setpoint"] = test.experiment.drive(result.time)
        records.append(Record.from_arrays(
            result.time, signals, source=test.name,
            meta={"kind": test.kind, "truth": params.name}))
    return add_noise(records, Noise() if noise is None else noise, seed)


def add_noise(records: Sequence[Record], noise: Noise, seed: int = 0) -> list[Record]:
    """The records as a bench with ``noise`` logs them (its rate, its sensors' lag,
    offsets, noise and resolution), reproducible by ``seed`` (one simulation serves many
    noise realisations)."""
    rng = np.random.default_rng(seed)
    noisy = []
    for rec in records:
        rec = noise.sampled(rec)
        pressure, position = noise.apply(rng, rec[PRESSURE_SIGNAL], rec["position"], rec.time)
        signals = {**rec.signals, PRESSURE_SIGNAL: pressure, "position": position}
        noisy.append(Record.from_arrays(rec.time, signals, rec.units, rec.source,
                                        {**rec.meta, "seed": str(seed)}))
    return noisy
