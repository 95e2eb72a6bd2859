"""Bench campaigns for the paper's identification procedure (section III.2).

A campaign is a list of tests, each an ``Experiment`` with a kind the staged procedure
knows (``sweep``, ``ramp``, ``presliding``) and a sample rate. ``synthetic_campaign``
simulates it on any parameter set and adds realistic measurement effects (pressure and
position noise, position quantisation, a seed), giving ``Record`` objects that are the
basis of the known-answer tests and of ``pneumact campaign``.

How the tests are driven, and why:

- ``sweep`` and ``ramp`` go through the pressure regulator (the paper's EPC) on a
  pressure set-point, and record the chamber pressure: the chamber damps the mechanics,
  so the actuator slides steadily even at 0.1 mm/s. Driven by an ideal pressure source
  it would stick-slip below about 6·vs (σ2 + g'(v) < 0 with δ = 1), and eq. 12 would
  have no steady data there.
- ``presliding`` prescribes fast pressure steps (2 ms, as a fast solenoid valve gives)
  after a stop and a partial reversal, so that the stuck mode (~67 Hz, damped by σ1)
  rings: slow excitation shows the stiffness σ0 only, never the damping σ1.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ExperimentError
from ..experiments import Experiment, PiecewiseLinear
from ..io.records import Record

__all__ = ["BenchTest", "Noise", "add_noise", "paper_campaign", "synthetic_campaign"]

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
    """Measurement effects: white noise (standard deviations, SI) and the position
    sensor's resolution [m] (0: none)."""

    pressure: float = 20.0
    position: float = 1e-6
    resolution: float = 1e-6

    def apply(self, rng: np.random.Generator, pressure: np.ndarray, position: np.ndarray):
        pressure = pressure + rng.normal(0.0, self.pressure, pressure.shape)
        position = position + rng.normal(0.0, self.position, position.shape)
        if self.resolution > 0:
            position = np.round(position / self.resolution) * self.resolution
        return pressure, position


def _piecewise(points: Sequence[tuple[float, float]]) -> PiecewiseLinear:
    """A set-point from (duration of the segment [s], value at its end [Pa]) pairs,
    starting from the first value."""
    times, values = [0.0], [points[0][1]]
    for duration, value in points[1:]:
        times.append(times[-1] + duration)
        values.append(value)
    return PiecewiseLinear(times, values)


def _test(name, kind, points, valve, rate) -> BenchTest:
    drive = _piecewise(points)
    t_end = float(drive.breakpoints()[-1])
    n = round(t_end * rate) + 1
    return BenchTest(name, kind, Experiment(drive, "pressure", t_end, n_points=n, name=name),
                     valve, rate)


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


def synthetic_campaign(params, tests: Sequence[BenchTest] | None = None,
                       noise: Noise | None = None, seed: int = 0, friction=None
                       ) -> list[Record]:
    """Simulate each bench test on ``params`` (LuGre friction unless ``friction``) and
    return measured-like records: chamber pressure [Pa abs] and position [m] (and the
    regulator's set-point [Pa abs], as commanded, for the regulator-driven tests) with
    ``noise`` (default ``Noise()``; ``Noise(0, 0, 0)`` for exact data), reproducible by
    ``seed``. Each record's ``meta`` holds its kind and the truth's parameter set name."""
    from ..models import Actuator, LuGre, PressureRegulator, PressureSource
    from ..simulation import simulate

    tests = paper_campaign(params) if tests is None else list(tests)
    friction = LuGre() if friction is None else friction
    records = []
    for test in tests:
        valve = PressureRegulator() if test.valve == "regulator" else PressureSource()
        result = simulate(Actuator(params, friction=friction, valve=valve), test.experiment)
        signals = {"pressure": result["pressure"], "position": result["position"]}
        if test.valve == "regulator":  # the bench logs what it commanded, too
            signals["setpoint"] = test.experiment.drive(result.time)
        records.append(Record.from_arrays(
            result.time, signals, source=test.name,
            meta={"kind": test.kind, "truth": params.name}))
    return add_noise(records, Noise() if noise is None else noise, seed)


def add_noise(records: Sequence[Record], noise: Noise, seed: int = 0) -> list[Record]:
    """The records with measurement ``noise`` on pressure and position, reproducible by
    ``seed`` (one simulation serves many noise realisations)."""
    rng = np.random.default_rng(seed)
    noisy = []
    for rec in records:
        pressure, position = noise.apply(rng, rec["pressure"], rec["position"])
        signals = {**rec.signals, "pressure": pressure, "position": position}
        noisy.append(Record.from_arrays(rec.time, signals, rec.units, rec.source,
                                        {**rec.meta, "seed": str(seed)}))
    return noisy
