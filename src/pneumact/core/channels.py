"""Signal channels handed to every kernel, in this order (``experiments.pack_channels``).

A model fills the channels it uses and leaves the others empty: the experiment's drive
(pressure, command, set-point, force, velocity or position), the external loads of the
actuator against time and against position, and the valve's normalised area maps
against the command u. A closed loop adds its position set-point, a feed-forward
signal added to the controller output and a force disturbance on a rig's mass; its
plant's drive channel then holds one value, the controller's output, which the loop
writes at ``INPUT_OFFSET`` past the channel's start.

Models name their channels (``in_order``); only the packing puts them in this order.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..errors import ExperimentError

#: a model's channels, in order
CHANNELS = ("drive", "load_t", "load_x", "map_res", "map_atm")
#: a closed loop's: its plant's, then its own
LOOP_CHANNELS = (*CHANNELS, "setpoint", "feedforward", "disturbance")
CH_DRIVE = LOOP_CHANNELS.index("drive")
CH_LOAD_T = LOOP_CHANNELS.index("load_t")
CH_LOAD_X = LOOP_CHANNELS.index("load_x")
CH_MAP_RES = LOOP_CHANNELS.index("map_res")
CH_MAP_ATM = LOOP_CHANNELS.index("map_atm")
CH_SETPOINT = LOOP_CHANNELS.index("setpoint")
CH_FEEDFORWARD = LOOP_CHANNELS.index("feedforward")
CH_DISTURBANCE = LOOP_CHANNELS.index("disturbance")
N_CHANNELS = len(CHANNELS)
N_LOOP_CHANNELS = len(LOOP_CHANNELS)
#: [n_terms = 1, kind = PWL, n = 1, t0, value]: where a one-point channel holds its value
INPUT_OFFSET = 4


def in_order(named: Mapping[str, Any], names: tuple[str, ...] = CHANNELS) -> list[Any]:
    """The signals of ``named`` (channel name → signal or None) in the declared order of
    ``names``, for ``experiments.pack_channels``; a name left out is an empty channel."""
    unknown = sorted(set(named) - set(names))
    if unknown:
        raise ExperimentError(f"channels {unknown}: not among the declared {list(names)}")
    return [named.get(name) for name in names]
