"""Estimates with their uncertainty, and linear least squares that reports it.

Every stage and fit returns ``Estimates``: values, standard errors and the covariance,
95 % intervals from Student's t with the residual degrees of freedom, and a table.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import DataError
from ..io.report import ResultVocabulary
from ..plotting import tight_layout

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["Estimates", "covariance_from_jacobian", "linear_least_squares"]

#: Directions of the column-scaled information matrix whose singular value is below this
#: fraction of the largest are not determined by the data (their variance is infinite):
#: far above round-off (1e-16) and far below any direction a fit resolves.
RANK_TOLERANCE = 1e-10


@dataclass(frozen=True, eq=False)
class Estimates(ResultVocabulary):
    """Named estimates (SI) with standard errors, covariance and degrees of freedom.

    ``to_pandas()``: value, standard error and interval per estimate
    (``"correlation"``: the correlation matrix); ``plot()``: each estimate's interval
    relative to its value; ``write(folder)``: both tables, the figure and report.html."""

    report_title = "Estimates"
    figure_name = "intervals"

    def tables(self) -> dict[str, pd.DataFrame]:
        names = list(self.names)
        return {"estimates": self.to_pandas(),
                "correlation": pd.DataFrame(self.correlation, index=names, columns=names)}

    def plot(self, level: float = 0.95) -> Figure:
        """The ``level`` interval of each estimate, in % of its value."""
        import matplotlib.pyplot as plt

        ci = self.interval(level)
        scale = np.where(self.values != 0, np.abs(self.values), 1.0)
        low, high = 100 * (ci[:, 0] - self.values) / scale, 100 * (ci[:, 1] - self.values) / scale
        fig, ax = plt.subplots(figsize=(6.5, 0.3 * len(self.names) + 1.4))
        y = np.arange(len(self.names))
        ax.errorbar(np.zeros(len(y)), y, xerr=np.vstack([-low, high]), fmt="o", capsize=3)
        ax.set_yticks(y, list(self.names))
        ax.invert_yaxis()
        ax.axvline(0.0, color="k", lw=0.6)
        ax.set_xlabel(f"{100 * level:g} % interval [% of the estimate]")
        ax.grid(True, axis="x", alpha=0.3)
        tight_layout(fig)
        return fig

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

    def to_pandas(self, name: str | None = None, level: float = 0.95) -> pd.DataFrame:
        """value, stderr, relative stderr and the ``level`` interval per estimate (SI);
        ``name="correlation"``: the correlation matrix."""
        if name is not None:
            return super().to_pandas(name)
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


def covariance_from_jacobian(jac: np.ndarray, residuals: np.ndarray, n_par: int,
                             groups: Sequence[int] | None = None, correlated: bool = True
                             ) -> tuple[np.ndarray, int]:
    """Covariance of least-squares estimates from the Jacobian and residuals at the optimum.

    With ``correlated`` (the default) the Newey-West (HAC) sandwich
    (JᵀJ)⁻¹·S·(JᵀJ)⁻¹, S = Σ_l w_l·Σ_t g_t·g_{t−l}ᵀ, g_t = J_tᵀ·r_t, Bartlett weights,
    within each group of consecutive rows (one record or signal; ``groups`` gives their
    lengths): residuals of a time series are correlated (input errors, unmodelled
    dynamics, quantisation), and the textbook s²·(JᵀJ)⁻¹ then claims intervals several
    times too narrow. The bandwidth is three times the lag at which the residuals'
    autocorrelation falls below 1/e. ``correlated=False`` gives s²·(JᵀJ)⁻¹ with
    s² = Σr²/(N − P). Infinite where JᵀJ is singular. Returns (cov, dof)."""
    jac = np.asarray(jac, dtype=float)
    residuals = np.asarray(residuals, dtype=float)
    dof = residuals.size - n_par
    bread = _inverse_information(jac, n_par)
    if not correlated:
        s2 = float(residuals @ residuals) / dof if dof > 0 else np.nan
        return s2 * bread, dof
    scale = residuals.size / dof if dof > 0 else np.nan  # small-sample correction
    meat = np.zeros((n_par, n_par))
    start = 0
    for length in (groups or [residuals.size]):
        g = jac[start:start + length] * residuals[start:start + length, None]
        r = residuals[start:start + length]
        start += length
        meat += _long_run_covariance(g, _bandwidth(r))
    with np.errstate(invalid="ignore"):  # inf·0 of a dead parameter: its row stays inf
        covariance = scale * bread @ meat @ bread
    # a negative variance is round-off of a sandwich that cancelled: no interval, rather
    # than one of width zero
    negative = np.diag(covariance) < 0
    return (_with_infinite(covariance, negative) if np.any(negative) else covariance), dof


#: Up to this bandwidth the lag sums are direct products (O(L·n·P²)), beyond it FFTs
#: (O(P²·n·log n)).
DIRECT_BANDWIDTH = 32


def _inverse_information(jac: np.ndarray, n_par: int) -> np.ndarray:
    """(JᵀJ)⁻¹, computed on the column-scaled Jacobian (parameters of very different
    magnitudes must not look rank-deficient); a parameter the data do not determine
    (a direction of JᵀJ below round-off, ``RANK_TOLERANCE``) gets an infinite variance,
    the others keep theirs."""
    scale = np.linalg.norm(jac, axis=0)
    if jac.shape[1] < n_par or np.any(scale == 0):
        dead = np.zeros(n_par, bool) if jac.shape[1] < n_par else scale == 0
        if jac.shape[1] < n_par:
            dead[:] = True
        return _with_infinite(np.zeros((n_par, n_par)), dead)
    _, sv, vt = np.linalg.svd(jac / scale, full_matrices=False)
    keep = sv > RANK_TOLERANCE * sv.max()
    inverse = (vt[keep].T / sv[keep] ** 2) @ vt[keep]
    # a parameter with a share of a discarded direction is not determined by the data
    dead = np.any(np.abs(vt[~keep]) > 0.1, axis=0) if np.any(~keep) else np.zeros(n_par, bool)
    return _with_infinite(inverse / np.outer(scale, scale), dead)


def _with_infinite(covariance: np.ndarray, dead: np.ndarray) -> np.ndarray:
    """``covariance`` with the rows and columns of the ``dead`` parameters infinite."""
    covariance = covariance.copy()
    covariance[dead, :] = np.inf
    covariance[:, dead] = np.inf
    return covariance


def _long_run_covariance(g: np.ndarray, bandwidth: int) -> np.ndarray:
    """Σ_{|l| ≤ L} (1 − |l|/(L+1))·Σ_t g_t·g_{t−l}ᵀ.

    Beyond ``DIRECT_BANDWIDTH`` the lag sum is taken in the frequency domain: with the
    columns' spectra S, zero-padded to a fast length N of at least n + L + 1 (so that no
    lag within the bandwidth wraps onto another), and W the spectrum of the Bartlett
    weights over the circular lags, Parseval gives Σ_l w_l·c_ab(l) =
    Re(Σ_k S_a(k)·conj(S_b(k))·W_k)/N: one weighted product for all pairs instead of an
    inverse FFT per pair (the 5 µm campaign of ``reproduction.identify_richer``: 38 HAC
    covariances took 3.0 s of CPU in the inverse FFTs)."""
    n = g.shape[0]
    if bandwidth <= DIRECT_BANDWIDTH:
        out = g.T @ g
        for lag in range(1, min(bandwidth, n - 1) + 1):
            cross = g[lag:].T @ g[:-lag]
            out += (1.0 - lag / (bandwidth + 1.0)) * (cross + cross.T)
        return out
    from scipy.fft import next_fast_len, rfft

    lags = min(bandwidth, n - 1)  # longer lags have no pairs of samples
    length = next_fast_len(n + lags + 1, real=True)
    spectra = rfft(g, length, axis=0)
    return _weighted_spectral_product(spectra, _bartlett_spectrum(bandwidth, lags, length),
                                      length)


def _bartlett_spectrum(bandwidth: int, lags: int, length: int) -> np.ndarray:
    """The (real) rfft of the Bartlett weights 1 − |l|/(``bandwidth``+1) on the circular
    lags |l| ≤ ``lags`` of a sequence of ``length`` (lag −l at ``length`` − l), zero
    beyond."""
    from scipy.fft import rfft

    weights = np.zeros(length)
    weights[0] = 1.0
    ramp = 1.0 - np.arange(1, lags + 1) / (bandwidth + 1.0)
    weights[1:lags + 1] = ramp
    if lags:
        weights[length - lags:] = ramp[::-1]
    return rfft(weights).real


def _weighted_spectral_product(spectra: np.ndarray, window: np.ndarray,
                               length: int) -> np.ndarray:
    """Re(Sᴴ·diag(W)·S)/length over the full spectrum of real sequences of ``length``,
    from their half spectra (rfft): the bins other than 0 and length/2 count twice."""
    count = np.full(window.size, 2.0)
    count[0] = 1.0
    if length % 2 == 0:
        count[-1] = 1.0
    scale = (count * window / length)[:, None]
    real, imaginary = spectra.real, spectra.imag
    out = real.T @ (scale * real) + imaginary.T @ (scale * imaginary)
    return 0.5 * (out + out.T)


def long_run_variance(series: np.ndarray) -> float:
    """The HAC (Bartlett, ``_bandwidth``) variance of the sum of a series correlated in
    time, about its mean: what the variance of Σx would be were the samples independent
    times what their correlation adds (a held-out loss differential's, for instance)."""
    x = np.asarray(series, dtype=float).ravel()
    centred = (x - x.mean())[:, None]
    return float(_long_run_covariance(centred, _bandwidth(x))[0, 0])


def _bandwidth(r: np.ndarray) -> int:
    """Three times the lag where the autocorrelation of ``r`` first drops below 1/e."""
    n = r.size
    if n < 4:
        return 0
    centred = r - r.mean()
    spectrum = np.fft.rfft(centred, 2 * n)
    acf = np.fft.irfft(np.abs(spectrum) ** 2)[:n]
    if acf[0] <= 0:
        return 0
    below = np.flatnonzero(acf / acf[0] < np.exp(-1.0))
    lag = int(below[0]) if below.size else n
    return int(min(n // 4, 3 * lag))


def linear_least_squares(design: np.ndarray, target: np.ndarray, names: Sequence[str],
                         units: Sequence[str] = (), what: str = "linear fit",
                         correlated: bool = False) -> tuple[Estimates, np.ndarray, float]:
    """Ordinary least squares ``target ≈ design @ θ`` with standard errors (``correlated``:
    the rows are a time series, see :func:`covariance_from_jacobian`).

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
    cov, dof = covariance_from_jacobian(design, residuals, design.shape[1],
                                        correlated=correlated)
    cond = float(np.linalg.cond(scaled))
    est = Estimates(tuple(names), theta, np.sqrt(np.diag(cov)), cov, dof, tuple(units))
    return est, residuals, cond
