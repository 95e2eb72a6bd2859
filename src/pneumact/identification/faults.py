"""What a real bench adds to the records, named from the records themselves.

A bench is not the model: its pressure sensor reads with an offset, its regulator is
slower or faster than the one in the model, its position sensor lags, quantises and
samples. Each of these, left out, shows only as "the model does not fit" and moves the
friction parameters (a 3 ms position lag is k·τ of viscous friction to eq. 13: σ2 ten
times too large on vgt-paper). Each is checked here where the records can tell:

- **the pressure side** (``pressure_side``): a record that logged both its regulator's
  set-point and the chamber pressure holds the pressure sensor's offset and the
  regulator's dynamics. The model at the prior, driven by the set-point, gives the
  chamber pressure; the measured one less it is regressed on [1, dp/dt]: the constant
  is the sensor's offset (the records' median, robust to the one whose transient
  breaks the regression), the slope how much later the bench's pressure follows than
  the model's. The offset is taken off every pressure record; a record whose pressure
  the model's regulator does not follow (``REGULATOR_RATIO``) says the bench's regulator
  is not the model's, and by how much later it follows. (Driving the model by the
  measured pressure instead was tried: on a regulator four times slower the rebuilt
  inputs left residuals of 3.5-4.5 noise deviations on every ramp, worse than the
  set-point; a fit of the regulator's time constant at the prior stopped at 13 ms of
  40 ms, the prior's friction moving the chamber. So the regulator is named, not fixed.)
- **the position sensor's zero** (``position_zero``): where a record starts at rest on
  the lower stop (the drive well below the prior's preload, which no friction can hold
  the diaphragm against), the model's position is the stop's tiny penetration
  (F0 − drive)/k_stop; what the sensor reads there, less that, is its offset. Left in,
  the preload absorbs k·offset and every record's motion misfits. The records' median
  is taken off every position record where it is significant.
- **a position-sensor lag** (``lag_search``): where the model does not fit, lags on a
  grid are undone from the records and the stages run again on them (a lag is k·τ of
  viscous friction to stage (c), and its transients can leave too few steady
  segments); the lag whose stages predict the records within ``LAG_GAIN`` of the error
  without it starts a joint fit that frees it (``position_lag``, ``models.sensors``).
- **the resolution and the sample rate** (``sensor_notes``): read from the records and
  named where they limit what the records can tell.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..io.records import PRESSURE_SIGNAL, Record
from ..models.actuator import CHAMBER_PRESSURE
from .diagnostics import Diagnostic, named_list
from .inputs import noise_level, resolution, sensor_noise
from .smoothing import savgol_filter

if TYPE_CHECKING:
    from ..parameters.parameter_set import ParameterSet

__all__ = [
    "LAG_BOUND_MARGIN",
    "LAG_GAIN",
    "OFFSET_SIGMAS",
    "PRESLIDING_ALIASED",
    "PRESLIDING_SAMPLES_PER_PERIOD",
    "REGULATOR_RATIO",
    "PositionZero",
    "PressureSide",
    "SensorOffset",
    "finest_sample_period",
    "lag_search",
    "position_zero",
    "pressure_side",
    "quantisation_covariance",
    "quantised_records",
    "regulator_check",
    "sensor_notes",
    "undersampled_presliding",
    "viscous_lag_bound",
    "without_lag",
]

#: A pressure offset is named and taken off when it is this many standard errors from
#: zero (the records' offsets agree to ±0.3 Pa with 20 Pa of sensor noise: a real offset
#: of the sensor's noise is found) ...
OFFSET_SIGMAS = 5.0
#: ... and exceeds this fraction of the pressure sensor's noise (smaller ones change no
#: force beyond its noise).
OFFSET_NOISE = 0.5
#: The position sensor's zero is read where the drive is below this share of the
#: preload the prior allows for (F0·(1 − prior_spread)): the diaphragm rests on its stop
#: whatever the prior's error ...
REST_DRIVE_SHARE = 0.5
#: ... on a record's first samples, before the drive first exceeds that: at least this
#: many (a record that starts elsewhere says nothing of the zero).
REST_MIN_SAMPLES = 10
#: A record whose measured chamber pressure departs from the model's (driven by the
#: set-point, at the prior) by more than this many pressure-noise deviations (RMS, the
#: offset removed) is not followed by the model's regulator: measured 1.2-5 on
#: campaigns of drawn actuators with the right regulator (the prior's friction moves the
#: chamber a little), 10-70 with a regulator four times slower or a gain four times
#: lower than the model's.
REGULATOR_RATIO = 10.0
#: A position lag is fitted when the model with it (and the σ2 it implies) predicts the
#: records with at most this share of the error (sum of squared noise ratios) without it.
LAG_GAIN = 0.5
#: The fewest sweeps and ramps a lag is judged on (``lag_search``): the records the
#: staged values predict within ``joint.ADMIT_RATIO`` noise deviations, where there are
#: this many, else all of them (a drawn actuator with a 2.7 ms lag, staged Fs −9 %, vs
#: +31 %: its slow ramps missed by 56-104 deviations with the lag or without it, its fast
#: ones by 2.9-9.1 without and 1.5-2.8 with it)
LAG_JUDGED_MIN = 2
#: The shares of the staged σ2 tried as a lag's k·τ (``lag_search``): without re-staging,
#: so between the grid's sample periods too (a 2.7 ms lag on 198 Hz records, whose grid
#: starts at 5.1 ms)
LAG_VISCOUS_SHARES = (0.25, 0.5, 0.65, 0.8, 0.9)
#: Lags searched, in the finest sample period of the sweeps' and ramps' records (a
#: sweep is often sampled slower than the ramps that resolve a lag).
LAG_GRID_SAMPLES = (1, 2, 4, 8, 16, 32, 64)
#: Stage (c) takes a lag τ for viscous friction k·τ, so the σ2 it found bounds the lag:
#: τ ≤ σ2/k. The grid stops at this multiple of that bound (σ2's scatter between
#: stagings); a bound below one sample period skips the search (no re-staging).
LAG_BOUND_MARGIN = 2.0
#: A lag is undone with the slope of a cubic over this many samples (the shortest
#: Savitzky-Golay derivative: the least smoothing).
DELAG_SAMPLES = 7


@dataclass(frozen=True)
class SensorOffset:
    """What the records say of one sensor's offset: the ``offset`` (reading − the model's
    value) and its standard error, whether it was taken off (``applied``), per record what
    it was read from (``table``), the records as corrected (``records``) and the
    ``diagnostics`` naming it."""

    offset: float
    offset_stderr: float
    applied: bool
    table: pd.DataFrame
    records: list[Record]
    diagnostics: list[Diagnostic] = field(default_factory=list)


@dataclass(frozen=True)
class PressureSide(SensorOffset):
    """The pressure sensor's offset [Pa] from the set-point/pressure pairs; ``table``: per
    record the regression at the prior."""


@dataclass(frozen=True)
class PositionZero(SensorOffset):
    """The position sensor's offset [m] from the records at rest on the lower stop;
    ``table``: per record the offset and the samples it rests on."""


def _rest_offset(record: Record, prior, prior_spread: float) -> dict | None:
    """The record's offset on its first samples at rest on the stop (see ``position_zero``),
    or None where it does not start there."""
    from .bench import drive_force

    drive = drive_force(record[PRESSURE_SIGNAL], prior)
    limit = REST_DRIVE_SHARE * (1.0 - prior_spread) * prior["F0"]
    above = np.flatnonzero(drive > limit)
    rest = slice(0, int(above[0]) if above.size else drive.size)
    if rest.stop < REST_MIN_SAMPLES:
        return None
    penetration = np.maximum(prior["F0"] - drive[rest], 0.0) / prior["k_stop"]
    reading = record["position"][rest] + penetration  # the model's position is −penetration
    return {"record": record.source, "offset": float(np.median(reading)),
            "samples": rest.stop, "noise": sensor_noise(record["position"]),
            "resolution": resolution(record["position"])}


def position_zero(records: Sequence[Record], prior, prior_spread: float = 0.5
                  ) -> PositionZero:
    """The position sensor's offset (see the module docstring) from the ``records`` that
    start at rest on the lower stop, with the preload and stop of ``prior``: the median
    of the records' offsets, its standard error from their spread (at least the noise of
    the samples read, and a quantised sensor's rounding), taken off every position
    record where it is ``OFFSET_SIGMAS`` standard errors from zero and above half the
    position noise."""
    rows = [row for r in records if "position" in r and PRESSURE_SIGNAL in r
            if (row := _rest_offset(r, prior, prior_spread)) is not None]
    table = pd.DataFrame(rows, columns=["record", "offset", "samples", "noise", "resolution"])
    if not len(table):
        return PositionZero(0.0, np.inf, False, table, list(records))
    offsets = table["offset"].to_numpy()
    offset = float(np.median(offsets))
    noise = float(table["noise"].median())
    spread = 1.4826 * float(np.median(np.abs(offsets - offset))) if offsets.size > 2 else 0.0
    floor = noise / np.sqrt(table["samples"].median())  # one record's median, white noise
    # a quantised sensor at rest reads one rounded value: its error, up to half a step,
    # is the same in every record and no average takes it off (q/√12, the phase unknown)
    rounding = float(table["resolution"].max()) / np.sqrt(12.0)
    stderr = max(spread / np.sqrt(offsets.size), floor, rounding)
    applied = abs(offset) > OFFSET_SIGMAS * stderr and abs(offset) > OFFSET_NOISE * noise
    diagnostics = []
    if applied:
        diagnostics.append(Diagnostic(
            "warning", "bench", f"the position sensor reads {offset * 1e6:+.3g} µm "
            f"(±{1.96 * stderr * 1e6:.2g} µm) where the diaphragm rests on its lower stop "
            f"({len(table)} records start there): taken off every position record "
            "(position_offset)", "zero the position sensor at the stop, or log the stop's "
            "reading with the records"))
    corrected = [_shifted(r, offset if applied else 0.0, "position") if "position" in r
                 else r for r in records]
    return PositionZero(offset, float(stderr), bool(applied), table, corrected, diagnostics)


def _regression(time, measured, simulated) -> tuple[float, float, float]:
    """(offset, delay [s], RMS left) of measured − simulated ≈ offset − delay·dp/dt."""
    difference = measured - simulated
    rate = np.gradient(simulated, time)
    design = np.column_stack([np.ones_like(difference), -rate])
    coef, *_ = np.linalg.lstsq(design, difference, rcond=None)
    left = difference - coef[0]
    return float(coef[0]), float(coef[1]), float(np.sqrt(np.mean(left**2)))


def _shifted(record: Record, offset: float, signal: str = PRESSURE_SIGNAL) -> Record:
    if offset == 0.0:
        return record
    signals = {**record.signals, signal: record[signal] - offset}
    return Record.from_arrays(record.time, signals, record.units, record.source,
                              record.meta)


def _pressure_table(records: Sequence[Record], params, friction, chamber,
                    workers: int | None) -> pd.DataFrame:
    """Per record with a set-point: the regression of its measured chamber pressure on
    the model's at ``params`` (offset, delay, RMS left over the pressure noise)."""
    from ..simulation import Rodas4, simulate
    from .fit import experiment_for, map_on_threads
    from .joint import bench_model

    def check(record: Record) -> dict:
        model = bench_model(record, params, friction, chamber)
        result = simulate(model, experiment_for(model, record, smooth=True),
                          Rodas4(rtol=1e-6), t_eval=record.time)
        offset, delay, left = _regression(record.time, record[PRESSURE_SIGNAL],
                                          result[CHAMBER_PRESSURE])
        noise = max(sensor_noise(record[PRESSURE_SIGNAL]), 1e-9)
        return {"record": record.source, "offset": offset, "delay": delay,
                "ratio": left / noise, "regulator_follows": bool(left <= REGULATOR_RATIO
                                                                 * noise)}

    paired = [r for r in records if "setpoint" in r and PRESSURE_SIGNAL in r]
    return pd.DataFrame(map_on_threads(workers or 1, check, paired),
                        columns=["record", "offset", "delay", "ratio", "regulator_follows"])


def pressure_side(records: Sequence[Record], prior, friction=None, chamber=None,
                  workers: int | None = 1) -> PressureSide:
    """The pressure sensor's offset (see the module docstring) from the ``records``
    that logged a set-point, with the model at ``prior``: the median of the records'
    offsets (a fast ramp whose motion the prior's friction gets wrong departs from the
    model by more than an offset, the others agree)."""
    table = _pressure_table(records, prior, friction, chamber, workers)
    if not len(table):
        return PressureSide(0.0, np.inf, False, table, list(records))
    offsets = table["offset"].to_numpy()
    offset = float(np.median(offsets))
    noise = float(np.median([noise_level(r[PRESSURE_SIGNAL]) for r in records
                             if "setpoint" in r and PRESSURE_SIGNAL in r]))
    spread = 1.4826 * float(np.median(np.abs(offsets - offset))) if offsets.size > 2 else \
        noise
    stderr = max(spread, 1e-3 * noise) / np.sqrt(offsets.size)
    applied = abs(offset) > OFFSET_SIGMAS * stderr and abs(offset) > OFFSET_NOISE * noise
    diagnostics = []
    if applied:
        diagnostics.append(Diagnostic(
            "warning", "bench", f"the pressure sensor reads {offset / 1e3:+.3g} kPa "
            f"(±{1.96 * stderr:.2g} Pa) from the chamber pressure the regulator holds at "
            f"its set-point ({len(table)} records): taken off every pressure record "
            "(pressure_offset)", "zero the pressure sensor, or check the regulator's own "
            "offset against a reference gauge"))
    corrected = [_shifted(r, offset if applied else 0.0) if PRESSURE_SIGNAL in r else r
                 for r in records]
    return PressureSide(offset, float(stderr), bool(applied), table, corrected, diagnostics)


def regulator_check(records: Sequence[Record], params, friction=None, chamber=None,
                    workers: int | None = 1) -> tuple[pd.DataFrame, list[Diagnostic]]:
    """Does the model's chamber pressure follow the bench's? At the identified ``params`` (the
    friction right, so the motion and the chamber volume are), each record's measured
    pressure against the model's (``REGULATOR_RATIO``), and the median delay of those
    it does not follow. Returns the table and a diagnostic naming it, if any."""
    table = _pressure_table(records, params, friction, chamber, workers)
    slow = table[~table["regulator_follows"]] if len(table) else table
    if not len(slow):
        return table, []
    delay = float(slow["delay"].median())
    word = "later" if delay > 0 else "earlier"
    worst = slow.loc[slow["ratio"].idxmax()]
    shown = named_list([Path(n).name for n in sorted(slow["record"])])
    return table, [Diagnostic(
        "warning", "bench", f"the chamber pressure the model makes from the set-point does "
        f"not follow the measured one on {shown} (up to "
        f"{worst['ratio']:.3g}× the pressure noise, {Path(worst['record']).name}; the "
        f"bench's pressure follows {abs(delay) * 1e3:.3g} ms {word} than the model's): the "
        "bench's regulator or the chamber's thermodynamics are not the model's, and the "
        "records driven by the set-point misfit for that reason",
        "state the regulator's reg_kp, reg_ti, reg_tau (datasheet, or its response to a "
        "set-point step), or try another chamber law (chamber=Adiabatic()), and identify "
        "again")]


def without_lag(records: Sequence[Record], tau: float) -> list[Record]:
    """The ``records`` with a first-order position lag ``tau`` undone (x + τ·dx/dt, the
    slope of a cubic over ``DELAG_SAMPLES`` samples): a start for the stages, which
    read forces from positions, not a record to fit (its noise is no longer white)."""
    out = []
    for record in records:
        x = record["position"]
        dt = float(np.median(np.diff(record.time)))
        if tau <= 0 or x.size <= DELAG_SAMPLES:
            out.append(record)
            continue
        slope = savgol_filter(x, DELAG_SAMPLES, 3, deriv=1, delta=dt)
        out.append(Record.from_arrays(record.time, {**record.signals,
                                                    "position": x + tau * slope},
                                      record.units, record.source, record.meta))
    return out


def finest_sample_period(records: Sequence[Record], kinds: Sequence[str]) -> float:
    """The shortest median sample period [s] of the sweeps and ramps (a sweep is often
    logged slower than the ramps that resolve a lag)."""
    return min(float(np.median(np.diff(r.time)))
               for r, kind in zip(records, kinds, strict=True) if kind != "presliding")


def lag_search(records: Sequence[Record], kinds: Sequence[str], staged: ParameterSet,
               restage: Callable[[list[Record]], ParameterSet], friction=None,
               chamber=None, workers: int | None = 1, longest: float = np.inf
               ) -> tuple[float, ParameterSet, float, float]:
    """(the position lag [s] that predicts ``records`` best, the staged values with it,
    the records' error with it, without it). Each lag τ of the grid is tried twice: the
    stages run again (``restage``: records -> parameter set, or an exception) on the
    records with that lag undone (``without_lag``); and for each share of the staged
    σ2 in ``LAG_VISCOUS_SHARES``, the staged values with that share of σ2 taken for a lag
    τ = share·σ2/k (stage (c) reads a lag as viscous friction k·τ: the same steady
    sliding, the lag's transients). The model at those values, seen through the lag, predicts the
    original records; the error is the sum of the squared ratios of the prediction error
    to the noise (``joint.prediction_ratio``) over the sweeps and ramps the staged values
    predict within ``joint.ADMIT_RATIO`` noise deviations (all of them where fewer than
    ``LAG_JUDGED_MIN`` do: a record missed farther is in another regime, stick-slip
    against sliding, and a lag's small change there is not evidence). A lag of 0 (and
    ``staged``) when none helps. Only lags up to ``longest`` are re-staged
    (``viscous_lag_bound``): none where it is below one sample period, and then only
    the shares of σ2 are tried (a 1.15 ms lag on 101 Hz records: the grid starts at
    9.9 ms, above the 5.1 ms bound, and the lag is a share of the staged σ2)."""
    from .fit import map_on_threads
    from .joint import ADMIT_RATIO, prediction_ratio

    moving = [(r, k) for r, k in zip(records, kinds, strict=True) if k != "presliding"]
    if not moving:
        return 0.0, staged, np.inf, np.inf
    period = finest_sample_period(records, kinds)
    grid = [n * period for n in LAG_GRID_SAMPLES if n * period <= longest]

    def ratios(at, which) -> np.ndarray:
        return np.array([prediction_ratio(r, kind, at, friction, chamber)
                         for r, kind in which])

    first = map_on_threads(workers or 1, lambda rk: ratios(staged, [rk])[0], moving)
    near = [i for i, ratio in enumerate(first) if ratio <= ADMIT_RATIO]
    chosen = near if len(near) >= LAG_JUDGED_MIN else range(len(moving))
    judged = [moving[i] for i in chosen]
    trials = []
    for tau in grid:
        try:
            trials.append((tau, restage(without_lag(records, tau)).with_values(
                {"position_lag": tau})))
        except Exception:
            continue
    for share in LAG_VISCOUS_SHARES:
        tau = share * staged["sigma2"] / staged["k"]
        trials.append((tau, staged.with_values({"position_lag": tau,
                                                "sigma2": (1.0 - share) * staged["sigma2"]})))
    without = float(np.sum(np.square([first[i] for i in chosen])))
    errors = map_on_threads(workers or 1,
                            lambda trial: float(np.sum(np.square(ratios(trial[1], judged)))),
                            trials)
    if not trials or not np.nanmin(errors) < without:
        return 0.0, staged, without, without
    best = int(np.nanargmin(errors))
    return trials[best][0], trials[best][1], float(errors[best]), without


def viscous_lag_bound(staged: ParameterSet) -> float:
    """The longest position lag [s] the staged values allow: stage (c) reads a lag τ as
    viscous friction k·τ, so τ ≤ σ2/k, times ``LAG_BOUND_MARGIN``."""
    return LAG_BOUND_MARGIN * max(staged["sigma2"], 0.0) / staged["k"]


def sensor_notes(records: Sequence[Record], kinds: Sequence[str], params
                 ) -> tuple[list[Diagnostic], pd.DataFrame]:
    """Notes on what the position sensor's resolution and the sample rate limit, and a
    table of both per record (read from the records)."""
    rows, notes = [], []
    for record, kind in zip(records, kinds, strict=True):
        x = record["position"]
        step = resolution(x)
        rate = 1.0 / float(np.median(np.diff(record.time)))
        rows.append({"record": record.source, "kind": kind, "position_resolution": step,
                     "position_noise": noise_level(x), "sample_rate": rate})
    table = pd.DataFrame(rows, columns=["record", "kind", "position_resolution",
                                        "position_noise", "sample_rate"])
    quantised = table[table["position_resolution"] > np.sqrt(12.0)
                      * table["position_noise"]]
    if len(quantised):
        step = float(quantised["position_resolution"].max())
        notes.append(Diagnostic(
            "warning", "bench", f"the position is quantised at {step * 1e6:.3g} µm, "
            f"coarser than its white noise ({_micrometres(quantised['position_noise'])}): "
            "where the actuator holds still or creeps the rounding error is not white; the "
            "residual checks take resolution/√12 as the noise, and the rounding's effect "
            "on the estimates (its unknown phase, drawn) is in their intervals",
            "a finer position sensor or ADC (or dither) for the presliding test"))
    stuck = _stuck_frequency(params)
    slowest = undersampled_presliding(table, params)
    if slowest is not None:
        notes.append(Diagnostic(
            "warning", "bench", f"the presliding record is sampled at {slowest:.3g} Hz, "
            f"less than ten samples per period of the stuck mode ({stuck:.3g} Hz at the "
            "prior's σ0 and m): its steps and ringing fall between samples, so σ1 "
            "rests on little", f"sample the presliding test at {20 * stuck:.3g} Hz or "
            "faster (pneumact campaign --plan sets the rate)"))
    return notes, table


#: A presliding test resolves its steps and ringing with at least this many samples per
#: period of the stuck mode (fewer: a note, σ1 rests on little) ...
PRESLIDING_SAMPLES_PER_PERIOD = 10.0
#: ... and below this many the stuck mode's ringing is aliased or nearly so: σ0 and σ1
#: get no interval. The sampling theorem's two is not enough: measured on one drawn
#: actuator (family-7-22 of 40, noise seed 1) sampled at 2.2, 3.0, 4.0 and 5.0 samples
#: per period: σ0 −17 % at ±6.7 % ("identified"), then −0.7 %, −1.5 %, +0.01 %; another
#: at 1.5: σ0 −0.15 % at ±0.05 %; another at 5.9: σ0 and σ1 within 0.2 %.
PRESLIDING_ALIASED = 3.0


def undersampled_presliding(table: pd.DataFrame, params,
                            per_period: float = PRESLIDING_SAMPLES_PER_PERIOD
                            ) -> float | None:
    """The sample rate [Hz] of the slowest presliding record of ``table``
    (``sensor_notes``) where it is below ``per_period`` samples per period of the stuck
    mode at ``params``, else None."""
    stuck = _stuck_frequency(params)
    presliding = table[table["kind"] == "presliding"]
    if not len(presliding) or not np.isfinite(stuck):
        return None
    rate = float(presliding["sample_rate"].min())
    return rate if rate < per_period * stuck else None


def _micrometres(noise: pd.Series) -> str:
    value = float(noise.median()) * 1e6
    return f"{value:.2g} µm" if value >= 0.01 else "none measurable"


def _stuck_frequency(params) -> float:
    """The stuck mode's natural frequency [Hz]: the mass on spring and bristles."""
    try:
        return float(np.sqrt((params["k"] + params["sigma0"]) / params["m"]) / (2 * np.pi))
    except KeyError:
        return float("nan")


#: Draws of the quantisation's unknown phase (``quantisation_covariance``).
QUANTISATION_DRAWS = 64


def quantised_records(fit) -> dict[int, float]:
    """Record index -> the position resolution of each record of ``fit`` whose
    quantisation exceeds its white noise (resolution > √12 × ``noise_level``)."""
    out = {}
    for i, record in enumerate(fit.records):
        step = resolution(record["position"])
        if step > np.sqrt(12.0) * noise_level(record["position"]):
            out[i] = step
    return out


def quantisation_covariance(fit, steps: dict[int, float], draws: int = QUANTISATION_DRAWS,
                            seed: int = 0) -> np.ndarray:
    """What a position sensor's quantisation does to the estimates of ``fit``: the
    rounding error of a coarse sensor (``steps``: record index -> resolution) is not
    white noise but a function of the position, so it does not average out where the
    actuator holds still or creeps. Its phase on the grid is unknown: each draw rounds
    the fitted position with a random phase per record, and one Gauss-Newton step maps
    the rounding error onto the estimates; their covariance over the draws is added to
    the estimates' (the residual covariance alone missed the truth on 2 of 8
    parameters of a 10 µm sensor)."""
    rng = np.random.default_rng(seed)
    jac = np.asarray(fit.jacobian, dtype=float)
    masks = fit.masks()
    moves = []
    for _ in range(draws):
        rows = []
        for i, mask in enumerate(masks):
            for signal in fit.signals:
                n = int(mask.sum())
                step = steps.get(i) if signal == "position" else None
                if step is None:
                    rows.append(np.zeros(n))
                    continue
                shifted = fit.fitted(i, signal)[mask] + rng.uniform(-step / 2, step / 2)
                error = np.round(shifted / step) * step - shifted
                rows.append(fit.weight(i, signal) * error)
        moves.append(np.linalg.lstsq(jac, np.concatenate(rows), rcond=None)[0])
    return np.cov(np.array(moves), rowvar=False)
