"""The bench's sensors: what stands between the actuator's states and a record.

A record is not the actuator's position and chamber pressure but what its sensors made of
them: an offset (a zero not set, a gauge read as absolute), a first-order lag (a
potentiometer's filter, a pressure transducer's tubing), a resolution (an ADC's step)
and a sample rate. Each is a parameter with its own catalogue entry, so that an
identified model can carry the bench it was identified on:

    measured(t) = Q( L_τ[ y + offset ](t) )

with L_τ the first-order lag dy_m/dt = (y − y_m)/τ (the sensor settled at the record's
start) and Q the rounding to the resolution. The sensors read the model's outputs and
feed nothing back, so they are applied after a simulation (``Sensors.measure``) and are
not part of the compiled kernel; the lag is exact for an output linear between samples.

The defaults are an ideal bench (no offset, no lag, no quantisation): a parameter set
that states none of these describes the actuator alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from ..parameters.catalogue import ParameterSpec, declare
from .actuator import CHAMBER_PRESSURE

if TYPE_CHECKING:
    from collections.abc import Mapping

__all__ = ["SENSOR_PARAMETERS", "Sensors", "first_order_lag", "lag_derivative"]

P = ParameterSpec
SENSOR_PARAMETERS = declare(
    P("position_offset", "m", "position sensor offset (reading at the rest stop)", None,
      -1.0, False, 1.0, group="sensors", plausible=(-0.05, 0.05)),
    P("pressure_offset", "Pa", "pressure sensor offset (reading − chamber pressure)", None,
      -1e6, False, 1e6, group="sensors", plausible=(-2e4, 2e4)),
    P("position_lag", "s", "time constant of the position sensor's first-order lag", None,
      0.0, False, 10.0, group="sensors", plausible=(0.0, 0.2)),
    P("pressure_lag", "s", "time constant of the pressure sensor's first-order lag", None,
      0.0, False, 10.0, group="sensors", plausible=(0.0, 0.2)),
    P("position_resolution", "m", "position sensor resolution (quantisation step)", None,
      0.0, False, 0.01, group="sensors", plausible=(0.0, 2e-4)),
    P("sample_rate", "Hz", "sample rate of the bench's data acquisition", None, 0.0, True,
      1e7, group="sensors", plausible=(10.0, 1e6)),
)

#: the signal each offset, lag and resolution belongs to
_OF_SIGNAL = {"position": ("position_offset", "position_lag", "position_resolution"),
              CHAMBER_PRESSURE: ("pressure_offset", "pressure_lag", None)}


def _uniform_step(time: np.ndarray) -> float | None:
    dt = np.diff(time)
    if dt.size and np.ptp(dt) <= 1e-9 * np.mean(dt):
        return float(np.mean(dt))
    return None


def first_order_lag(time: np.ndarray, values: np.ndarray, tau: float) -> np.ndarray:
    """``values`` (samples at ``time``, along the first axis) seen through a first-order
    sensor of time constant ``tau`` [s], settled at the first sample; exact for a signal
    linear between samples (tau = 0: the values themselves)."""
    values = np.asarray(values, dtype=float)
    if tau < 0 or not np.isfinite(tau):
        raise ParameterError(f"first_order_lag: tau = {tau}; must be a finite time >= 0 s")
    if tau == 0 or values.shape[0] < 2:
        return values.copy()
    time = np.asarray(time, dtype=float)
    h = _uniform_step(time)
    if h is not None:
        a = np.exp(-h / tau)
        c1 = 1.0 - tau / h * (1.0 - a)  # weight of the new sample
        c0 = (1.0 - a) - c1  # of the previous one
        first = values[:1]
        change = values - first
        fed = c1 * change
        fed[1:] += c0 * change[:-1]
        return _geometric_recursion(fed, a) + first
    out = np.empty_like(values)
    out[0] = values[0]
    for i in range(1, values.shape[0]):
        step = time[i] - time[i - 1]
        a = np.exp(-step / tau)
        slope = (values[i] - values[i - 1]) / step
        out[i] = values[i] - tau * slope + a * (out[i - 1] - values[i - 1] + tau * slope)
    return out


#: The recursion's blocks keep a^-j within 10^LAG_BLOCK_DECADES (see
#: ``_geometric_recursion``): far from overflow for any signal in SI units.
LAG_BLOCK_DECADES = 100
#: Below this a (a lag shorter than a third of the sample step), y[n] is a sum of the
#: few terms a^k·fed[n − k] above 1e-18 of it (fewer than 14), not a recursion.
LAG_SHORT_MEMORY = 0.05


def _geometric_recursion(fed: np.ndarray, a: float) -> np.ndarray:
    """y[n] = a·y[n−1] + fed[n] along the first axis (y[−1] = 0, 0 <= a < 1): what
    ``scipy.signal.lfilter`` computes for a first-order filter, in numpy (without its
    0.9 s import). Within a block of samples j = 0, 1, …, y[j] = a^j·(a·y_before +
    Σ_{i<=j} a^-i·fed[i]), a cumulative sum; the blocks are short enough for a^-j to
    stay finite, and the rounding, relative to the sum, is that of y itself."""
    out = fed.copy()
    if a < LAG_SHORT_MEMORY:  # a^k falls below 1e-18 of fed within a few samples
        terms = 0 if a == 0.0 else math.ceil(math.log(1e-18) / math.log(a))
        for k in range(1, min(terms, fed.shape[0])):
            out[k:] += a**k * fed[:-k]
        return out
    span = int(LAG_BLOCK_DECADES * math.log(10.0) / -math.log(a))
    steps = np.arange(min(span, fed.shape[0]), dtype=float).reshape(
        -1, *([1] * (fed.ndim - 1)))
    grow, decay = a ** -steps, a ** steps
    before = np.zeros(fed.shape[1:])
    for start in range(0, fed.shape[0], span):
        block = fed[start:start + span]
        m = block.shape[0]
        out[start:start + m] = decay[:m] * (a * before + np.cumsum(grow[:m] * block, axis=0))
        before = out[start + m - 1]
    return out


def lag_derivative(time: np.ndarray, values: np.ndarray, tau: float) -> np.ndarray:
    """∂ first_order_lag(time, values, tau) / ∂tau (central differences of the filter:
    a cheap post-processing, no simulation), one-sided at tau = 0."""
    h = _uniform_step(np.asarray(time, dtype=float))
    scale = h if h is not None else float(np.median(np.diff(time)))
    step = max(1e-4 * tau, 1e-3 * scale)
    upper = first_order_lag(time, values, tau + step)
    if tau > step:
        return (upper - first_order_lag(time, values, tau - step)) / (2 * step)
    return (upper - first_order_lag(time, values, tau)) / step


@dataclass(frozen=True)
class Sensors:
    """The bench's sensors (SI): offsets [m, Pa], first-order lags [s], the position
    resolution [m] (0: none) and the sample rate [Hz] (None: as recorded)."""

    position_offset: float = 0.0
    pressure_offset: float = 0.0
    position_lag: float = 0.0
    pressure_lag: float = 0.0
    position_resolution: float = 0.0
    sample_rate: float | None = None

    def __post_init__(self) -> None:
        for name in ("position_lag", "pressure_lag", "position_resolution"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"Sensors: {name} = {value}; must be a finite value "
                                     ">= 0")
        if self.sample_rate is not None and not self.sample_rate > 0:
            raise ParameterError(f"Sensors: sample_rate = {self.sample_rate}; must be > 0 Hz")

    @classmethod
    def from_params(cls, params: Mapping[str, float] | None) -> Sensors:
        """The sensors a parameter set states (an ideal bench for what it leaves out)."""
        if params is None:
            return cls()
        given = {n: float(params[n]) for n in SENSOR_PARAMETERS if n in params}
        return cls(**given)

    @property
    def ideal(self) -> bool:
        """No offset, lag or quantisation: the records are the states themselves."""
        return not any((self.position_offset, self.pressure_offset, self.position_lag,
                        self.pressure_lag, self.position_resolution))

    def lag(self, signal: str) -> float:
        """The lag [s] of ``signal``'s sensor (0 for a signal without one)."""
        names = _OF_SIGNAL.get(signal)
        return float(getattr(self, names[1])) if names else 0.0

    def offset(self, signal: str) -> float:
        names = _OF_SIGNAL.get(signal)
        return float(getattr(self, names[0])) if names else 0.0

    def measure(self, time: np.ndarray, signal: str, values: np.ndarray,
                quantise: bool = True) -> np.ndarray:
        """What ``signal``'s sensor reads when the true signal is ``values``."""
        out = first_order_lag(time, np.asarray(values, dtype=float) + self.offset(signal),
                              self.lag(signal))
        if quantise and signal == "position" and self.position_resolution > 0:
            out = np.round(out / self.position_resolution) * self.position_resolution
        return out
