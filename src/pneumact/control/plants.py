"""What a controlled plant's input is, and which values it takes (shared by the closed
loop and the linearisation)."""

from __future__ import annotations

import math

from ..errors import ParameterError
from ..models.actuator import Actuator
from ..models.rig import FrictionRig

__all__ = ["input_kind", "input_range"]


def input_kind(plant, who: str) -> str:
    """``force`` (a rig's force drive), ``command`` or ``pressure`` (an actuator's valve);
    one ParameterError, naming ``who`` asks, for any other plant."""
    if isinstance(plant, FrictionRig):
        if plant.drive != "force":
            raise ParameterError(f"{who}: plant = FrictionRig(drive={plant.drive!r}); "
                                 "allowed: an Actuator, or a FrictionRig with drive='force' "
                                 "(a kinematic drive has no input to act on)")
        return "force"
    if isinstance(plant, Actuator):
        return plant.plant_kind
    raise ParameterError(f"{who}: plant = {type(plant).__name__}; allowed: Actuator, "
                         "FrictionRig(drive='force')")


def input_range(plant) -> tuple[float, float]:
    """The input values the plant accepts: a command in [0, 1], a regulator's set-point
    in [p_res, p_atm] (it is clipped there), a pressure or force unbounded."""
    kind = input_kind(plant, "input_range")
    if kind == "command":
        return 0.0, 1.0
    if kind == "pressure":
        from ..models.valves import PressureRegulator

        if isinstance(plant.valve, PressureRegulator):
            return float(plant.params["p_res"]), float(plant.params["p_atm"])
        return 0.0, math.inf
    return -math.inf, math.inf
