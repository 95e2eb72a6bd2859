"""What a controlled plant's input is, and which values it takes (shared by the closed
loop and the linearisation). Both are asked of the plant itself (the model protocol:
``plant_kind``, ``drive_quantity``, ``input_range``)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping

from ..core.signals import Constant
from ..errors import ExperimentError, ParameterError
from ..models.cylinder import SPOOL_INPUT
from ..models.rig import DRIVE_INPUTS
from ..models.valves import COMMAND_INPUT, PRESSURE_INPUT

__all__ = ["CONTROLLABLE", "held_inputs", "input_kind", "input_range"]

#: the plant inputs a position controller can act on, with their units (as the
#: components that own them declare them: a rig's force, a valve's, the 5/3 valve's)
CONTROLLABLE = {channel.name: channel.unit for channel in (
    DRIVE_INPUTS["force"], PRESSURE_INPUT, COMMAND_INPUT, SPOOL_INPUT)}
ALLOWED = ("an Actuator, a Cylinder, or a FrictionRig with drive='force' (a kinematic "
           "drive has no input to act on); a Cylinder fed by its 5/3 valve (one input, the "
           "spool command; two 3/2 valves take two, unless mirrored=True drives both by "
           "it)")


def input_kind(plant, who: str) -> str:
    """``force`` (a rig's force drive), ``command`` or ``pressure`` (an actuator's valve),
    ``spool`` (a cylinder's 5/3 valve); one ParameterError, naming ``who`` asks, for any
    other plant (a closed loop, a kinematic drive)."""
    from ..simulation.simulate import Model

    if not isinstance(plant, Model):
        raise ParameterError(f"{who}: plant = {type(plant).__name__}; allowed: {ALLOWED}")
    kind = plant.plant_kind
    if kind not in CONTROLLABLE or plant.drive_quantity != kind:
        raise ParameterError(f"{who}: plant = {plant.describe()}; allowed: {ALLOWED}")
    return kind


def input_range(plant) -> tuple[float, float]:
    """The input values the plant accepts: a command in [0, 1], a spool command in
    [−1, 1], a regulator's set-point in [p_res, p_atm] (it is clipped there), a pressure
    or force unbounded."""
    input_kind(plant, "input_range")
    return plant.input_range


def held_inputs(plant, inputs: Mapping[str, float] | None, who: str) -> dict[str, Constant]:
    """The plant's other declared inputs held at the constant values ``inputs`` gives
    (input name -> value in its SI unit: a cylinder's ``{"load": 500.0}`` [N]), as the
    ``drives`` of ``plant.channels``: the operating point of a linearisation or a holding
    input. One ExperimentError, naming ``who``, the input, the value and what is allowed,
    for a name the plant does not declare beside its drive (its drive is the input value)
    or a value outside the declared range."""
    if inputs is None:
        return {}
    if not isinstance(inputs, Mapping):
        raise ParameterError(f"{who}: inputs = {inputs!r}; give a dict of input name -> "
                             "constant value, e.g. {'load': 500.0} (N)")
    drive = plant.drive_input.name
    others = {channel.name: channel for channel in plant.inputs() if channel.name != drive}
    allowed = ", ".join(channel.describe() for channel in others.values()) or "none"
    held: dict[str, Constant] = {}
    for name, value in inputs.items():
        channel = others.get(name)
        if channel is None:
            its_drive = (f" ({name!r} is its drive, the input value)"
                         if name == plant.drive_quantity else "")
            raise ExperimentError(f"{who}: inputs = {{{name!r}: {value!r}}}; "
                                  f"{plant.describe()} declares no input {name!r} beside "
                                  f"its drive{its_drive}; allowed: {allowed}")
        if not (isinstance(value, numbers.Real) and not isinstance(value, bool)
                and math.isfinite(value) and channel.accepts(value, value)):
            raise ExperimentError(f"{who}: inputs = {{{name!r}: {value!r}}} {channel.unit}; "
                                  f"allowed for the {channel.label or name} of this plant: a "
                                  f"finite number in [{channel.low:g}, {channel.high:g}] "
                                  f"{channel.unit}")
        held[name] = Constant(float(value))
    return held
