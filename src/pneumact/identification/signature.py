"""What one slow up-and-down loop (a valve signature) tells about the actuator.

The data most users have is a positioner's "valve signature": a slow pressure sweep up
and down with the position logged (the paper's own Fig. 6 bench). Of the force balance
(p_atm − p)·A_d − m·a = F0 + k·x + F_f it determines

- F0 and k: the mean of the two branches (the spring line);
- the friction level on the branches: half their separation times A_d, which is
  Fc + σ2·|v| + the Stribeck term at the sweep's speed. Fc is that level less σ2·|v|
  (σ2 fitted where the speed varies enough to tell it, else the prior's with its
  uncertainty) less the Stribeck term, of which only a bound is known (the prior's
  highest plausible Fs and vs at the sweep's slowest speed, Fc what the level leaves):
  half the bound is taken off and the whole bound goes into the interval;
- σ2 where the branch speed varies by at least ``SPEED_RANGE`` (a sine sweep), else
  nothing;

and nothing of Fs, vs, σ0 and σ1 (they act below the sweep's speed or in micrometres of
presliding): those are named as not identifiable from a signature, with the test that
would fix each. The valve engineer's numbers come with it: the bench set (the pressures
at the start and the end of the rated travel on the spring line), the spring rate, the
friction band and the dead band (the pressure change after a reversal before the
position moves), each with its interval.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from ..errors import DataError
from ..io.records import PRESSURE_SIGNAL, Record
from .diagnostics import (
    IDENTIFIED_HALF_WIDTH,
    MISFIT_STRUCTURE,
    MODEL_FIDELITY,
    NOT_IDENTIFIABLE,
    POORLY_HALF_WIDTH,
    REMEDIES,
    SMOOTHING_SAMPLES,
    Diagnostic,
    Verdict,
    verdicts,
)
from .estimates import Estimates, linear_least_squares
from .inputs import noise_level, sensor_noise
from .stages import StageResult, sliding_branches

__all__ = ["SIGNATURE_PARAMETERS", "SPEED_RANGE", "SPRING_LINE_AGREEMENT", "UNSTATED_LAG",
           "SignatureFit", "signature_fit", "spring_line_check", "valve_numbers"]

#: What a signature can determine; the other spring and friction parameters it cannot.
SIGNATURE_PARAMETERS = ("F0", "k", "Fc", "sigma2")
#: σ2 is fitted only when the sliding speeds on the branches span at least this ratio
#: (10th to 90th percentile): on a sweep at one speed σ2·|v| is a constant, which Fc
#: absorbs (the two columns of the regression are then the same up to a factor).
SPEED_RANGE = 2.0
#: Samples faster than this many of the highest plausible vs are used whatever the
#: branch's median speed (the Stribeck term is below e^-3 = 5 % of Fs − Fc there, and
#: its bound goes into Fc's interval): a sine sweep's varying speed tells σ2.
STRIBECK_DECAYED = 3.0
#: The velocity is differentiated over this many of the usual windows: its noise
#: (5 % of the speed over the usual window) would bias σ2 low and Fc high by the
#: share of the speed's variance it makes (errors in the regressor: 1-2 % measured on
#: a sine sweep); a window 4× longer has 8× less noise, and the margins keep the
#: reversals, where a long window blurs, out of the fit.
SIGNATURE_SMOOTHING = 4.0
#: A position sensor's lag the prior does not state (``position_lag``; 0 states none) is
#: taken as uniform on [0, ``UNSTATED_LAG``] [s] (a potentiometer's filter, an LVDT's
#: demodulator): it reads as k·τ·|v| of friction on the branches (k·τ on a fitted σ2)
UNSTATED_LAG = 0.01
#: ... and is named where it moves Fc by this share or more
LAG_NOTE_SHARE = 0.01
#: The dead band is read where the position has left its turning value by this many
#: position-noise standard deviations (a 5-σ move: noise alone never qualifies).
DEAD_BAND_SIGMAS = 5.0
#: Why the parameters a signature cannot tell stay unidentified.
NOT_FROM_A_SIGNATURE = {
    "Fs": "a signature slides at one speed range: static friction acts below it",
    "vs": "a signature slides at one speed range: the Stribeck velocity acts below it",
    "sigma0": "the bristle stiffness acts over micrometres, after a stop: a signature "
              "never stops on a branch",
    "sigma1": "the bristle damping acts over micrometres, after a stop: a signature "
              "never stops on a branch",
    "delta": "the Stribeck exponent acts below the signature's speed range",
}


@dataclass(frozen=True)
class SignatureFit:
    """The signature's regression: its estimates (F0, k, Fc and σ2 when the speed
    varies), the friction level and its speed, the bound of the Stribeck term taken
    into Fc's interval, the stage result (data and fit) and the findings."""

    estimates: Estimates
    level: float
    level_stderr: float
    speed: float
    stribeck_bound: float
    sigma2_fitted: bool
    stage: StageResult
    diagnostics: tuple[Diagnostic, ...]
    structure: float
    #: the friction level less σ2·|v| (the prior's where σ2 is not fitted): what Fc and
    #: the Stribeck term share; at or below zero Fc is not told
    coulomb_room: float = np.inf


def _structure(residual: np.ndarray) -> float:
    """RMS of the residual averaged over ``SMOOTHING_SAMPLES`` against what white noise
    of the residual's own level leaves after that average (1 for noise alone)."""
    width = min(SMOOTHING_SAMPLES, residual.size)
    averaged = np.convolve(residual, np.ones(width) / width, mode="valid")
    noise = noise_level(residual)
    return float(np.sqrt(np.mean(averaged**2)) / (noise / np.sqrt(width))) if noise > 0 \
        else np.inf


def stribeck_bound(params, speed: float, spread: float, level: float) -> float:
    """The largest Stribeck term S = (Fs − Fc)·e, e = exp(−(v/vs)^δ), at ``speed`` [N]
    that an actuator within ``spread`` of ``params`` can have when its friction level
    on the branches is ``level`` = Fc + σ2·v + S: Fs and vs at their highest, Fc what
    the level leaves, so S = (Fs_high − level + σ2·v + S)·e, solved for S."""
    high = 1.0 + spread
    decay = float(np.exp(-((speed / (params["vs"] * high)) ** params["delta"])))
    if decay >= 1.0:
        return np.inf
    excess = params["Fs"] * high - level + params["sigma2"] * high * speed
    return float(max(excess, 0.0) * decay / (1.0 - decay))


def signature_fit(sweeps: Sequence[Record], params, spread: float = 0.5) -> SignatureFit:
    """The regression (p_atm − p)·A_d − m·a = F0 + k·x + F·sgn(v) (+ σ2·v where the
    speed varies) over the freely sliding samples of the ``sweeps``; Fc from the level F
    (see the module docstring), its interval including σ2's and the Stribeck bound's."""
    fast = STRIBECK_DECAYED * params["vs"] * (1.0 + spread)
    parts = [sliding_branches(r, params, fast, SIGNATURE_SMOOTHING) for r in sweeps]
    x, f, v = (np.concatenate([p[i] for p in parts]) for i in range(3))
    if not (np.any(v > 0) and np.any(v < 0)):
        raise DataError("signature: the records need both branches (the position rising "
                        "and falling) off the rest stop; a signature is a slow sweep up "
                        "and back down")
    speed = np.abs(v)
    low, high = np.percentile(speed, [10, 90])
    sign = np.sign(v)
    prior_s2 = params["sigma2"]
    prior_s2_sd = prior_s2 * spread / 1.96
    columns = [np.ones_like(x), x, sign]
    names, units = ["F0", "k", "friction_level"], ["N", "N/m", "N"]
    sigma2_fitted = False
    if high >= SPEED_RANGE * low:  # the speed varies: try σ2
        est, residual, _ = linear_least_squares(np.column_stack([*columns, v]), f,
                                                [*names, "sigma2"], [*units, "N*s/m"],
                                                "signature", correlated=True)
        # the records tell σ2 when they pin it better than the prior does, or to
        # within POORLY_HALF_WIDTH whatever the prior says
        tells = max(prior_s2_sd, POORLY_HALF_WIDTH * abs(est["sigma2"]) / 1.96)
        sigma2_fitted = bool(est["sigma2"] > 0 and est.stderr[3] < tells)
    if not sigma2_fitted:
        est, residual, _ = linear_least_squares(np.column_stack(columns), f, names, units,
                                                "signature", correlated=True)
    slowest = float(low)
    mean_speed = float(np.mean(speed))
    level = est["friction_level"]
    # what the level leaves for Fc and the Stribeck term together: Fc ≥ 0 caps the
    # Stribeck term at it (a sweep near the prior's highest vs: uncapped, the bound's
    # midpoint put Fc below zero on 3 of 16 drawn actuators)
    room = level - (0.0 if sigma2_fitted else prior_s2 * mean_speed)
    bound = min(stribeck_bound(params, slowest, spread, level), max(room, 0.0))
    # an unstated lag's viscous share k·τ (uniform on [0, k·UNSTATED_LAG], no more than
    # what it would read as): half taken off, the whole in the interval
    lag_viscous = est["k"] * (UNSTATED_LAG if "position_lag" not in params else 0.0)
    level_se = float(est.stderr[2])
    if sigma2_fitted:
        lag_viscous = min(lag_viscous, est["sigma2"])
        fc, s2 = level - bound / 2, est["sigma2"] - lag_viscous / 2
        cov = est.covariance.copy()
        cov[2, 2] += bound**2 / 12  # the Stribeck term: uniform on [0, bound]
        cov[3, 3] += lag_viscous**2 / 12
    else:  # σ2 held at the prior, its uncertainty carried into Fc's
        lagged = min(lag_viscous * mean_speed, max(room, 0.0))
        fc, s2 = level - prior_s2 * mean_speed - bound / 2 - lagged / 2, prior_s2
        cov = np.zeros((4, 4))
        cov[:3, :3] = est.covariance
        cov[2, 2] += (mean_speed * prior_s2_sd) ** 2 + bound**2 / 12 + lagged**2 / 12
        cov[3, 3] = np.inf
    if room <= 0:  # no Coulomb friction left to tell: Fc held at the prior's
        fc = params["Fc"]
        cov[2, :] = cov[:, 2] = np.inf
    # the same lag on the spring line, mostly its transients after each reversal near
    # the stroke's ends: what undoing the whole of it moves F0 and k by (half taken off,
    # the whole, uniform, in their intervals; the 40-actuator study: unstated lags of
    # 0.9-15 ms moved them 0.03-0.16 % at ±0.02-0.08 %)
    spring_shift = _unstated_lag_shift(sweeps, params, spread, est) if lag_viscous > 0 \
        else np.zeros(2)
    cov[:2, :2] += np.outer(spring_shift, spring_shift) / 12
    values = np.array([est["F0"] - spring_shift[0] / 2, est["k"] - spring_shift[1] / 2,
                       fc, s2])
    fidelity = (MODEL_FIDELITY * values[:3]) ** 2
    cov[np.arange(3), np.arange(3)] += fidelity
    stderr = np.sqrt(np.diag(cov))
    estimates = Estimates(SIGNATURE_PARAMETERS, values, stderr, cov, est.dof,
                          ("N", "N/m", "N", "N*s/m"))
    structure = _structure(residual)
    notes = []
    if not sigma2_fitted:
        notes.append(Diagnostic(
            "note", "signature", f"the branches slide at one speed ({low * 1e3:.3g}-"
            f"{high * 1e3:.3g} mm/s): σ2 is held at the prior's {prior_s2:.3g} N·s/m and "
            f"its ±{100 * spread:.0f} % goes into Fc's interval", REMEDIES["sigma2"]))
    # a position sensor's lag τ reads x − v·τ: k·τ·|v| of friction on the branches (its
    # transients at the reversals aside); undone where the prior states it
    # (``identify_signature``), else taken as up to UNSTATED_LAG and named
    lagged = est["k"] * UNSTATED_LAG * mean_speed
    if "position_lag" not in params and lagged >= LAG_NOTE_SHARE * abs(fc):
        notes.append(Diagnostic(
            "note", "signature", f"the position sensor's lag is not stated: taken as 0-"
            f"{UNSTATED_LAG * 1e3:.3g} ms, which reads as up to {lagged:.3g} N of friction "
            f"at the sweep's {mean_speed * 1e3:.3g} mm/s ({100 * lagged / abs(fc):.2g} % of "
            "Fc): half of it taken off, the whole in Fc's interval", "state the sensor's "
            "lag in the prior (position_lag; 0 for none), or sweep more slowly"))
    if bound > IDENTIFIED_HALF_WIDTH * abs(fc):
        notes.append(Diagnostic(
            "warning", "signature", f"the sweep slides at {slowest * 1e3:.3g} mm/s, within "
            f"reach of the Stribeck velocity the prior allows: up to {bound:.3g} N of the "
            "friction level may be static friction, so Fc is uncertain by that much",
            "a faster sweep, or ramps well above vs"))
    data = pd.DataFrame({"x": x * 1e3, "measured": f, "fitted": f - residual,
                         "branch": sign})
    stage = StageResult("signature", estimates, tuple(Path(r.source).name for r in sweeps), data,
                        "position [mm]", "drive force (p_atm − p)·A_d − m·a [N]",
                        extra={"speed": mean_speed, "slowest": slowest})
    return SignatureFit(estimates, float(level), level_se, mean_speed, bound,
                        sigma2_fitted, stage, tuple(notes), structure, float(room))


def _unstated_lag_shift(sweeps: Sequence[Record], params, spread: float,
                        est: Estimates) -> np.ndarray:
    """How much a position lag of ``UNSTATED_LAG`` moves the spring line (F0, k) of
    ``est``: the sweeps' fit with that lag undone (``faults.without_lag``), less
    ``est``'s (zero where the undone sweeps cannot be fitted)."""
    from .faults import without_lag

    try:
        undone = signature_fit(without_lag(sweeps, UNSTATED_LAG),
                               params.replace(position_lag=UNSTATED_LAG), spread)
    except DataError:
        return np.zeros(2)
    return np.array([est["F0"] - undone.estimates["F0"], est["k"] - undone.estimates["k"]])


def signature_verdicts(fit: SignatureFit, names: Sequence[str]) -> list[Verdict]:
    """A verdict for each of ``names``: F0, k, Fc (and σ2 if fitted) by their intervals,
    refused together when the spring line does not fit the branches; every other
    parameter not identifiable from a signature, with the test that would tell it."""
    est = fit.estimates
    caveat = ""
    if fit.structure > MISFIT_STRUCTURE:
        caveat = (f"a straight spring line with constant friction does not fit the "
                  f"branches (their residual averaged over {SMOOTHING_SAMPLES} samples is "
                  f"{fit.structure:.3g}× what noise leaves): a non-linear spring, a sensor "
                  "lag or stick-slip")
    ci = est.interval(0.95)
    half = (ci[:, 1] - ci[:, 0]) / 2
    judged = {v.parameter: v for v in verdicts(est.names, est.values, half,
                                               [False] * len(est.names), caveat)}
    if not fit.sigma2_fitted:
        judged["sigma2"] = Verdict("sigma2", NOT_IDENTIFIABLE, "the signature slides at one "
                                   "speed: σ2·|v| is a constant, which Fc absorbs",
                                   REMEDIES["sigma2"])
    if fit.coulomb_room <= 0:
        judged["Fc"] = Verdict("Fc", NOT_IDENTIFIABLE, f"the friction level on the branches "
                               f"({fit.level:.3g} N) is no more than the prior's σ2·|v| at "
                               f"the sweep's speed: no Coulomb friction is left to tell",
                               "ramps at several steady speeds (pneumact campaign --plan), "
                               "which tell σ2 and Fc apart")
    out = []
    for name in names:
        if name in judged:
            out.append(judged[name])
        else:
            out.append(Verdict(name, NOT_IDENTIFIABLE,
                               NOT_FROM_A_SIGNATURE.get(name, "not from a signature"),
                               REMEDIES.get(name, "")))
    return out


#: The spring line of the sweep vouches for the joint fit's F0 or k where the two differ
#: by less than this many standard deviations of their difference (95 %)
SPRING_LINE_AGREEMENT = 1.96
#: The parameters a sweep's spring line tells whatever the friction dynamics do
SPRING_LINE = ("F0", "k")


def spring_line_check(sweeps: Sequence[Record], params, spread: float, joint: Estimates,
                      judged: Sequence[Verdict]) -> tuple[Estimates | None, list[Verdict]]:
    """F0 and k from the sweeps' spring line where the joint fit could not vouch for
    them (a record it does not follow, a misfit's influence): the spring line is the
    mean of the two branches, which stick-slip and the friction's dynamics move little,
    but it has failure modes of its own (stick-slip on the branches biases it by a
    few standard errors). So it is taken only where its own fit holds (the branches'
    structure, its verdict) and the joint estimate, made by output error from every
    record, is precise (it would be identified but for the misfit) and agrees with it
    within ``SPRING_LINE_AGREEMENT`` standard deviations of the difference: two
    estimators that fail differently. Returns the spring line's
    estimates (None where nothing was vouched for) and a verdict per vouched name."""
    wanted = [v.parameter for v in judged if v.parameter in SPRING_LINE and not v.identified]
    if not wanted or not sweeps:
        return None, []
    try:
        fitted = signature_fit(sweeps, params, spread)
    except DataError:  # a sweep without both branches off the stop
        return None, []
    own = {v.parameter: v for v in signature_verdicts(fitted, list(SPRING_LINE))}
    est = fitted.estimates
    out = []
    for name in wanted:
        j = joint.names.index(name)
        se_joint, se_line = joint.stderr[j], est.stderr[est.names.index(name)]
        # the joint estimate is precise enough to be identified but for what it could
        # not vouch for: agreement with a wide one (two optima) would prove nothing
        precise = 1.96 * se_joint <= IDENTIFIED_HALF_WIDTH * abs(joint.values[j])
        if not (own[name].identified and precise):
            continue
        distance = abs(joint.values[j] - est[name]) / np.hypot(se_joint, se_line)
        if distance <= SPRING_LINE_AGREEMENT:
            out.append(Verdict(name, own[name].verdict, f"{own[name].reason}, from the "
                               f"sweep's spring line (the joint fit, which could not vouch "
                               f"for it, agrees within {distance:.2g} standard deviations)"))
    return (est if out else None), out


def _turns(record: Record) -> list[int]:
    """Indices where the drive (the logged set-point, else the pressure, smoothed over
    half a per cent of the record) turns."""
    drive = record["setpoint"] if "setpoint" in record.signals else record[PRESSURE_SIGNAL]
    n = max(5, len(record) // 200) | 1
    smooth = np.convolve(drive, np.ones(n) / n, mode="valid")
    step = np.diff(smooth)
    moving = np.abs(step) > 1e-9 * max(np.ptp(smooth), 1.0)
    signs = np.sign(step[moving])
    where = np.flatnonzero(moving)
    turns = where[1:][signs[1:] != signs[:-1]]
    return [int(i) + n // 2 for i in turns]


def dead_band(records: Sequence[Record], params) -> tuple[float, float, int]:
    """The pressure change [Pa] after each reversal of the drive (off the rest stop)
    before the position moves back by ``DEAD_BAND_SIGMAS`` noise deviations: its mean,
    the half-width of its 95 % interval (the spread between reversals, and the pressure
    the detection distance takes along the spring line), and how many reversals were
    read (0: none, then NaNs)."""
    bands, resolutions = [], []
    for record in records:
        x, p = record["position"], record[PRESSURE_SIGNAL]
        floor = x.min() + 0.05 * np.ptp(x)
        threshold = max(DEAD_BAND_SIGMAS * sensor_noise(x), 1e-9)
        smooth_p = np.convolve(p, np.ones(9) / 9, mode="same")
        window = max(len(record) // 4, 1)
        for i in _turns(record):
            if x[i] <= floor or i < window // 10:
                continue
            direction = np.sign(x[i] - x[max(0, i - window // 10)])
            ahead = x[i:i + window]
            extreme = i + int(np.argmax(direction * ahead))
            moved = np.flatnonzero(direction * (x[extreme] - x[extreme:]) > threshold)
            if direction == 0 or moved.size == 0:
                continue
            j = extreme + int(moved[0])
            bands.append(abs(smooth_p[j] - smooth_p[i]))
            resolutions.append(threshold * params["k"] / params["A_d"])
    if not bands:
        return np.nan, np.nan, 0
    values = np.array(bands)
    spread = stats.t.ppf(0.975, values.size - 1) * values.std(ddof=1) / np.sqrt(values.size) \
        if values.size > 1 else 0.0
    return float(values.mean()), float(np.hypot(spread, max(resolutions))), int(values.size)


def valve_numbers(fit: SignatureFit, records: Sequence[Record], params) -> pd.DataFrame:
    """The valve engineer's numbers with 95 % intervals: bench set (vacuum at the start
    and the end of the rated travel x_max on the spring line), spring rate, friction
    band (in pressure, and as a force), dead band; SI with a display column in the
    units a valve engineer reads."""
    est = fit.estimates
    area, x_end = params["A_d"], params["x_max"]
    t = stats.t.ppf(0.975, est.dof) if est.dof > 0 else 1.96
    cov = est.covariance[:2, :2]
    f0, k = est["F0"], est["k"]

    def line(x: float) -> tuple[float, float]:
        gradient = np.array([1.0, x]) / area
        return (f0 + k * x) / area, float(t * np.sqrt(gradient @ cov @ gradient))

    start, start_hw = line(0.0)
    end, end_hw = line(x_end)
    level_hw = t * fit.level_stderr
    band, band_hw, reversals = dead_band(records, params)
    rows = [
        ("bench set: start of travel (vacuum)", start, start_hw, "Pa", 1e-3, "kPa",
         "F0/A_d: the vacuum at which the diaphragm leaves its rest stop, friction aside"),
        ("bench set: end of rated travel (vacuum)", end, end_hw, "Pa", 1e-3, "kPa",
         f"(F0 + k·x_max)/A_d at x_max = {x_end * 1e3:.4g} mm, friction aside"),
        ("spring rate", k, t * est.stderr[1], "N/m", 1e-3, "N/mm", "k"),
        ("spring rate in pressure", k / area, t * est.stderr[1] / area, "Pa/m", 1e-6,
         "kPa/mm", "k/A_d: vacuum per unit of travel"),
        ("friction band", 2 * fit.level / area, 2 * level_hw / area, "Pa", 1e-3, "kPa",
         f"separation of the branches at {fit.speed * 1e3:.3g} mm/s: 2·(Fc + σ2·|v| + "
         "Stribeck)/A_d"),
        ("friction force on the branches", fit.level, level_hw, "N", 1.0, "N",
         "half the friction band times A_d"),
        ("dead band", band, band_hw, "Pa", 1e-3, "kPa",
         f"pressure change after a reversal before the position moves ({reversals} "
         "reversal(s) read)" if reversals else "no reversal away from the end stops to read"),
    ]
    frame = pd.DataFrame(rows, columns=["quantity", "value", "ci95_half_width", "unit",
                                        "display_factor", "display_unit", "meaning"])
    frame["display"] = [
        f"{v * s:.4g} ± {h * s:.2g} {u}" if np.isfinite(v) else "not measured"
        for v, h, s, u in zip(frame["value"], frame["ci95_half_width"],
                              frame["display_factor"], frame["display_unit"], strict=True)]
    return frame.drop(columns="display_factor").set_index("quantity")


def signature_records(records: Sequence[Record], kinds: Sequence[str]) -> list[Record]:
    """The records a signature identification uses: the sweeps (``kinds`` per record)."""
    chosen = [r for r, kind in zip(records, kinds, strict=True) if kind == "sweep"]
    if not chosen:
        raise DataError("signature: no sweep among "
                        + ", ".join(Path(r.source).name for r in records)
                        + "; a signature is a slow pressure sweep up and down (name the "
                          "file sweep*)")
    return chosen
