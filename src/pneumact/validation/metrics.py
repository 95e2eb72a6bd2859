"""How close a prediction is to a measurement: the numbers of system identification.

With e = y − ŷ over N samples and ȳ the mean of the measurement:

* RMS error √(Σe²/N) and maximum |e| (in the signal's unit);
* NRMSE = ‖e‖ / ‖y − ȳ‖ (normalised by the measurement's spread, as MATLAB's
  ``compare`` and ``goodnessOfFit(..., 'NRMSE')``);
* fit % = 100·(1 − NRMSE): 100 for a perfect prediction, 0 for the mean of y;
* R² = 1 − Σe² / Σ(y − ȳ)² = 1 − NRMSE².

``autocorrelation`` of the residuals tells whether the model left structure behind
(white residuals stay inside ±1.96/√N beyond lag 0).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import DataError

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["METRIC_NAMES", "autocorrelation", "error_metrics", "metrics_for_reading"]

METRIC_NAMES = ("rms", "max", "nrmse", "fit_percent", "r2", "n")


def _pair(measured, predicted, what: str) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(measured, dtype=float).ravel()
    y_hat = np.asarray(predicted, dtype=float).ravel()
    if y.shape != y_hat.shape:
        raise DataError(f"{what}: {y.size} measured samples but {y_hat.size} predicted; "
                        "compare them on the same time grid")
    if y.size < 2:
        raise DataError(f"{what}: {y.size} samples; need at least 2")
    for name, values in (("measured", y), ("predicted", y_hat)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise DataError(f"{what}: {name} value {values[bad[0]]} at sample {bad[0]} "
                            f"({bad.size} not finite); crop or clean the record first")
    return y, y_hat


def error_metrics(measured, predicted, what: str = "signal") -> dict[str, float]:
    """RMS, max, NRMSE, fit % and R² of ``predicted`` against ``measured`` (same grid)."""
    y, y_hat = _pair(measured, predicted, what)
    error = y - y_hat
    spread = float(np.linalg.norm(y - y.mean()))
    norm = float(np.linalg.norm(error))
    nrmse = norm / spread if spread > 0 else (0.0 if norm == 0 else np.inf)
    return {"rms": float(np.sqrt(np.mean(error**2))), "max": float(np.max(np.abs(error))),
            "nrmse": nrmse, "fit_percent": 100.0 * (1.0 - nrmse), "r2": 1.0 - nrmse**2,
            "n": float(y.size)}


def autocorrelation(residual, max_lag: int | None = None) -> tuple[np.ndarray, float]:
    """(normalised autocorrelation at lags 0..max_lag, the ±95 % band of white noise
    1.96/√N). ``max_lag`` defaults to min(N − 1, N/4, 200)."""
    e = np.asarray(residual, dtype=float).ravel()
    if e.size < 2 or not np.all(np.isfinite(e)):
        raise DataError(f"autocorrelation: need at least 2 finite residuals, got {e.size}")
    e = e - e.mean()
    lags = min(e.size - 1, max(1, e.size // 4), 200) if max_lag is None else int(max_lag)
    if not 0 < lags < e.size:
        raise DataError(f"max_lag = {max_lag}; must be between 1 and {e.size - 1}")
    # the autocorrelation through the FFT (zero-padded past 2N − 1: not circular), as
    # scipy.signal.correlate does for long records, without its 0.9 s import
    spectrum = np.fft.rfft(e, 2 * e.size)
    full = np.fft.irfft(spectrum * np.conj(spectrum), 2 * e.size)[:lags + 1]
    acf = full / full[0] if full[0] > 0 else np.zeros(lags + 1)
    return acf, 1.96 / np.sqrt(e.size)


#: the metric columns as a person reads them ("rms" and "max" get the signal's unit)
_READ_AS = {"nrmse": "NRMSE [1]", "fit_percent": "fit [%]", "r2": "R² [1]"}


def metrics_for_reading(frame: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """A metrics table (``Validation.metrics``) for a person: one table per signal, its
    RMS and max in display units (µm or mm, kPa, N) with the unit in the header."""
    from ..core.units import signal_unit
    from ..io.display import display_frame

    tables = {}
    for signal, part in frame.groupby("signal", sort=False):
        unit = signal_unit(str(signal)) or "1"
        named = part.drop(columns="signal").rename(
            columns={"rms": f"rms [{unit}]", "max": f"max [{unit}]", **_READ_AS})
        tables[str(signal)] = display_frame(named)
    return tables
