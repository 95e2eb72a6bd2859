"""The SI unit of each signal name pneumact knows, one table for every layer: records
convert their columns to it (``io``), figures label their axes from it (``plotting``),
results and tables carry it.

``drive_<name>`` is the signal a drive imposes on a rig (a force, a velocity, a
position, a spring end, a pressure or a valve command).
"""

from __future__ import annotations

__all__ = ["SIGNAL_UNITS", "signal_unit"]

#: Known signal names and their SI unit ("1": dimensionless).
SIGNAL_UNITS: dict[str, str] = {
    "time": "s",
    "pressure": "Pa",
    "pressure_gauge": "Pa",
    "setpoint": "Pa",  # a pressure regulator's set-point
    "position": "m",
    "position_setpoint": "m",  # a position controller's set-point
    "velocity": "m/s",
    "force": "N",
    "friction": "N",
    "command": "1",
    "spool": "1",  # a 5/3 valve's spool command, in [-1, 1]
    "command_a": "1",  # chamber A's 3/2 valve command, in [-1, 1] (a cylinder's input)
    "command_b": "1",  # chamber B's 3/2 valve command, in [-1, 1] (a cylinder's input)
    "load": "N",  # an external load force (a cylinder's input)
    "supply": "Pa",  # a 5/3 valve's supply pressure, absolute (a cylinder's input)
}

_DRIVE_UNITS: dict[str, str] = {"force": "N", "velocity": "m/s", "position": "m",
                                "spring": "m", "pressure": "Pa", "command": "1"}


def signal_unit(name: str) -> str:
    """The SI unit of the signal ``name``, or "" for a name pneumact does not know."""
    if name.startswith("drive_"):
        return _DRIVE_UNITS.get(name[len("drive_"):], "")
    return SIGNAL_UNITS.get(name, "")
