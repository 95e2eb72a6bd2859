"""The filters computed in numpy to keep ``scipy.signal`` (a 0.9 s import) off the path
from a record to identified parameters: each against scipy.signal's own, and the path
itself without the import."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy import signal

import reference as ref
from pneumact.identification.smoothing import savgol_filter, savgol_weights
from pneumact.models.sensors import first_order_lag
from pneumact.validation.metrics import autocorrelation

pytestmark = pytest.mark.unit


def _close(ours: np.ndarray, theirs: np.ndarray) -> None:
    scale = max(float(np.max(np.abs(theirs))), 1e-300)
    assert ours.shape == theirs.shape
    assert float(np.max(np.abs(ours - theirs))) <= ref.NUMPY_FILTER_RTOL * scale


@pytest.mark.parametrize("n", [7, 60, 5001])
@pytest.mark.parametrize("window, order", [(5, 3), (7, 2), (31, 3), (201, 3)])
def test_savitzky_golay_is_scipy_s(n, window, order):
    if window > n:
        pytest.skip("a window longer than the record is refused")
    rng = np.random.default_rng(n + window)
    x = np.sin(np.linspace(0, 6, n)) * 1e-2 + np.cumsum(rng.normal(size=n)) * 1e-5
    for deriv in range(order + 1):
        _close(savgol_filter(x, window, order, deriv=deriv, delta=1e-3),
               signal.savgol_filter(x, window, order, deriv=deriv, delta=1e-3))
        _close(savgol_weights(window, order, deriv, 1e-3),
               signal.savgol_coeffs(window, order, deriv=deriv, delta=1e-3, use="dot"))


@pytest.mark.parametrize("tau_over_step", [0.0, 0.01, 0.3, 0.5, 5.0, 1e3, 1e6])
@pytest.mark.parametrize("shape", [(2,), (9,), (40_000,), (3000, 2)])
def test_the_first_order_lag_is_lfilter_s(tau_over_step, shape):
    """Every regime of the recursion: no lag, a memory of a few samples, blocks of the
    cumulative sum from a few to one; a column at a time or several."""
    step = 1e-3
    time = step * np.arange(shape[0])
    rng = np.random.default_rng(shape[0])
    values = 1e-3 * (np.cumsum(rng.normal(size=shape), axis=0) + 3.0)
    tau = tau_over_step * step
    ours = first_order_lag(time, values, tau)
    if tau == 0:
        np.testing.assert_array_equal(ours, values)
        return
    a = np.exp(-step / tau)
    c1 = 1.0 - tau / step * (1.0 - a)
    theirs = signal.lfilter([c1, (1.0 - a) - c1], [1.0, -a], values - values[:1],
                            axis=0) + values[:1]
    _close(ours, theirs)


@pytest.mark.parametrize("n", [2, 3, 50, 20_001])
def test_the_autocorrelation_is_scipy_s(n):
    e = np.random.default_rng(n).normal(size=n) + 0.3
    acf, band = autocorrelation(e)
    centred = e - e.mean()
    full = signal.correlate(centred, centred, mode="full", method="direct")
    _close(acf, full[n - 1:n - 1 + acf.size] / full[n - 1])
    assert band == pytest.approx(1.96 / np.sqrt(n))


def test_an_identification_never_imports_scipy_signal():
    """From a simulated record to its kinematics, residual whiteness and a first-order
    lag: the identification path runs without importing scipy.signal."""
    script = (
        "import sys, numpy as np\n"
        "import pneumact as pa\n"
        "from pneumact.identification.bench import kinematics\n"
        "from pneumact.models.sensors import first_order_lag\n"
        "from pneumact.validation.metrics import autocorrelation\n"
        "t = np.linspace(0, 2, 2001)\n"
        "x = 0.01 * np.sin(t) + 1e-6 * np.random.default_rng(0).normal(size=t.size)\n"
        "rec = pa.Record.from_arrays(t, {'pressure': 5e4 + 0 * t, 'position': x},\n"
        "                               {'pressure': 'Pa', 'position': 'm'}, 'r')\n"
        "kinematics(rec); autocorrelation(x); first_order_lag(t, x, 5e-3)\n"
        "print('scipy.signal' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False", out.stderr
