"""The paper's four identification stages (section III.2, eqs. 9-13).

(a) spring: F0 and k (and the friction level) from the two branches of a quasi-static
    sweep, by linear least squares of (p_atm − p)·A_d − m·a = F0 + k·x + F·sgn(v);
(b) Fc and σ2 by linear least squares of eq. 13 over steady sliding fast enough that
    the Stribeck term is negligible, with an offset and a slope in x that absorb the
    errors of stage (a) (0.1 % of k is 0.13 N at 10 mm, as much as σ2·v at 30 mm/s);
(c) Fs and vs (optionally δ) by nonlinear least squares of eq. 12 over the slower steady
    segments, within Fs ≥ Fc; the uncertainty of the stage-(b) values it holds is
    propagated into its standard errors (delta method);
(d) σ0 and σ1 by output-error least squares on the presliding records, with the model
    in the loop (forward-sensitivity Jacobian), after the approach to the stop.

Eq. 13 holds only where v ≫ vs, and vs is what stage (c) finds, so (b) and (c) are
iterated (``sliding_and_stribeck``): stage (b) uses the segments at which the Stribeck
term (Fs − Fc)·exp(−(v/vs)^δ) of the current (c) is below the standard error of Fc, and
stops when that speed no longer changes. Where the records have too few such segments,
a diagnostic names the speed they need and eq. 12 is fitted over all segments at once.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from ..errors import DataError
from ..io.records import Record
from ..io.report import ResultVocabulary
from ..plotting import tight_layout
from .bench import (
    drive_force,
    kinematics,
    moving_threshold,
    smoothing_window,
    steady_segments,
)
from .diagnostics import REMEDIES, Diagnostic
from .estimates import Estimates, covariance_from_jacobian, linear_least_squares
from .optima import cover_optima, restarted, stuck_reason

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["PRESLIDING_MIN_SAMPLES", "PRIOR_FACTOR", "STAGES", "StageResult", "presliding_range",
           "presliding_window", "prior_bounds", "segments_of", "settled_part",
           "sliding_and_stribeck", "sliding_branches", "sliding_remedy", "stage_presliding",
           "stage_sliding", "stage_spring", "stage_stribeck", "within"]

STAGES = {
    "spring": "(a) spring: F0, k from the quasi-static sweep",
    "sliding": "(b) sliding friction: Fc, σ2 by eq. 13 (|v| ≫ vs)",
    "stribeck": "(c) Stribeck: Fs, vs by eq. 12 (lower velocities)",
    "presliding": "(d) presliding: σ0, σ1 by output error, model in the loop",
    "signature": "(a') signature: F0, k, Fc (σ2) from one slow up-and-down loop",
}
#: Fraction of the sweep's travel kept away from the rest stop and the turning point in
#: stage (a): the spring line is fitted where the diaphragm slides freely.
SWEEP_MARGIN = 0.02
#: Stage (a) keeps, of each branch, the samples moving at least this fraction of the
#: branch's median speed: the break-away transient at the start of a branch has
#: Stribeck friction, at small x on one branch and large x on the other, which would
#: leak into k.
SWEEP_STEADY = 0.8
#: Iterations of stages (b) and (c) before the sliding threshold must have settled.
MAX_THRESHOLD_ITERATIONS = 10
#: Fewest steady segments eq. 13 needs (in both directions together).
MIN_SLIDING_SEGMENTS = 5
#: Segments in one direction whose speeds differ by less than this share are one point
#: of eq. 13 (each ramp test's approach repeats one motion: on a drawn 213 mm actuator
#: five approaches at 10.81 mm/s and two ramps at ±16.65 mm/s were all the segments
#: above the threshold, and eq. 13's four unknowns came out Fc ×6, σ2 = −5 402 N·s/m).
DISTINCT_SPEED = 0.02
#: The presliding part of a record starts this many stuck-mode periods
#: 2π·√(m/(k + σ0)) after the approach (its ringing has decayed to a few per cent).
SETTLE_PERIODS = 5.0
#: Search bounds of the output-error fits: this factor either side of the prior value.
PRIOR_FACTOR = 10.0
#: A presliding record's "approach" is its longest run faster than this fraction of its
#: fastest motion (scale-free: whatever the actuator's speed).
APPROACH_FRACTION = 0.1
#: ... and it is over only once the position stays within this fraction of the record's
#: travel of where it rests at the end: an approach that stick-slips is a train of
#: slides, and its longest one need not be its last (issue 38: a window that began
#: inside such an approach reported 2 050 µm of presliding motion, really 45 µm).
APPROACH_SETTLED = 0.1


@dataclass(eq=False)
class StageResult(ResultVocabulary):
    """One stage: estimates, the records used, data with the fitted curve, and what the
    stage found worth saying (``diagnostics``).

    ``to_pandas()``: the estimates (``"data"``: the data and the fitted curve); ``plot()``:
    data, fit and residuals; ``write(folder)``: both tables, the figure and report.html."""

    report_title = "Identification stage"
    figure_name = "stage"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"estimates": self.estimates.to_pandas(), "data": self.data}

    def report_text(self) -> str:
        return (f"{self.title}, from {', '.join(self.records)}. "
                + " ".join(d.line() for d in self.diagnostics))

    name: str
    estimates: Estimates
    records: tuple[str, ...]
    data: pd.DataFrame  # columns x, measured, fitted (+ stage-specific)
    xlabel: str
    ylabel: str
    extra: dict = field(default_factory=dict)
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def title(self) -> str:
        return STAGES[self.name]

    def plot(self) -> Figure:
        """Data and fitted curve (top), residuals (bottom), against the stage's x."""
        import matplotlib.pyplot as plt

        if "fit" in self.extra:
            return self.extra["fit"].plot_fit()
        fig, (ax, axr) = plt.subplots(2, 1, sharex=True, figsize=(6.5, 5.5),
                                      gridspec_kw={"height_ratios": [2, 1]})
        order = np.argsort(self.data["x"].to_numpy())
        d = self.data.iloc[order]
        ax.plot(d["x"], d["measured"], "k.", ms=3, label="from the records")
        x, fitted = d["x"].to_numpy(), d["fitted"].to_numpy()
        both = (x < 0).any() and (x > 0).any()
        branches = [x < 0, x > 0] if both else [np.ones_like(x, dtype=bool)]
        for i, branch in enumerate(branches):  # a Coulomb step is not drawn through v = 0
            ax.plot(x[branch], fitted[branch], "C0-", lw=1.2,
                    label="fitted" if i == 0 else None)
        axr.plot(d["x"], d["measured"] - d["fitted"], "C3.", ms=3)
        axr.axhline(0, color="k", lw=0.6)
        ax.set_ylabel(self.ylabel)
        unit = self.ylabel[self.ylabel.rfind("["):] if self.ylabel.endswith("]") else ""
        axr.set_ylabel(f"residual {unit}".strip())
        axr.set_xlabel(self.xlabel)
        ax.set_title(self.title, fontsize=10)
        ax.legend(fontsize=8)
        for a in (ax, axr):
            a.grid(True, alpha=0.3)
        if self.name == "stribeck":
            ax.set_xscale("symlog", linthresh=1e-1)
        tight_layout(fig)
        return fig


# --------------------------------------------------------------------------- (a)
def sliding_branches(record: Record, params, fast: float = np.inf, smoothing: float = 1.0
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(position, drive force less inertia, velocity) of the samples of a sweep that
    slide freely on either branch: faster than the velocity noise allows to call
    "moving", ``SWEEP_MARGIN`` of the travel away from the rest stop and the turning
    point, and on each branch at least ``SWEEP_STEADY`` × its median speed or at least
    ``fast`` [m/s] (a speed at which the Stribeck term has died out). ``smoothing``
    lengthens the differentiation window (``bench.smoothing_window``) by that factor."""
    kin = kinematics(record, None if smoothing == 1.0 else
                     smoothing * smoothing_window(record))
    travel = float(np.ptp(kin.position))
    margin = SWEEP_MARGIN * travel
    moving = (np.abs(kin.velocity) > moving_threshold(kin, record)) & \
        (kin.position > kin.position.min() + margin) & \
        (kin.position < kin.position.max() - margin)
    speed = np.abs(kin.velocity)
    keep = np.zeros_like(moving)
    for sign in (1, -1):
        branch = moving & (np.sign(kin.velocity) == sign)
        if branch.any():
            keep |= branch & ((speed >= SWEEP_STEADY * np.median(speed[branch]))
                              | (speed >= fast))
    force = drive_force(kin.pressure, params) - params["m"] * kin.acceleration
    return kin.position[keep], force[keep], kin.velocity[keep]


def stage_spring(sweeps: Sequence[Record], params) -> StageResult:
    """(a): F0, k and the friction level from the moving parts of quasi-static sweeps:
    faster than the velocity noise allows to call "moving", ``SWEEP_MARGIN`` of the
    travel away from the rest stop and the turning point, and on each branch at least
    ``SWEEP_STEADY`` × its median speed."""
    parts = [sliding_branches(rec, params) for rec in sweeps]
    x, f, s = (np.concatenate([part[i] for part in parts]) for i in range(3))
    s = np.sign(s)
    if not (np.any(s > 0) and np.any(s < 0)):
        raise DataError("stage (a): the sweep records need both branches (increasing and "
                        "decreasing position) off the rest stop")
    est, res, _ = linear_least_squares(np.column_stack([np.ones_like(x), x, s]), f,
                                       ["F0", "k", "friction_level"], ["N", "N/m", "N"],
                                       "stage (a) spring", correlated=True)
    data = pd.DataFrame({"x": x * 1e3, "measured": f, "fitted": f - res, "branch": s})
    return StageResult("spring", est, tuple(os.path.basename(r.source) for r in sweeps), data,
                       "position [mm]", "drive force (p_atm − p)·A_d − m·a [N]")


# --------------------------------------------------------------------------- (b), (c)
def presliding_range(params) -> float:
    """How far a bristle deflects before gross sliding, 3·Fs/σ0 [m] (LuGre's presliding
    creep runs to about three times the static deflection Fs/σ0)."""
    return 3.0 * params["Fs"] / params["sigma0"]


def segments_of(records: Sequence[Record], params, presliding: float) -> pd.DataFrame:
    """Steady sliding segments of all ``records`` (``bench.steady_segments``)."""
    frames = [steady_segments(r, params, presliding_range=presliding) for r in records]
    frames = [f for f in frames if len(f)]
    if not frames:
        raise DataError("stages (b, c): no steady sliding segment found in the records; "
                        "ramps need a steady part of several differentiation windows")
    return pd.concat(frames, ignore_index=True)


def stage_sliding(segments: pd.DataFrame, sliding_speed: float) -> StageResult:
    """(b): Fc, σ2 (and an offset) from eq. 13 over |v| ≥ ``sliding_speed``."""
    fast = segments[np.abs(segments["velocity"]) >= sliding_speed]
    v, f = fast["velocity"].to_numpy(), fast["friction"].to_numpy()
    x = fast["position"].to_numpy()
    if np.sum(v > 0) < 1 or np.sum(v < 0) < 1 or len(v) < MIN_SLIDING_SEGMENTS:
        raise DataError(f"stage (b): {len(v)} steady segments at |v| >= "
                        f"{sliding_speed * 1e3:.3g} mm/s; need at least "
                        f"{MIN_SLIDING_SEGMENTS}, in both directions")
    design = np.column_stack([np.sign(v), v, np.ones_like(v), x])
    est, res, _ = linear_least_squares(design, f, ["Fc", "sigma2", "offset", "spring_error"],
                                       ["N", "N*s/m", "N", "N/m"], "stage (b) eq. 13")
    data = pd.DataFrame({"x": v * 1e3, "measured": f, "fitted": f - res,
                         "record": fast["record"].to_numpy()})
    return StageResult("sliding", est, tuple(dict.fromkeys(fast["record"])), data,
                       "velocity [mm/s]", "friction force [N]",
                       extra={"sliding_speed": sliding_speed})


def stage_stribeck(segments: pd.DataFrame, sliding: StageResult, params,
                   sliding_speed: float, fit_delta: bool = False) -> StageResult:
    """(c): Fs, vs (and δ) by nonlinear least squares of eq. 12 below ``sliding_speed``,
    with Fc, σ2 and the offset of stage (b) held."""
    slow = segments[np.abs(segments["velocity"]) < sliding_speed]
    v, f = slow["velocity"].to_numpy(), slow["friction"].to_numpy()
    fc, s2, off, dk = (sliding.estimates[n] for n in ("Fc", "sigma2", "offset",
                                                      "spring_error"))
    x = slow["position"].to_numpy()
    n_par = 3 if fit_delta else 2
    if len(v) <= n_par + 1:
        raise DataError(f"stage (c): {len(v)} steady segments below "
                        f"{sliding_speed * 1e3:.3g} mm/s; need at least {n_par + 2}")
    y = np.sign(v) * (f - s2 * v - off - dk * x)  # = g(|v|)
    speed = np.abs(v)

    def model(q):
        fs, vs = q[0], np.exp(q[1])
        delta = q[2] if fit_delta else params["delta"]
        return fc + (fs - fc) * np.exp(-((speed / vs) ** delta))

    # Fs ≥ Fc (Fc + (Fs − Fc)·e^… ≥ Fc), vs within 1 µm/s … 1 m/s, δ within 0.3 … 5
    lower = [fc, np.log(1e-6)] + ([0.3] if fit_delta else [])
    upper = [10 * max(fc, y.max()), 0.0] + ([5.0] if fit_delta else [])

    def solve(vs0: float):
        q0 = [max(params["Fs"], y.max()), np.log(vs0)] + ([params["delta"]]
                                                          if fit_delta else [])
        q0 = np.clip(q0, np.nextafter(lower, np.inf), np.nextafter(upper, -np.inf))
        return least_squares(lambda q: model(q) - y, q0, bounds=(lower, upper),
                             x_scale="jac")

    def stuck(solution) -> bool:
        return bool(np.any(np.isclose(solution.x, lower, rtol=0, atol=1e-9)) or
                    np.any(np.isclose(solution.x, upper, rtol=0, atol=1e-9)))

    # from the prior's vs and from spread starts: the best optimum inside the bounds,
    # else the best there is (a prior's vs 100 times too low stopped at 1-2 % of the
    # true vs; issue 38: one start ended at vs = 1 m/s, and the remedy asked an 8 mm
    # stroke for ramps at metres per second)
    tries = [solve(params["vs"] * f) for f in (1.0, *STRIBECK_RESTARTS)]
    inside = [t for t in tries if not stuck(t)]
    sol = min(inside or tries, key=lambda t: t.cost)
    jac = sol.jac.copy()
    values = _stribeck_values(sol.x)
    jac[:, 1] /= values[1]  # back from log vs to vs
    cov, dof = covariance_from_jacobian(jac, sol.fun, n_par, correlated=False)
    # the estimates of stage (b) are held here: add their uncertainty (delta method)
    sign = np.sign(v)
    decay = np.exp(-((speed / values[1]) ** (values[2] if fit_delta else params["delta"])))
    held = np.column_stack([1 - decay, speed, sign, sign * x])  # ∂r/∂(Fc, σ2, offset, dk)
    b_idx = [sliding.estimates.names.index(n)
             for n in ("Fc", "sigma2", "offset", "spring_error")]
    cov_b = sliding.estimates.covariance[np.ix_(b_idx, b_idx)]
    gain = -np.linalg.pinv(jac) @ held  # ∂θ_c/∂θ_b at the optimum
    cov = cov + gain @ cov_b @ gain.T
    names = ["Fs", "vs"] + (["delta"] if fit_delta else [])
    cov, widened = _covering_optima(cov, values, sol, [t for t in inside if t is not sol], dof)
    est = Estimates(tuple(names), values, np.sqrt(np.diag(cov)), cov, dof,
                    ("N", "m/s", "")[:n_par])
    fitted = np.sign(v) * model(sol.x) + s2 * v + off + dk * x
    data = pd.DataFrame({"x": v * 1e3, "measured": f, "fitted": fitted,
                         "record": slow["record"].to_numpy()})
    at_bound = stuck(sol)
    stuck_at = np.isclose(sol.x, lower, rtol=0, atol=1e-9) | \
        np.isclose(sol.x, upper, rtol=0, atol=1e-9)
    reason = stuck_reason(names, values, stuck_at, len(tries)) if at_bound else ""
    optima = ", ".join(n for n, w in zip(names, widened, strict=True) if w)
    return StageResult("stribeck", est, tuple(dict.fromkeys(slow["record"])), data,
                       "velocity [mm/s]", "friction force [N]",
                       extra={"at_bound": at_bound, "stuck": reason, "optima": optima})


def _stribeck_values(q: np.ndarray) -> np.ndarray:
    """Stage (c)'s solution (Fs, log vs[, δ]) as (Fs, vs[, δ])."""
    values = np.array(q, dtype=float)
    values[1] = np.exp(values[1])
    return values


def _covering_optima(cov: np.ndarray, values: np.ndarray, best, others: list, dof: int
                     ) -> tuple[np.ndarray, np.ndarray]:
    """``cov`` widened to cover every other optimum of stage (c) within the noise
    (``optima.cover_optima``; the noise variance is the best fit's residual variance)."""
    variance = float(best.fun @ best.fun) / max(dof, 1)
    return cover_optima(cov, values, best.cost,
                        [(_stribeck_values(t.x), t.cost) for t in others], variance)


#: Stage (c) starts from the prior's vs and from these multiples of it (eq. 12 in vs
#: has local optima: a tenth of the data's range of speeds away, a start can stop there).
STRIBECK_RESTARTS = (1 / 30, 1 / 10, 1 / 3, 3.0, 10.0, 30.0)


def sliding_remedy(needed: float, params) -> str:
    """The test that would let eq. 13 hold: ramps from ``needed`` [m/s] to three times
    it, when the regulator can drive them (``campaign.regulator_reach``); else no
    speed is asked for (a remedy from a speed the bench cannot reach is no remedy), and
    the test that would tell is named instead."""
    from .campaign import regulator_reach

    reach = regulator_reach(params)
    if needed <= reach:
        return (f"add ramps at {needed * 1e3:.3g} to {min(3 * needed, reach) * 1e3:.3g} "
                "mm/s in both directions; meanwhile eq. 13 is used where it holds least "
                "badly and the joint refinement fits eq. 12 whole")
    return (f"ramps at {needed * 1e3:.3g} mm/s are beyond what the regulator drives "
            f"(about {reach * 1e3:.3g} mm/s), so no ramp speed is proposed from this vs: "
            "ramps at many steady speeds between vs/3 and 3·vs of the prior, which tell "
            "vs itself, would tell where eq. 13 holds; the joint refinement fits eq. 12 "
            "whole")


def _stribeck_remedy(params) -> str:
    """Ramps around the prior's vs (never around a vs stuck at a bound), as far as the
    regulator drives them."""
    from .campaign import regulator_reach

    vs, reach = params["vs"], regulator_reach(params)
    if vs / 3 >= reach:
        return (f"the prior's vs/3 = {vs / 3 * 1e3:.3g} mm/s is beyond what the regulator "
                f"drives (about {reach * 1e3:.3g} mm/s): " + REMEDIES["vs"] + ", with a "
                "faster regulator")
    return (f"add ramps around the prior's vs, from {vs / 3 * 1e3:.3g} to "
            f"{min(3 * vs, reach) * 1e3:.3g} mm/s (not from the stuck estimate)")


def _needed_speed(sliding: StageResult, stribeck: StageResult, delta: float) -> float:
    """Slowest speed at which the Stribeck term (Fs − Fc)·exp(−(v/vs)^δ) is below the
    standard error of Fc: there eq. 13 biases Fc by less than its own uncertainty."""
    fc_se = sliding.estimates.stderr[sliding.estimates.names.index("Fc")]
    amplitude = stribeck.estimates["Fs"] - sliding.estimates["Fc"]
    vs = stribeck.estimates["vs"]
    if "delta" in stribeck.estimates.names:
        delta = stribeck.estimates["delta"]
    if not (fc_se > 0 and amplitude > fc_se):
        return 0.0
    return float(vs * np.log(amplitude / fc_se) ** (1.0 / delta))


def distinct_threshold(segments: pd.DataFrame) -> float:
    """The highest sliding threshold [m/s] at which the segments at or above it give eq.
    13 ``MIN_SLIDING_SEGMENTS`` distinct points, two in each direction at least (speeds
    within ``DISTINCT_SPEED`` of each other in one direction are one point); 0 where
    the segments never do."""
    velocity = segments["velocity"].to_numpy()
    points: list[tuple[float, float]] = []
    for v in velocity[np.argsort(-np.abs(velocity))]:
        if not any(np.sign(v) == sign and abs(abs(v) / speed - 1) < DISTINCT_SPEED
                   for sign, speed in points):
            points.append((float(np.sign(v)), abs(float(v))))
        signs = [sign for sign, _ in points]
        if len(points) >= MIN_SLIDING_SEGMENTS and signs.count(1.0) >= 2 and \
                signs.count(-1.0) >= 2:
            return abs(float(v)) * (1 - DISTINCT_SPEED)
    return 0.0


def sliding_and_stribeck(segments: pd.DataFrame, params, fit_delta: bool = False,
                         sliding_speed: float | None = None
                         ) -> tuple[StageResult | None, StageResult | None, list[Diagnostic]]:
    """Stages (b) and (c), iterated until the slowest segment of (b) is fast enough for
    the vs of (c) (see the module docstring); ``sliding_speed`` fixes the threshold
    instead, and is then only checked. Returns (sliding, stribeck, diagnostics); a stage
    the segments cannot support is None, with a diagnostic that says why and what test
    would help (the joint refinement then starts from the prior's values)."""
    from .campaign import regulator_reach

    speeds = np.sort(np.abs(segments["velocity"].to_numpy()))
    min_slow = (3 if fit_delta else 2) + 2
    distinct = distinct_threshold(segments) or np.inf
    notes: list[Diagnostic] = []
    if sliding_speed is None:
        if speeds.size < MIN_SLIDING_SEGMENTS + min_slow:
            notes.append(Diagnostic(
                "warning", "(b, c)", f"{speeds.size} steady sliding segments in the "
                f"records; eqs. 13 and 12 need at least {MIN_SLIDING_SEGMENTS + min_slow}",
                "add ramps at more steady speeds (the diaphragm may stick-slip on the "
                "slower ones: steady sliding needs σ2 + g'(v) > 0)"))
            return None, None, notes
        threshold = float(speeds[-MIN_SLIDING_SEGMENTS:].min()) if \
            speeds.size < 2 * MIN_SLIDING_SEGMENTS else float(np.median(speeds))
        threshold = min(max(threshold, float(speeds[min_slow])), distinct)
    else:
        threshold = sliding_speed
    sliding = stribeck = None
    for _ in range(MAX_THRESHOLD_ITERATIONS):
        try:
            new_sliding = stage_sliding(segments, threshold)
            new_stribeck = stage_stribeck(segments, new_sliding, params, threshold, fit_delta)
        except DataError as exc:
            notes.append(Diagnostic("warning", "(b, c)", str(exc)))
            break
        sliding, stribeck = new_sliding, new_stribeck
        if stribeck.extra.get("at_bound"):
            break  # a vs at its bound sets no threshold and no remedy (see below)
        needed = _needed_speed(sliding, stribeck, params["delta"])
        if sliding_speed is not None:
            if needed > threshold:
                notes.append(Diagnostic(
                    "warning", "(b)", f"the given sliding speed {threshold * 1e3:.3g} mm/s "
                    f"is not well above vs = {stribeck.estimates['vs'] * 1e3:.3g} mm/s: the "
                    f"Stribeck term there exceeds the Fc standard error, which biases Fc "
                    f"and σ2", f"use at least {needed * 1e3:.3g} mm/s, or leave the sliding "
                    "speed to the procedure" if needed <= regulator_reach(params) else
                    "leave the sliding speed to the procedure (the speed this vs asks "
                    f"for, {needed * 1e3:.3g} mm/s, is beyond what the regulator drives)"))
            break
        above = speeds[speeds >= needed]
        if above.size < MIN_SLIDING_SEGMENTS:
            notes.append(Diagnostic(
                "warning", "(b)", f"eq. 13 needs steady sliding at |v| ≥ "
                f"{needed * 1e3:.3g} mm/s (where the Stribeck term of vs = "
                f"{stribeck.estimates['vs'] * 1e3:.3g} mm/s is below the Fc standard "
                f"error); the records have {above.size} such segments "
                f"(need {MIN_SLIDING_SEGMENTS})", sliding_remedy(needed, params)))
            break
        new = min(float(max(above[0], speeds[min(min_slow, speeds.size - 1)])), distinct)
        if new == threshold:
            notes.append(Diagnostic(
                "note", "(b)", f"eq. 13 on {np.sum(speeds >= threshold)} segments at |v| ≥ "
                f"{threshold * 1e3:.3g} mm/s, where the Stribeck term is below the Fc "
                f"standard error (vs = {stribeck.estimates['vs'] * 1e3:.3g} mm/s)"))
            break
        threshold = new
    else:
        notes.append(Diagnostic("warning", "(b, c)", "the sliding threshold did not settle "
                                f"in {MAX_THRESHOLD_ITERATIONS} iterations"))
    if stribeck is not None and stribeck.extra.get("optima"):
        notes.append(Diagnostic(
            "warning", "(c)", f"eq. 12 has more than one optimum within the noise for "
            f"{stribeck.extra['optima']}: the interval covers them all",
            REMEDIES["vs"]))
    if stribeck is not None and stribeck.extra.get("at_bound"):
        notes.append(Diagnostic("warning", "(c)", f"{stribeck.extra['stuck']}: the slow "
                                "segments do not show the Stribeck dip",
                                _stribeck_remedy(params)))
    return sliding, stribeck, notes


# --------------------------------------------------------------------------- (d)
def stuck_period(params) -> float:
    """Period 2π·√(m/(k + σ0)) [s] of the stuck (presliding) mode."""
    return float(2 * np.pi * np.sqrt(params["m"] / (params["k"] + params["sigma0"])))


def presliding_window(record: Record, params) -> float:
    """Start [s] of the presliding part of ``record``: ``SETTLE_PERIODS`` stuck-mode
    periods after its approach (its longest run faster than ``APPROACH_FRACTION`` of
    its fastest motion, and not before the position settles within ``APPROACH_SETTLED``
    of the travel of where it ends)."""
    kin = kinematics(record)
    speed = np.abs(kin.velocity)
    moving = speed > APPROACH_FRACTION * speed.max()
    edges = np.flatnonzero(np.diff(np.concatenate([[0], moving.astype(np.int8), [0]])))
    if edges.size == 0:
        return float(record.time[0])
    runs = list(zip(edges[::2], edges[1::2], strict=True))
    _i0, i1 = max(runs, key=lambda r: r[1] - r[0])
    x = kin.measured_position
    rest = float(np.median(x[-max(1, x.size // 10):]))
    away = np.flatnonzero(np.abs(x - rest) > APPROACH_SETTLED * np.ptp(x))
    if away.size:
        i1 = max(i1, int(away[-1]) + 1)
    return float(kin.time[min(i1, kin.time.size - 1)] + SETTLE_PERIODS * stuck_period(params))


#: A presliding record is fitted from its settled part on only where that part holds at
#: least this many samples (a record that ends within ``SETTLE_PERIODS`` stuck periods of
#: its approach has none: the drawn bench's family-7-26 crashed the procedure)
PRESLIDING_MIN_SAMPLES = 10


def settled_part(record: Record, params) -> tuple[float, float] | None:
    """(start, end) [s] of ``record``'s presliding part (``presliding_window`` to its
    end), or None where it holds fewer than ``PRESLIDING_MIN_SAMPLES`` samples."""
    start = presliding_window(record, params)
    if np.count_nonzero(record.time >= start) < PRESLIDING_MIN_SAMPLES:
        return None
    return start, float(record.time[-1])


def prior_bounds(prior, names: Sequence[str]) -> dict[str, tuple[float, float]]:
    """Search bounds of each parameter: ``PRIOR_FACTOR`` either side of its prior value
    (a guess off by more than that is not a prior; a fit that wanders there meets a
    model so stiff or so light that every simulation crawls)."""
    return {n: (prior[n] / PRIOR_FACTOR, prior[n] * PRIOR_FACTOR) for n in names}


def within(values: dict[str, float], bounds: dict[str, tuple[float, float]]
           ) -> dict[str, float]:
    """``values`` clipped into ``bounds`` (those that have bounds)."""
    return {n: float(np.clip(v, *bounds[n])) if n in bounds else v
            for n, v in values.items()}


def stage_presliding(records: Sequence[Record], params, friction=None, solver=None,
                     prior=None) -> StageResult:
    """(d): σ0, σ1 by output error on the presliding part of each record (a sensor
    offset per record is fitted too: the stuck position remembers the approach), within
    ``prior_bounds`` of ``prior`` (default ``params``)."""
    from ..models import Actuator, LuGre, PressureSource
    from .fit import fit

    free = ["sigma0", "sigma1"]
    bounds = prior_bounds(params if prior is None else prior, free)
    start = within({n: params[n] for n in free}, bounds)
    model = Actuator(params, friction=friction or LuGre(), valve=PressureSource())
    parts = [settled_part(r, params) for r in records]
    short = [Path(r.source).name for r, part in zip(records, parts, strict=True) if part is None]
    if short:
        raise DataError(
            f"{', '.join(short)}: the record ends within {SETTLE_PERIODS:g} stuck-mode "
            f"periods ({SETTLE_PERIODS * stuck_period(params) * 1e3:.3g} ms at the current "
            "σ0 and m) of its approach, so no settled presliding part is left to fit; hold "
            "each step longer after the approach")
    windows = [part for part in parts if part is not None]

    def solve(values: np.ndarray):
        return fit(model, records, free, offsets=["position"], window=windows,
                   solver=solver, bounds=bounds,
                   start=within(dict(zip(free, map(float, values), strict=True)), bounds))

    def values_of(result) -> np.ndarray:
        return np.array([result.values[n] for n in free])

    def stuck_of(result) -> np.ndarray:
        low, high = (np.array([bounds[n][side] for n in free]) for side in (0, 1))
        values = values_of(result)
        return np.isclose(values, low, rtol=1e-6) | np.isclose(values, high, rtol=1e-6)

    prior_values = np.array([(params if prior is None else prior)[n] for n in free])
    tries = restarted(solve, np.array([start[n] for n in free]), prior_values, free,
                      stuck_of, lambda r: float(r.cost), values_of)
    result = tries.best
    keep = [n in ("sigma0", "sigma1") for n in result.estimates.names]
    est = result.estimates
    idx = np.flatnonzero(keep)
    sub = Estimates(tuple(est.names[i] for i in idx), est.values[idx], est.stderr[idx],
                    est.covariance[np.ix_(idx, idx)], est.dof,
                    tuple(est.units[i] for i in idx))
    rec, sim = records[0], result.simulated[0]
    data = pd.DataFrame({"x": rec.time, "measured": rec["position"] * 1e3,
                         "fitted": sim["position"] * 1e3})
    return StageResult("presliding", sub, tuple(os.path.basename(r.source) for r in records), data,
                       "time [s]", "position [mm]",
                       {"fit": result, "stuck": tries.reason, "starts": len(tries.solutions)})
