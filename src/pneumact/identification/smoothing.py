"""Savitzky-Golay differentiation in numpy: the velocity and acceleration of a record.

The same numbers as ``scipy.signal.savgol_coeffs`` and ``savgol_filter`` (mode
"interp"; a test holds them together), without importing ``scipy.signal``: that import
alone costs about 0.9 s of CPU, most of an identification's start, and nothing else on
the path from a record to identified parameters needs it.

Inside the record, each sample's value (or derivative) is that of the least-squares
polynomial over the ``window`` samples centred on it, a fixed weighting of them; over the
first and last half windows, that of the polynomial fitted to the first or last window.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import DataError

__all__ = ["savgol_filter", "savgol_weights"]


def savgol_weights(window: int, order: int, deriv: int = 0, delta: float = 1.0) -> np.ndarray:
    """The weights of the ``window`` samples centred on a sample (oldest first) that give
    the ``deriv``-th derivative, for a sample spacing ``delta``, of the least-squares
    polynomial of degree ``order`` through them."""
    _check(window, order, deriv)
    half = window // 2
    offsets = np.arange(-half, half + 1, dtype=float)
    powers = offsets[np.newaxis, :] ** np.arange(order + 1)[:, np.newaxis]
    unit = np.zeros(order + 1)
    unit[deriv] = math.factorial(deriv) / delta**deriv
    return np.linalg.lstsq(powers, unit, rcond=None)[0]


def savgol_filter(x, window: int, order: int, deriv: int = 0,
                  delta: float = 1.0) -> np.ndarray:
    """``x`` (1-D) smoothed (``deriv`` 0) or differentiated by a Savitzky-Golay filter of
    ``window`` samples and degree ``order``, the half windows at the ends from the
    polynomial fitted to the first and last windows (scipy's mode "interp")."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < window:
        raise DataError(f"savgol_filter: {x.size} samples; need a 1-D record of at least "
                        f"window = {window}")
    half = window // 2
    out = np.empty_like(x)
    out[half:x.size - half] = np.correlate(x, savgol_weights(window, order, deriv, delta),
                                           mode="valid")
    positions = np.arange(window, dtype=float)
    for fitted, rows, at in ((x[:window], slice(0, half), positions[:half]),
                             (x[-window:], slice(x.size - half, x.size),
                              positions[window - half:])):
        polynomial = np.polyder(np.polyfit(positions, fitted, order), deriv)
        out[rows] = np.polyval(polynomial, at) / delta**deriv
    return out


def _check(window: int, order: int, deriv: int) -> None:
    if not (isinstance(window, int | np.integer) and window >= 1 and window % 2 == 1):
        raise DataError(f"savgol: window = {window!r}; must be an odd number of samples")
    if not 0 <= deriv <= order < window:
        raise DataError(f"savgol: order = {order!r}, deriv = {deriv!r}; need 0 <= deriv <= "
                        f"order < window = {window}")
