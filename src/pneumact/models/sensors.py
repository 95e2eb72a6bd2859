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

The sensor is a component kind placed once per measured signal, as the cylinder's
chambers are: a model with several signals of one quantity (the cylinder's
``pressure_a`` and ``pressure_b``) declares its sensors (``declare_sensors``), each the
instance ``sensor_<signal>`` whose parameters are ``sensor_pressure_a.offset``,
``sensor_pressure_a.lag`` (and ``sensor_position.resolution``) with the catalogue entry
of its kind. The kind follows the signal's unit (``SENSOR_KINDS``: a position sensor
in m, a pressure sensor in Pa), since an entry carries one unit and one range; its
entries are those of the single-chamber actuator's sensor of that quantity. That actuator
places no instance: its sensors (``DEFAULT_SENSORS``) keep their names
(``position_offset``, ``pressure_lag``, ...). ``sample_rate`` is the bench's, one for all.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from ..core.component import instance_entry
from ..errors import ParameterError
from ..parameters.catalogue import ParameterSpec, declare, declare_instances, declare_kind
from .actuator import CHAMBER_PRESSURE

__all__ = ["DEFAULT_SENSORS", "SENSOR_KINDS", "SENSOR_PARAMETERS", "Sensor", "SensorNames",
           "Sensors", "declare_sensors", "first_order_lag", "lag_derivative",
           "sensor_instance", "sensor_names"]

P = ParameterSpec
_SPECS = (
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
SENSOR_PARAMETERS = declare(*_SPECS)


class SensorNames(NamedTuple):
    """The parameters of one signal's sensor: its offset, lag and resolution (None: a
    sensor without one)."""

    offset: str
    lag: str
    resolution: str | None


#: the single-chamber actuator's sensors, its default instances: each signal's sensor
#: parameters, named as they always were
DEFAULT_SENSORS: Mapping[str, SensorNames] = MappingProxyType({
    "position": SensorNames("position_offset", "position_lag", "position_resolution"),
    CHAMBER_PRESSURE: SensorNames("pressure_offset", "pressure_lag", None)})
#: the sensor kind of a signal, by the signal's unit (an entry carries one unit and range)
SENSOR_KINDS = MappingProxyType({"m": "position_sensor", "Pa": "pressure_sensor"})


def _kind_entries(quantity: str) -> tuple[ParameterSpec, ...]:
    """A sensor kind's entries (local names offset, lag, resolution): those of the
    single-chamber actuator's sensor of ``quantity`` (position, pressure), its units and
    ranges."""
    by_name = {spec.name: spec for spec in _SPECS}
    return tuple(replace(by_name[name], name=local) for local, name in zip(
        SensorNames._fields, DEFAULT_SENSORS[quantity], strict=True) if name is not None)


#: each sensor kind's local parameter names
_KIND_LOCALS = {kind: declare_kind(kind, *_kind_entries(quantity))
                for quantity, kind in (("position", SENSOR_KINDS["m"]),
                                       (CHAMBER_PRESSURE, SENSOR_KINDS["Pa"]))}


def sensor_instance(signal: str) -> str:
    """The instance name of ``signal``'s sensor: ``sensor_pressure_a``."""
    return f"sensor_{signal}"


def declare_sensors(**signals: str) -> Mapping[str, SensorNames]:
    """Place a sensor on each measured signal of a model (``pressure_a="Pa"``: the signal
    and its unit): the instance ``sensor_<signal>`` of the kind of its unit, whose
    parameters (``sensor_pressure_a.lag``) carry that kind's entries. Returns each
    signal's ``SensorNames``, the model's ``sensor_names``. Called at a model module's
    import, as ``declare_instances`` is."""
    placed = {}
    for signal, unit in signals.items():
        kind = SENSOR_KINDS.get(unit)
        if kind is None:
            raise RuntimeError(f"declare_sensors: {signal} in {unit!r}: no sensor kind of "
                               f"that unit; kinds by unit: {dict(SENSOR_KINDS)}")
        instance = sensor_instance(signal)
        declare_instances(kind, **{instance: f"the sensor of the signal {signal}"})
        has_resolution = "resolution" in _KIND_LOCALS[kind]
        placed[signal] = SensorNames(
            instance_entry(instance, "offset"), instance_entry(instance, "lag"),
            instance_entry(instance, "resolution") if has_resolution else None)
    return MappingProxyType(placed)


def sensor_names(model: object) -> Mapping[str, SensorNames]:
    """The sensors of ``model``'s measured signals: those it declares (``sensor_names``,
    its plant's for a closed loop), else the single-chamber actuator's defaults."""
    declared = getattr(model, "sensor_names", None)
    plant = getattr(model, "plant", None)
    if declared is None and plant is not None:
        return sensor_names(plant)
    return DEFAULT_SENSORS if declared is None else declared


def is_sensor_parameter(name: str) -> bool:
    """Whether ``name`` is a sensor's parameter (of the defaults, or of an instance named
    ``sensor_...``), of this model or not."""
    return name in SENSOR_PARAMETERS or (name.startswith("sensor_") and "." in name)


def refuse_foreign_sensors(names: Iterable[str], placed: Mapping[str, SensorNames],
                           what: str) -> None:
    """One ParameterError naming the sensor parameters among ``names`` that no sensor in
    ``placed`` has (an unknown instance, another model's sensors), and the allowed ones."""
    allowed = [n for sensor in placed.values() for n in sensor if n] + ["sample_rate"]
    foreign = [n for n in names if is_sensor_parameter(n) and n not in allowed]
    if foreign:
        raise ParameterError(f"{what}: {', '.join(repr(n) for n in foreign)} "
                             f"{'is' if len(foreign) == 1 else 'are'} no sensor parameter of "
                             f"this model; its sensors' parameters: {', '.join(allowed)}")


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
class Sensor:
    """One signal's sensor (SI, in the signal's unit): its offset, first-order lag [s] and
    resolution (0: none)."""

    offset: float = 0.0
    lag: float = 0.0
    resolution: float = 0.0


@dataclass(frozen=True)
class Sensors:
    """The bench's sensors (SI): offsets [m, Pa], first-order lags [s], the position
    resolution [m] (0: none) and the sample rate [Hz] (None: as recorded). The named
    fields are the single-chamber actuator's sensors; ``placed`` holds, by signal, the
    sensors of a model that declares its own (``declare_sensors``)."""

    position_offset: float = 0.0
    pressure_offset: float = 0.0
    position_lag: float = 0.0
    pressure_lag: float = 0.0
    position_resolution: float = 0.0
    sample_rate: float | None = None
    placed: Mapping[str, Sensor] = field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        checked = [(name, getattr(self, name))
                   for name in ("position_lag", "pressure_lag", "position_resolution")]
        checked += [(instance_entry(sensor_instance(signal), local), getattr(sensor, local))
                    for signal, sensor in self.placed.items()
                    for local in ("lag", "resolution")]
        for name, value in checked:
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"Sensors: {name} = {value}; must be a finite value "
                                     ">= 0")
        if self.sample_rate is not None and not self.sample_rate > 0:
            raise ParameterError(f"Sensors: sample_rate = {self.sample_rate}; must be > 0 Hz")

    @classmethod
    def from_params(cls, params: Mapping[str, float] | None,
                    names: Mapping[str, SensorNames] | None = None) -> Sensors:
        """The sensors a parameter set states (an ideal bench for what it leaves out):
        those ``names`` gives by signal (a model's ``sensor_names``; default: the
        single-chamber actuator's). A sensor parameter of no sensor there (an unknown
        instance, another model's names) is refused naming it and the allowed ones."""
        if params is None:
            return cls()
        placed = DEFAULT_SENSORS if names is None else names
        refuse_foreign_sensors(params.keys(), placed, "Sensors")
        if placed is DEFAULT_SENSORS:
            given = {n: float(params[n]) for n in SENSOR_PARAMETERS if n in params}
            return cls(**given)  # type: ignore[arg-type]  # the named fields, all floats
        rate = float(params["sample_rate"]) if "sample_rate" in params else None
        return cls(sample_rate=rate, placed=MappingProxyType({
            signal: Sensor(*(float(params[n]) if n is not None and n in params else 0.0
                             for n in sensor))
            for signal, sensor in placed.items()}))

    @classmethod
    def of(cls, model: object) -> Sensors:
        """The sensors ``model``'s parameter set states for its measured signals."""
        return cls.from_params(getattr(model, "params", None), sensor_names(model))

    def sensor(self, signal: str) -> Sensor:
        """``signal``'s sensor (an ideal one for a signal without one)."""
        if signal in self.placed:
            return self.placed[signal]
        names = DEFAULT_SENSORS.get(signal)
        if names is None:
            return Sensor()
        return Sensor(*(float(getattr(self, n)) if n else 0.0 for n in names))

    @property
    def ideal(self) -> bool:
        """No offset, lag or quantisation: the records are the states themselves."""
        return not any((self.position_offset, self.pressure_offset, self.position_lag,
                        self.pressure_lag, self.position_resolution,
                        *(v for sensor in self.placed.values()
                          for v in (sensor.offset, sensor.lag, sensor.resolution))))

    def lag(self, signal: str) -> float:
        """The lag [s] of ``signal``'s sensor (0 for a signal without one)."""
        return self.sensor(signal).lag

    def offset(self, signal: str) -> float:
        """The offset of ``signal``'s sensor (0 for a signal without one)."""
        return self.sensor(signal).offset

    def measure(self, time: np.ndarray, signal: str, values: np.ndarray,
                quantise: bool = True) -> np.ndarray:
        """What ``signal``'s sensor reads when the true signal is ``values``."""
        sensor = self.sensor(signal)
        out = first_order_lag(time, np.asarray(values, dtype=float) + sensor.offset,
                              sensor.lag)
        if quantise and sensor.resolution > 0:
            out = np.round(out / sensor.resolution) * sensor.resolution
        return out
