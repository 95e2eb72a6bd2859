"""How sure an identification is: diagnostics, residual checks and a verdict per parameter.

A wrong number with a tight interval is the worst thing an identification can print, so
every estimate gets a verdict:

- ``identified``: its 95 % interval is narrower than ±``IDENTIFIED_HALF_WIDTH`` of its
  value (σ0, σ1: ``PRESLIDING_HALF_WIDTH``), it is not at a bound, and the model fits
  every record;
- ``poorly identified``: the interval is finite but wider (up to
  ±``POORLY_HALF_WIDTH``), or the model does not fit a record (then no interval holds);
- ``not identifiable``: the interval is wider still or infinite (the records do not
  excite the parameter: a rank-deficient Jacobian), or the estimate ended at a bound.

Each verdict carries its reason and the test that would fix it (``REMEDIES``). A
``Diagnostic`` is one finding of a stage or of the joint fit (a threshold that could not
be met, too few segments, a record the model does not fit), with its severity.

A model fits a record when the RMS of its residual is at most ``MISFIT_RATIO`` times the
sensor noise the record itself shows (``inputs.sensor_noise``) and the residual has no
structure beyond noise (``MISFIT_STRUCTURE``, ``residual_checks``). Measured on campaigns
made by the identified model itself, the RMS ratio is 0.85-0.9 and the structure
0.6-1.4; see the tests of model mismatch for what a sensor lag, an adiabatic chamber
identified as isothermal or friction of another law give.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .inputs import sensor_noise

__all__ = [
    "IDENTIFIED_HALF_WIDTH",
    "MISFIT_INFORMATION",
    "MISFIT_RATIO",
    "MISFIT_REFIT_SHARE",
    "MISFIT_REMEDY",
    "MISFIT_SHIFT",
    "MISFIT_STRUCTURE",
    "MODEL_FIDELITY",
    "POORLY_HALF_WIDTH",
    "PRESLIDING_HALF_WIDTH",
    "REMEDIES",
    "SMOOTHING_SAMPLES",
    "Diagnostic",
    "Verdict",
    "misfit_influence",
    "named_list",
    "residual_checks",
    "verdicts",
]

#: A 95 % interval within ±2.5 % of the value (σ0 and σ1, which act through micrometres of
#: deflection only: ±7.5 %): the records pin the parameter down, and an identified value
#: is within 5 % (15 %) of the truth even at four standard errors.
IDENTIFIED_HALF_WIDTH = 0.025
PRESLIDING_HALF_WIDTH = 0.075
#: No estimate is reported more precise than this fraction of its value: below it the
#: integration error, the end stops' penalty contact and the rebuilt inputs set the
#: limit, not the noise (measured: systematic errors up to 35 ppm of k on drawn
#: actuators whose noise alone allowed 3 ppm), and no bench holds a spring constant to
#: better than that from one day to the next anyway.
MODEL_FIDELITY = 1e-4
#: Beyond ±50 % the records say little more than the order of magnitude.
POORLY_HALF_WIDTH = 0.50
#: Residual RMS above this many sensor-noise standard deviations: the model misses
#: something the records show (see the module docstring for the measured ratios).
MISFIT_RATIO = 2.0
#: The residual averaged over this many samples ...
SMOOTHING_SAMPLES = 50
#: ... may exceed what noise alone leaves after that average by at most this factor:
#: white noise averages down by √50 ≈ 7, a misfit (a wrong local optimum, a law that
#: misses a feature) does not. Measured on drawn actuators: 0.3-1.4 on records that slide
#: steadily, up to 3.5 on slow ramps that stick-slip at estimates within 0.5 % of the
#: truth, 9-20 on the slow ramps of fits stuck in a local optimum.
MISFIT_STRUCTURE = 4.0

IDENTIFIED = "identified"
POORLY = "poorly identified"
NOT_IDENTIFIABLE = "not identifiable"

#: What test pins each parameter down (the campaign designer makes them).
REMEDIES = {
    "F0": "a quasi-static sweep that leaves the rest stop in both directions",
    "k": "a quasi-static sweep over most of the stroke",
    "Fc": "ramps at steady speeds well above vs, in both directions",
    "sigma2": "ramps at several speeds well above vs (the viscous slope needs a speed "
              "range, not one speed)",
    "Fs": "ramps at steady speeds around vs and below, in both directions",
    "vs": "ramps at steady speeds from about vs/3 to 3·vs",
    "delta": "ramps at many steady speeds across the Stribeck dip (vs/3 to 3·vs)",
    "sigma0": "a presliding test: small fast pressure steps below break-away after a stop",
    "sigma1": "a presliding test with steps fast enough to ring the stuck mode",
}


#: What to do when the model does not fit a record (then no parameter is trusted).
MISFIT_REMEDY = ("find what the model misses in the records the diagnostics name (a "
                 "sensor lag or offset, another friction law, the chamber's "
                 "thermodynamics) and compare the residual plots")


#: A parameter is still judged by its interval when the model does not fit some records
#: if the records that fit carry at least this share of what the records tell about it
#: (its column of the Jacobian) ...
MISFIT_INFORMATION = 0.5
#: ... and leaving the records it does not fit out (one Gauss-Newton step from the
#: joint optimum) moves it by at most this many of its standard errors; that move is
#: added to its variance.
MISFIT_SHIFT = 1.0
#: Where at most this share of the records misfit, the move is measured by fitting again
#: without them (``joint.refit_without``), not by one linear step; beyond it only where
#: the model misses the slow end of the campaign alone (``paper._slow_end_only``).
MISFIT_REFIT_SHARE = 0.25


@dataclass(frozen=True)
class Diagnostic:
    """One finding: ``severity`` is ``error`` (the result cannot be trusted), ``warning``
    (it holds with a caveat) or ``note``; ``stage`` says where; ``remedy`` what to do."""

    severity: str
    stage: str
    message: str
    remedy: str = ""

    def line(self) -> str:
        tail = f" ({self.remedy})" if self.remedy else ""
        return f"{self.severity}: {self.stage}: {self.message}{tail}"


@dataclass(frozen=True)
class Verdict:
    """The verdict on one parameter, why, and what would make it identifiable."""

    parameter: str
    verdict: str
    reason: str
    remedy: str = ""

    @property
    def identified(self) -> bool:
        return self.verdict == IDENTIFIED


def _moving_average(values: np.ndarray, width: int) -> np.ndarray:
    width = max(1, min(width, values.shape[-1]))
    kernel = np.ones(width) / width
    if values.ndim == 1:
        return np.convolve(values, kernel, mode="valid")
    return np.array([np.convolve(v, kernel, mode="valid") for v in values])


def named_list(names: Sequence[str], shown: int = 3) -> str:
    """'a, b, c and 4 more': a list of record names a line can hold."""
    if len(names) <= shown + 1:
        return ", ".join(names)
    return f"{', '.join(names[:shown])} and {len(names) - shown} more"


def residual_checks(fit, input_moves: dict | None = None, signal: str = "position"
                    ) -> pd.DataFrame:
    """Per record of ``fit`` (a ``FitResult``): the residual's RMS and the sensor noise
    the record itself shows (``ratio``), the RMS of the residual averaged over
    ``SMOOTHING_SAMPLES`` against what noise alone leaves after that average
    (``structure``: white noise shrinks by √n, what the noise on a measured input adds,
    ``input_moves`` from ``uncertainty.input_replicates``, does not), the lag-1
    autocorrelation, and whether the model fits (``ratio`` ≤ ``MISFIT_RATIO`` and
    ``structure`` ≤ ``MISFIT_STRUCTURE``)."""
    rows = []
    width = SMOOTHING_SAMPLES
    for i, (record, mask) in enumerate(zip(fit.records, fit.masks(), strict=True)):
        residual = fit.fitted(i, signal)[mask] - record[signal][mask]
        noise = sensor_noise(record[signal])
        rms = float(np.sqrt(np.mean(residual**2)))
        smooth = float(np.sqrt(np.mean(_moving_average(residual, width) ** 2)))
        moved = (input_moves or {}).get(i)
        input_part = 0.0 if moved is None else \
            float(np.sqrt(np.mean(_moving_average(moved, width) ** 2)))
        expected = np.hypot(noise / np.sqrt(min(width, residual.size)), input_part)
        centred = residual - residual.mean()
        denominator = float(centred @ centred)
        lag1 = float(centred[1:] @ centred[:-1] / denominator) if denominator > 0 else 0.0
        ratio = rms / np.hypot(noise, input_part) if noise > 0 else np.inf
        structure = smooth / expected if expected > 0 else np.inf
        rows.append({"record": Path(record.source).name, "signal": signal, "residual_rms": rms,
                     "sensor_noise": noise, "ratio": ratio, "structure": structure,
                     "lag1_autocorrelation": lag1,
                     "fits": bool(ratio <= MISFIT_RATIO and structure <= MISFIT_STRUCTURE)})
    return pd.DataFrame(rows)


def verdicts(names: Sequence[str], values: np.ndarray, half_widths: np.ndarray,
             at_bound: Sequence[bool], caveat: str = "") -> list[Verdict]:
    """A ``Verdict`` per parameter from its estimate, the half-width of its 95 %
    interval and whether it ended at a bound; a ``caveat`` (the model does not fit a
    record, the joint fit could not run) makes every otherwise identified parameter
    poorly identified, for that reason."""
    out = []
    for name, value, half, bound in zip(names, values, half_widths, at_bound, strict=True):
        remedy = REMEDIES.get(name, "")
        relative = abs(half / value) if value != 0 else np.inf
        identified = PRESLIDING_HALF_WIDTH if name in ("sigma0", "sigma1") else \
            IDENTIFIED_HALF_WIDTH
        if bound:
            out.append(Verdict(name, NOT_IDENTIFIABLE, "the estimate ended at a bound of its "
                               "search range", remedy))
        elif not np.isfinite(relative):
            out.append(Verdict(name, NOT_IDENTIFIABLE, "the records do not excite it (its "
                               "column of the Jacobian depends on the others)", remedy))
        elif relative > POORLY_HALF_WIDTH:
            out.append(Verdict(name, NOT_IDENTIFIABLE, f"95 % interval ±{100 * relative:.0f} %"
                               " of the value", remedy))
        elif caveat:
            out.append(Verdict(name, POORLY, caveat, MISFIT_REMEDY))
        elif relative > identified:
            out.append(Verdict(name, POORLY, f"95 % interval ±{100 * relative:.0f} % of the "
                               "value", remedy))
        else:
            out.append(Verdict(name, IDENTIFIED, f"95 % interval ±{100 * relative:.2g} % of "
                               "the value"))
    return out


def misfit_influence(fit, fits: Sequence[bool], stderr: np.ndarray, refit=None
                     ) -> tuple[dict[str, str], dict[str, float]]:
    """What the records the model does not fit (``fits`` False, one per record of the
    ``FitResult``) do to each estimate: (name -> why it is refused, for the estimates
    that rest on those records or that leaving them out moves by more than
    ``MISFIT_SHIFT`` standard errors (``stderr``, per estimate); name -> that move, for
    the others). A stage that fails thus refuses its own parameters and those that
    depend on it, not the others.

    The move is one Gauss-Newton step from the joint optimum, or, given ``refit`` (the
    fit again without those records, ``joint.refit_without``), the refit's values less
    the joint's, judged against the larger of the two standard errors; a record near a
    stick-slip boundary has a Jacobian so large that the step says it carries everything
    while the refit moves nothing (measured on a drawn actuator: the step said 100 % and
    4.1 standard errors, the refit moved every estimate by less than two)."""
    names = [Path(r.source).name for r, ok in zip(fit.records, fits, strict=True) if not ok]
    if refit is not None:
        share, move, scale_se = _refitted_move(fit, refit, stderr)
    else:
        share, move = _stepped_move(fit, fits)
        scale_se = np.asarray(stderr, dtype=float)
    refused, moves = {}, {}
    shown = ", ".join(names)
    for j, name in enumerate(fit.estimates.names):
        if "[" in name:
            continue
        z = abs(move[j]) / scale_se[j] if scale_se[j] > 0 else np.inf
        if share[j] < MISFIT_INFORMATION:
            refused[name] = (f"it rests on {shown} ({100 * (1 - share[j]):.0f} % of what the "
                             "records tell about it), which the model does not fit")
        elif not z <= MISFIT_SHIFT:
            refused[name] = (f"the model does not fit {shown}, and leaving it out moves "
                             f"{name} by {z:.2g} standard errors")
        else:
            moves[name] = float(move[j])
    return refused, moves


def _stepped_move(fit, fits: Sequence[bool]) -> tuple[np.ndarray, np.ndarray]:
    """(the share of each estimate's Jacobian column the fitting records carry, the move
    of one Gauss-Newton step without the others)."""
    sizes = [int(m.sum()) * len(fit.signals) for m in fit.masks()]
    bad = np.concatenate([np.full(n, not ok) for n, ok in zip(sizes, fits, strict=True)])
    jac = np.asarray(fit.jacobian, dtype=float)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    kept, left = jac[~bad] / scale, jac[bad] / scale
    share = np.sum(kept**2, axis=0)  # the columns are unit vectors over all records
    # the kept records' gradient at the joint optimum is minus the left-out ones'
    move = np.linalg.lstsq(kept.T @ kept, left.T @ fit.residuals[bad], rcond=None)[0]
    return share, move / scale


def _refitted_move(fit, refit, stderr: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(1 where the refit determines the estimate (a finite standard error) else 0, the
    refit's value less the joint's, the larger standard error of the two), per estimate
    of ``fit`` (0, 0, 1 for the per-record offsets)."""
    n = len(fit.estimates.names)
    share, move, scale_se = np.zeros(n), np.zeros(n), np.ones(n)
    for j, name in enumerate(fit.estimates.names):
        if "[" in name or name not in refit.estimates.names:
            continue
        k = refit.estimates.names.index(name)
        se = float(refit.estimates.stderr[k])
        share[j] = 1.0 if np.isfinite(se) and refit.success else 0.0
        move[j] = float(refit.estimates.values[k] - fit.estimates.values[j])
        scale_se[j] = max(float(stderr[j]), se) if np.isfinite(se) else float(stderr[j])
    return share, move, scale_se
