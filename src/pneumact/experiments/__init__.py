"""Experiments: what is applied to the actuator, the cylinder or the friction rig, and for
how long."""

from ..core.signals import Constant, PiecewiseLinear, Ramp, Signal, Sine, Step, Triangle
from .actuator import (
    QUANTITIES,
    CommandCycle,
    Experiment,
    PressureCycle,
    SpoolStep,
    from_csv,
    from_record,
    from_samples,
)
from .setpoints import SetpointProfile, SetpointRamp, SetpointStep, SetpointTable

__all__ = [
    "QUANTITIES", "CommandCycle", "Constant", "Experiment", "PiecewiseLinear", "PressureCycle",
    "Ramp", "SetpointProfile", "SetpointRamp", "SetpointStep", "SetpointTable",
    "Signal", "Sine", "SpoolStep", "Step", "Triangle", "from_csv", "from_record",
    "from_samples",
]
