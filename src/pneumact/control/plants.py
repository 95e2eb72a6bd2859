"""What a controlled plant's input is, and which values it takes (shared by the closed
loop and the linearisation). Both are asked of the plant itself (the model protocol:
``plant_kind``, ``drive_quantity``, ``input_range``)."""

from __future__ import annotations

from ..errors import ParameterError
from ..models.cylinder import SPOOL_INPUT
from ..models.rig import DRIVE_INPUTS
from ..models.valves import COMMAND_INPUT, PRESSURE_INPUT

__all__ = ["CONTROLLABLE", "input_kind", "input_range"]

#: the plant inputs a position controller can act on, with their units (as the
#: components that own them declare them: a rig's force, a valve's, the 5/3 valve's)
CONTROLLABLE = {channel.name: channel.unit for channel in (
    DRIVE_INPUTS["force"], PRESSURE_INPUT, COMMAND_INPUT, SPOOL_INPUT)}
ALLOWED = ("an Actuator, a Cylinder, or a FrictionRig with drive='force' (a kinematic "
           "drive has no input to act on)")


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
