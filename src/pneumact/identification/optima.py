"""Honest about local optima: restarts of a bounded fit, and intervals that cover every
optimum the noise cannot tell apart (issue 38, item 5).

- A least-squares fit whose solution ends at a bound of its search range has not found
  an optimum the data support: it is started again from the prior and from spread
  starts (``spread_starts``), and the best optimum inside the bounds is kept
  (``restarted_least_squares``). Only when every start ends at a bound does it give up,
  with the reason (``stuck_reason``).
- Two starts that reach costs within the noise (twice the cost difference of the scaled
  residuals below ``CHI2_95_1DOF``, the 95 % quantile of χ² with one degree of freedom)
  but values farther apart than the reported interval are two optima the records cannot
  tell apart: the interval of each such parameter is widened to cover both
  (``widen_for_optima``), never reported as tight about one of them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np
from scipy.optimize import OptimizeResult, least_squares

__all__ = [
    "BOUND_ATOL",
    "CHI2_95_1DOF",
    "RESTART_GAIN",
    "RESTART_RETURNS",
    "RESTART_SPREAD",
    "Restarted",
    "at_bound",
    "cover_optima",
    "cover_values",
    "restarted",
    "restarted_least_squares",
    "spread_starts",
    "stuck_reason",
    "widen_for_optima",
]

#: A solution of a fit (scipy's OptimizeResult, a FitResult).
Solution = TypeVar("Solution")

#: 95 % quantile of χ² with one degree of freedom: two optima whose scaled costs (Σr²/σ²)
#: differ by less are within the noise of each other.
CHI2_95_1DOF = 3.841458820694124
#: A value within this (relative to the search range) of a bound is at the bound (the
#: trust-region solver stops short of an active bound by some 1e-6 of the range).
BOUND_ATOL = 1e-6
#: The spread of the restarts about the prior: each parameter at prior × (1 ± spread/2),
#: the others at the prior (a prior is a guess within ±50 %).
RESTART_SPREAD = 0.5
#: A joint fit's restarts stop once this many starts in a row ended at a bound again with
#: no lower cost (by ``RESTART_GAIN``): the starts about the prior lie in the basin of
#: that bound (the reproduction's 5 ms-lag campaign: all six starts came back to σ1 and σ2
#: at their bounds, costs within 2e-5 of each other, at 4-6 s of CPU each)
RESTART_RETURNS = 2
#: The relative drop of cost that makes a restart that ends at a bound a new optimum
RESTART_GAIN = 1e-3


def at_bound(values: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Per value, whether it sits on its lower or upper bound (``BOUND_ATOL`` of the
    range)."""
    values, lower, upper = (np.asarray(a, dtype=float) for a in (values, lower, upper))
    span = np.where(np.isfinite(upper - lower), upper - lower, 1.0)
    tol = BOUND_ATOL * np.maximum(span, np.finfo(float).tiny)
    return (np.abs(values - lower) <= tol) | (np.abs(values - upper) <= tol)


def spread_starts(prior: np.ndarray, spread: float = RESTART_SPREAD,
                  which: np.ndarray | None = None) -> list[np.ndarray]:
    """The prior, then each parameter in turn (those ``which`` marks, default all) at
    prior × (1 − spread/2) and prior × (1 + spread/2): deterministic, 1 + 2·n starts for
    n parameters moved."""
    prior = np.asarray(prior, dtype=float)
    moved = np.ones(prior.size, bool) if which is None else np.asarray(which, bool)
    starts = [prior.copy()]
    for j in np.flatnonzero(moved):
        for factor in (1.0 - spread / 2, 1.0 + spread / 2):
            start = prior.copy()
            start[j] *= factor
            starts.append(start)
    return starts


def stuck_reason(names: Sequence[str], values: np.ndarray, stuck: np.ndarray,
                 starts: int) -> str:
    """'vs stuck at its bound 1 after 7 starts' for each stuck parameter."""
    return "; ".join(f"{name} stuck at its bound {value:.4g} after {starts} starts"
                     for name, value, bad in zip(names, values, stuck, strict=True) if bad)


@dataclass(frozen=True)
class Restarted(Generic[Solution]):
    """The best solution of a restarted fit, every start's solution, and whether the best
    is still at a bound (then ``reason`` says which parameter, where, after how many
    starts)."""

    best: Solution
    solutions: list[Solution]
    stuck: np.ndarray
    reason: str

    @property
    def ok(self) -> bool:
        return not bool(self.stuck.any())


def restarted(solve: Callable[[np.ndarray], Solution], start: np.ndarray, prior: np.ndarray,
              names: Sequence[str], stuck_of: Callable[[Solution], np.ndarray],
              cost_of: Callable[[Solution], float], values_of: Callable[[Solution], np.ndarray],
              spread: float = RESTART_SPREAD) -> Restarted[Solution]:
    """``solve(start)``; a solution ``stuck_of`` says is at a bound is solved again from
    ``spread_starts(prior, spread)``, and the best (``cost_of``) solution inside the
    bounds is kept (the best at a bound when none is inside; ``values_of`` gives its
    values for the reason)."""
    solutions = [solve(np.asarray(start, dtype=float))]
    if stuck_of(solutions[0]).any():
        solutions += [solve(s) for s in spread_starts(prior, spread)]
    inside = [s for s in solutions if not stuck_of(s).any()]
    best = min(inside or solutions, key=cost_of)
    stuck = np.asarray(stuck_of(best), bool)
    reason = stuck_reason(names, values_of(best), stuck, len(solutions)) if stuck.any() \
        else ""
    return Restarted(best, solutions, stuck, reason)


def restarted_least_squares(residuals: Callable[[np.ndarray], np.ndarray], start: np.ndarray,
                            lower: np.ndarray, upper: np.ndarray, prior: np.ndarray,
                            names: Sequence[str], spread: float = RESTART_SPREAD,
                            **options) -> Restarted[OptimizeResult]:
    """``scipy.optimize.least_squares`` from ``start`` within (``lower``, ``upper``),
    ``restarted`` from the prior and spread starts (each clipped inside the bounds) when
    it ends at a bound."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    inner = (np.nextafter(lower, np.inf), np.nextafter(upper, -np.inf))

    def solve(x0: np.ndarray) -> OptimizeResult:
        return least_squares(residuals, np.clip(x0, *inner), bounds=(lower, upper), **options)

    def stuck_of(solution: OptimizeResult) -> np.ndarray:
        return (np.asarray(solution.active_mask) != 0) | at_bound(solution.x, lower, upper)

    return restarted(solve, start, prior, names, stuck_of, lambda s: float(s.cost),
                     lambda s: s.x, spread)


def widen_for_optima(values: np.ndarray, half_widths: np.ndarray, best_cost: float,
                     others: Sequence[tuple[np.ndarray, float]], noise_variance: float = 1.0
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The ``half_widths`` of the 95 % intervals about the best optimum ``values``
    (cost ``best_cost`` = ½Σr²), each widened to reach every other optimum in ``others``
    ((values, cost) of the other starts) whose cost is within the noise of the best
    (2·Δcost/``noise_variance`` below ``CHI2_95_1DOF``) and which lies outside the
    interval. Returns (half-widths, which were widened)."""
    values = np.asarray(values, dtype=float)
    half = np.asarray(half_widths, dtype=float).copy()
    widened = np.zeros(values.size, bool)
    for other, cost in others:
        if not 2.0 * (cost - best_cost) / noise_variance < CHI2_95_1DOF:
            continue
        distance = np.abs(np.asarray(other, dtype=float) - values)
        apart = distance > half
        reach = distance + np.asarray(half_widths, dtype=float)
        half = np.where(apart, np.maximum(half, reach), half)
        widened |= apart
    return half, widened


def cover_values(covariance: np.ndarray, values: np.ndarray,
                 others: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """``covariance`` scaled so that each 95 % interval (1.96 standard errors) about
    ``values`` reaches each of ``others`` and its interval of the same width: estimates
    the records cannot be told from (refits with a held parameter elsewhere in its
    range). Returns (covariance, which estimates were widened)."""
    return cover_optima(covariance, values, 0.0, [(o, 0.0) for o in others], 1.0)


def cover_optima(covariance: np.ndarray, values: np.ndarray, best_cost: float,
                 others: Sequence[tuple[np.ndarray, float]], noise_variance: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """``covariance`` scaled so that each 95 % interval (1.96 standard errors) reaches
    every other optimum within the noise (``widen_for_optima``). Returns (covariance,
    which estimates were widened)."""
    half = 1.96 * np.sqrt(np.diag(covariance))
    if not others or not noise_variance > 0:
        return covariance, np.zeros(len(values), bool)
    wide, widened = widen_for_optima(values, half, best_cost, others, noise_variance)
    finite = np.isfinite(half) & (half > 0)
    scale = np.ones_like(half)
    scale[finite] = wide[finite] / half[finite]
    return covariance * np.outer(scale, scale), widened & finite
