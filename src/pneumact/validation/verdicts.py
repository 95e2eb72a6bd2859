"""Verdicts that fit % alone cannot fool: a model is adequate for a record only if it
follows the time series *and* reproduces the hysteresis loop, and its residuals say
whether structure was left behind.

Fit % (100·(1 − NRMSE)) is dominated by the large, slow part of a signal: a model whose
loop is half as wide still follows the 18 mm stroke and scores above 95 %. The checks,
per record:

* fit % of every compared signal ≥ ``min_fit_percent``;
* loop width in pressure and in position within ``loop_width`` (relative), loop area
  within ``loop_area`` (relative) of the measured ones;
* break-away pressure within ``breakaway`` × the measured loop width in pressure;
* positions at the pressure reversals within ``reversal`` × the measured loop width in
  position;
* residual whiteness: at most ``max_lags_outside`` of the autocorrelation lags 1..L
  outside the ±1.96/√N band of white noise (5 % of them are, by chance, for white noise).

The verdict is *inadequate* when a fit or loop check fails, *adequate* when all pass,
and *adequate, residuals not white* when only the whiteness check fails: the model
reproduces what was measured but left structure (a missing effect, or a noisy input).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .metrics import autocorrelation

__all__ = ["ADEQUATE", "INADEQUATE", "NOT_WHITE", "Criteria", "record_verdict",
           "worst_verdict"]

ADEQUATE = "adequate"
NOT_WHITE = "adequate, residuals not white"
INADEQUATE = "inadequate"
_ORDER = (ADEQUATE, NOT_WHITE, INADEQUATE)


@dataclass(frozen=True)
class Criteria:
    """Thresholds of the verdict (see the module's docstring)."""

    min_fit_percent: float = 90.0
    loop_width: float = 0.10
    loop_area: float = 0.15
    breakaway: float = 0.25
    reversal: float = 0.25
    max_lags_outside: float = 0.25


def _relative(loops, measure: str) -> float:
    row = loops[loops["measure"] == measure]
    return float(abs(row["relative"].iloc[0])) if len(row) else np.nan


def _loop_checks(rv, criteria: Criteria) -> tuple[dict[str, float], list[str]]:
    """The loop measures' errors and the reasons the loop checks fail."""
    loops = rv.loops()
    values = {"loop_width_pressure_error": np.nan, "loop_width_position_error": np.nan,
              "loop_area_error": np.nan, "breakaway_error": np.nan, "reversal_error": np.nan}
    if loops is None:
        return values, []
    measured = loops.set_index("measure")["measured"]
    width_p, width_x = measured["loop_width_pressure"], measured["loop_width_position"]
    breakaway = loops.set_index("measure")["difference"]["breakaway_pressure"]
    reversals = rv.reversals()
    worst_reversal = (float(np.max(np.abs(reversals["position_difference"])))
                      if reversals is not None and len(reversals) else np.nan)
    values.update({"loop_width_pressure_error": _relative(loops, "loop_width_pressure"),
                   "loop_width_position_error": _relative(loops, "loop_width_position"),
                   "loop_area_error": _relative(loops, "loop_area"),
                   "breakaway_error": abs(breakaway) / width_p,
                   "reversal_error": worst_reversal / width_x})
    limits = {"loop_width_pressure_error": ("loop width in pressure", criteria.loop_width,
                                            "of it"),
              "loop_width_position_error": ("loop width in position", criteria.loop_width,
                                            "of it"),
              "loop_area_error": ("loop area", criteria.loop_area, "of it"),
              "breakaway_error": ("break-away pressure", criteria.breakaway,
                                  "of the loop width"),
              "reversal_error": ("position at the reversals", criteria.reversal,
                                 "of the loop width in position")}
    reasons = [f"{what} off by {100 * values[key]:.3g} % {of} (allowed {100 * limit:g} %)"
               for key, (what, limit, of) in limits.items()
               if np.isfinite(values[key]) and values[key] > limit]
    return values, reasons


def _lags_outside(residual) -> float:
    acf, band = autocorrelation(residual)
    return float(np.mean(np.abs(acf[1:]) > band)) if acf.size > 1 else 0.0


def record_verdict(rv, criteria: Criteria) -> dict:
    """The verdict of one ``RecordValidation``, with every check's value and the reasons
    for it."""
    fits = dict(zip(rv.signals, rv.metrics()["fit_percent"], strict=True))
    reasons = [f"fit of {s} {fit:.3g} % (at least {criteria.min_fit_percent:g} % needed)"
               for s, fit in fits.items() if not fit >= criteria.min_fit_percent]
    loop_values, loop_reasons = _loop_checks(rv, criteria)
    reasons += loop_reasons
    outside = max(_lags_outside(rv.residual(s)) for s in rv.signals)
    white = outside <= criteria.max_lags_outside
    if reasons:
        verdict = INADEQUATE
    else:
        verdict = ADEQUATE if white else NOT_WHITE
    if not white:
        reasons.append(f"{100 * outside:.3g} % of the residual autocorrelation lags lie "
                       f"outside the white-noise band (at most "
                       f"{100 * criteria.max_lags_outside:g} %)")
    dropped = getattr(rv, "dropped", ())
    note = (f" ({', '.join(dropped)} not compared: the record's input, it drives the "
            "model)" if dropped else "")
    return {"record": rv.name, "input": rv.input, "valve": rv.valve, "verdict": verdict,
            "reasons": ("; ".join(reasons) or "all checks pass") + note,
            "fit_percent": min(fits.values()), **loop_values,
            "residual_lags_outside": outside}


def worst_verdict(verdicts) -> str:
    """The worst of several verdicts (inadequate > not white > adequate)."""
    return max(verdicts, key=_ORDER.index, default=ADEQUATE)
