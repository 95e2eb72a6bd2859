"""Channels are declared by name (``core.channels``); models name theirs and only the
packing puts them in the declared order, which the kernels' CH_* constants index."""

from __future__ import annotations

import pytest

import pneumact as pa
from pneumact.core.channels import CH_DRIVE, CH_LOAD_T, CH_LOAD_X, CHANNELS, in_order
from pneumact.core.signals import Constant
from pneumact.errors import ExperimentError


def test_named_channels_are_put_in_the_declared_order():
    drive, atm = Constant(1.0), Constant(2.0)
    assert in_order({"map_atm": atm, "drive": drive}) == [drive, None, None, None, atm]


def test_an_undeclared_channel_is_refused_by_name():
    with pytest.raises(ExperimentError, match="'loads'"):
        in_order({"loads": Constant(1.0)})


def test_the_actuator_channels_sit_where_the_kernels_read_them(vgt):
    drive, load, load_map = Constant(0.5), Constant(3.0), Constant(4.0)
    actuator = pa.Actuator(vgt, valve=pa.CommandValve(), load=load, load_map=load_map)
    channels = actuator.channels(drive)
    assert len(channels) == len(CHANNELS)
    assert channels[CH_DRIVE] is drive
    assert channels[CH_LOAD_T] is load
    assert channels[CH_LOAD_X] is load_map
