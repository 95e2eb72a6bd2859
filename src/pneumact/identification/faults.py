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
- **a position-sensor lag** (``lag_search``): where the model does not fit, the lag
  that stage (c)'s viscous slope may hide (σ2 − k·τ) is searched on a grid; one that
  brings the model's prediction of the records within ``LAG_GAIN`` of the error
  without it is fitted jointly as ``position_lag`` (``models.sensors``).
- **the resolution and the sample rate** (``sensor_notes``): read from the records and
  named where they limit what the records can tell.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..io.records import Record
from .diagnostics import Diagnostic
from .inputs import noise_level, resolution, sensor_noise

__all__ = ["LAG_GAIN", "OFFSET_SIGMAS", "REGULATOR_RATIO", "PressureSide", "lag_search",
           "pressure_side", "sensor_notes"]

#: A pressure offset is named and taken off when it is this many standard errors from
#: zero (the records' offsets agree to ±0.3 Pa with 20 Pa of sensor noise: a real offset
#: of the sensor's noise is found) ...
OFFSET_SIGMAS = 5.0
#: ... and exceeds this fraction of the pressure sensor's noise (smaller ones change no
#: force beyond its noise).
OFFSET_NOISE = 0.5
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
#: Lags searched, in sample periods of the position record (up to the σ2 the stages
#: found, which a lag cannot exceed: k·τ ≤ σ2).
LAG_GRID_SAMPLES = (0.5, 1, 2, 4, 8, 16, 32, 64, 128)


@dataclass(frozen=True)
class PressureSide:
    """What the set-point/pressure pairs say: the pressure sensor's ``offset`` [Pa] and
    its standard error, per record the regulator check (``table``), the records as
    corrected (``records``: the offset taken off where it is named) and the
    ``diagnostics``."""

    offset: float
    offset_stderr: float
    applied: bool
    table: pd.DataFrame
    records: list[Record]
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def slow_regulator(self) -> list[str]:
        """The records the model's regulator does not follow."""
        return [r for r, ok in zip(self.table["record"], self.table["regulator_follows"],
                                   strict=True) if not ok]


def _regression(time, measured, simulated) -> tuple[float, float, float]:
    """(offset, delay [s], RMS left) of measured − simulated ≈ offset − delay·dp/dt."""
    difference = measured - simulated
    rate = np.gradient(simulated, time)
    design = np.column_stack([np.ones_like(difference), -rate])
    coef, *_ = np.linalg.lstsq(design, difference, rcond=None)
    left = difference - coef[0]
    return float(coef[0]), float(coef[1]), float(np.sqrt(np.mean(left**2)))


def _shifted(record: Record, offset: float) -> Record:
    if offset == 0.0:
        return record
    signals = {**record.signals, "pressure": record["pressure"] - offset}
    return Record.from_arrays(record.time, signals, record.units, record.source,
                              record.meta)


def pressure_side(records: Sequence[Record], prior, friction=None, chamber=None,
                  workers: int | None = 1) -> PressureSide:
    """The pressure sensor's offset and the regulator check (see the module docstring)
    from the ``records`` that logged a set-point, with the model at ``prior``."""
    from ..simulation import Rodas4, simulate
    from .fit import experiment_for, map_on_threads
    from .joint import bench_model

    paired = [r for r in records if "setpoint" in r and "pressure" in r]
    columns = ["record", "offset", "delay", "ratio", "regulator_follows"]
    if not paired:
        return PressureSide(0.0, np.inf, False, pd.DataFrame(columns=columns), list(records))

    def check(record: Record) -> dict:
        model = bench_model(record, prior, friction, chamber)
        result = simulate(model, experiment_for(model, record, smooth=True),
                          Rodas4(rtol=1e-6), t_eval=record.time)
        offset, delay, left = _regression(record.time, record["pressure"],
                                          result["pressure"])
        noise = max(sensor_noise(record["pressure"]), 1e-9)
        return {"record": record.source, "offset": offset, "delay": delay,
                "ratio": left / noise, "regulator_follows": bool(left <= REGULATOR_RATIO
                                                                 * noise)}

    table = pd.DataFrame(map_on_threads(workers or 1, check, paired), columns=columns)
    follows = table[table["regulator_follows"]]
    use = follows if len(follows) else table
    offsets = use["offset"].to_numpy()
    offset = float(np.median(offsets))
    noise = float(np.median([noise_level(r["pressure"]) for r in paired]))
    spread = 1.4826 * float(np.median(np.abs(offsets - offset))) if offsets.size > 2 else \
        noise
    stderr = max(spread, 1e-3 * noise) / np.sqrt(offsets.size)
    applied = abs(offset) > OFFSET_SIGMAS * stderr and abs(offset) > OFFSET_NOISE * noise
    diagnostics = []
    if applied:
        diagnostics.append(Diagnostic(
            "warning", "bench", f"the pressure sensor reads {offset / 1e3:+.3g} kPa "
            f"(±{1.96 * stderr:.2g} Pa) from the chamber pressure the regulator holds at "
            f"its set-point ({len(use)} records agree): taken off every pressure record "
            "(pressure_offset)", "zero the pressure sensor, or check the regulator's own "
            "offset against a reference gauge"))
    slow = set(table.loc[~table["regulator_follows"], "record"])
    if slow:
        worst = table.loc[table["ratio"].idxmax()]
        delay = float(worst["delay"])
        word = "later" if delay > 0 else "earlier"
        diagnostics.append(Diagnostic(
            "warning", "bench", f"the model's pressure regulator does not follow the "
            f"chamber pressure of {_names(sorted(slow))} (worst {Path(worst['record']).name}:"
            f" {worst['ratio']:.3g}× the pressure noise; the bench's pressure follows "
            f"{abs(delay) * 1e3:.3g} ms {word} than the model's): the records driven by "
            "the set-point then misfit for a reason that is not the actuator's",
            "state the regulator's reg_kp, reg_ti, reg_tau from its datasheet or a step "
            "response to a set-point step, and identify again"))
    corrected = [_shifted(r, offset if applied else 0.0) if "pressure" in r else r
                 for r in records]
    return PressureSide(offset, float(stderr), bool(applied), table, corrected, diagnostics)


def _names(names: Sequence[str], shown: int = 3) -> str:
    names = [Path(n).name for n in names]
    if len(names) <= shown + 1:
        return ", ".join(names)
    return f"{', '.join(names[:shown])} and {len(names) - shown} more"


def lag_search(records: Sequence[Record], kinds: Sequence[str], params, friction=None,
               chamber=None, workers: int | None = 1) -> tuple[float, float, float]:
    """(the position lag [s] that predicts ``records`` best, their error with it, without
    it): on each lag of the grid the model runs at ``params`` with σ2 less k·τ (the
    viscous friction stage (c) took the lag for); the error is the sum over the sweeps
    and ramps of the squared ratio of the prediction error to the noise
    (``joint.prediction_ratio``). A lag of 0 when none helps."""
    from .fit import map_on_threads
    from .joint import prediction_ratio

    moving = [(r, k) for r, k in zip(records, kinds, strict=True) if k != "presliding"]
    if not moving:
        return 0.0, np.inf, np.inf
    period = float(np.median(np.diff(moving[0][0].time)))
    largest = params["sigma2"] / params["k"]
    lags = [0.0] + [n * period for n in LAG_GRID_SAMPLES if n * period < largest]

    def error(tau: float) -> float:
        values = {"position_lag": tau, "sigma2": params["sigma2"] - params["k"] * tau}
        at = params.with_values(values)
        ratios = [prediction_ratio(r, k, at, friction, chamber) for r, k in moving]
        return float(np.sum(np.square(ratios)))

    errors = map_on_threads(workers or 1, error, lags)
    best = int(np.nanargmin(errors))
    return float(lags[best]), float(errors[best]), float(errors[0])


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
            "warning", "bench", f"the position is quantised at {step * 1e6:.3g} µm, more "
            f"than its noise ({float(quantised['position_noise'].median()) * 1e6:.2g} µm): "
            "where the actuator holds still or creeps the rounding error is not white, and "
            "the residual checks take resolution/√12 as the noise",
            "a finer position sensor or ADC (or dither) for the presliding test"))
    stuck = _stuck_frequency(params)
    presliding = table[table["kind"] == "presliding"]
    if len(presliding) and np.isfinite(stuck):
        rate = float(presliding["sample_rate"].min())
        if rate < 10.0 * stuck:
            notes.append(Diagnostic(
                "warning", "bench", f"the presliding record is sampled at {rate:.3g} Hz, "
                f"less than ten samples per period of the stuck mode ({stuck:.3g} Hz at the "
                "prior's σ0 and m): its steps and ringing fall between samples, so σ1 "
                "rests on little", f"sample the presliding test at {20 * stuck:.3g} Hz or "
                "faster (pneumact campaign --plan sets the rate)"))
    return notes, table


def _stuck_frequency(params) -> float:
    """The stuck mode's natural frequency [Hz]: the mass on spring and bristles."""
    try:
        return float(np.sqrt((params["k"] + params["sigma0"]) / params["m"]) / (2 * np.pi))
    except KeyError:
        return float("nan")
