"""Estimates with their uncertainty, and linear least squares that reports it.

Every stage and fit returns ``Estimates``: values, standard errors and the covariance,
95 % intervals from Student's t with the residual degrees of freedom, and a table.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import DataError

__all__ = ["Estimates", "covariance_from_jacobian", "linear_least_squares"]


@dataclass(frozen=True, eq=False)
class Estimates:
    """Named estimates (SI) with standard errors, covariance and degrees of freedom."""

    names: tuple[str, ...]
    values: np.ndarray
    stderr: np.ndarray
    covariance: np.ndarray
    dof: int
    units: tuple[str, ...] = ()

    def __getitem__(self, name: str) -> float:
        return float(self.values[self._index(name)])

    def _index(self, name: str) -> int:
        if name not in self.names:
            raise KeyError(f"no estimate {name!r}; estimates: {', '.join(self.names)}")
        return self.names.index(name)

    def as_dict(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values, strict=True)}

    def interval(self, level: float = 0.95) -> np.ndarray:
        """(n × 2) two-sided confidence intervals from Student's t (normal if dof ≤ 0)."""
        from scipy import stats

        q = stats.t.ppf(0.5 + level / 2, self.dof) if self.dof > 0 else \
            stats.norm.ppf(0.5 + level / 2)
        return np.column_stack([self.values - q * self.stderr, self.values + q * self.stderr])

    @property
    def correlation(self) -> np.ndarray:
        d = np.where(self.stderr > 0, self.stderr, np.nan)
        return self.covariance / np.outer(d, d)

    def to_pandas(self, level: float = 0.95) -> pd.DataFrame:
        ci = self.interval(level)
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = 100 * self.stderr / np.abs(self.values)
        frame = pd.DataFrame({
            "value": self.values, "stderr": self.stderr, "relative_stderr_%": rel,
            f"ci{int(level * 100)}_low": ci[:, 0], f"ci{int(level * 100)}_high": ci[:, 1],
        }, index=pd.Index(self.names, name="parameter"))
        if self.units:
            frame.insert(0, "unit", list(self.units))
        return frame


def covariance_from_jacobian(jac: np.ndarray, residuals: np.ndarray, n_par: int
                             ) -> tuple[np.ndarray, int]:
    """s²·(JᵀJ)⁻¹ with s² = Σr²/(N − P): the Gauss-Newton covariance; infinite where
    JᵀJ is singular (the data cannot separate the parameters). Returns (cov, dof)."""
    dof = residuals.size - n_par
    s2 = float(residuals @ residuals) / dof if dof > 0 else np.nan
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    tol = (sv.max() if sv.size else 0.0) * max(jac.shape) * np.finfo(float).eps
    if sv.size < n_par or sv.min() <= tol:
        return np.full((n_par, n_par), np.inf), dof  # not identifiable from these data
    cov = (vt.T / sv**2) @ vt
    return s2 * cov, dof


def linear_least_squares(design: np.ndarray, target: np.ndarray, names: Sequence[str],
                         units: Sequence[str] = (), what: str = "linear fit"
                         ) -> tuple[Estimates, np.ndarray, float]:
    """Ordinary least squares ``target ≈ design @ θ`` with standard errors.

    Returns (estimates, residuals, condition number of the column-scaled design)."""
    design = np.asarray(design, dtype=float)
    target = np.asarray(target, dtype=float)
    if design.shape[0] <= design.shape[1]:
        raise DataError(f"{what}: {design.shape[0]} data points for {design.shape[1]} "
                        f"unknowns ({', '.join(names)}); need more points than unknowns")
    scale = np.linalg.norm(design, axis=0)
    if np.any(scale == 0):
        dead = [n for n, s in zip(names, scale, strict=True) if s == 0]
        raise DataError(f"{what}: the data never excite {', '.join(dead)} (its column is "
                        "zero); it cannot be estimated from these records")
    scaled = design / scale
    theta_s, *_ = np.linalg.lstsq(scaled, target, rcond=None)
    theta = theta_s / scale
    residuals = target - design @ theta
    cov, dof = covariance_from_jacobian(design, residuals, design.shape[1])
    cond = float(np.linalg.cond(scaled))
    est = Estimates(tuple(names), theta, np.sqrt(np.diag(cov)), cov, dof, tuple(units))
    return est, residuals, cond
