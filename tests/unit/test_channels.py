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


def test_an_input_declaration_states_a_name_a_record_signal_and_a_range():
    """A declaration without a record signal, or with an empty range, is refused naming
    the field and its value."""
    from pneumact.core.channels import InputChannel
    from pneumact.errors import ArgumentError

    with pytest.raises(ArgumentError, match=r"record_signals = \(\)"):
        InputChannel("command", "1", 0.0, 1.0)
    with pytest.raises(ArgumentError, match=r"low = 1\.0, high = 0\.0"):
        InputChannel("command", "1", 1.0, 0.0, record_signals=("command",))


def test_an_input_refusal_shows_the_values_in_its_display_unit():
    """A refusal names the experiment, the input and the span in the declared display
    unit, and the rule with the declared range there; inside, nothing is refused."""
    from pneumact.core.channels import InputChannel

    setpoint = InputChannel("position", "m", 0.0, 0.004, record_signals=("position_setpoint",),
                            label="set-point", rule="stroke {low:g} to {high:g} mm",
                            shown_in=("mm", 1e3))
    setpoint.check(0.0, 0.004, "exp")
    with pytest.raises(ExperimentError, match=r"^exp: its set-point spans 1 to 5 mm; "
                                              r"stroke 0 to 4 mm$"):
        setpoint.check(0.001, 0.005, "exp")
    assert setpoint.describe() == "'position' [m] in [0, 0.004]"
    assert setpoint.span == (0.0, 0.004) and setpoint.record_signal == "position_setpoint"


def test_a_layout_is_the_fixed_channels_then_the_extras_then_the_model_s_own():
    """``channel_layout``: CHANNELS first, the components' extras in order, the model's
    own last; CH_<NAME> constants only where an index moves (none for the fixed
    channels, nor for a loop's own after them)."""
    from pneumact.core.channels import (
        LOOP_CHANNELS,
        LOOP_OWN,
        channel_layout,
        layout_constants,
    )

    assert channel_layout() == CHANNELS
    assert channel_layout(own=LOOP_OWN) == LOOP_CHANNELS
    assert layout_constants(CHANNELS) == [] and layout_constants(LOOP_CHANNELS) == []
    layout = channel_layout(("supply", "command_b"), LOOP_OWN)
    assert layout == (*CHANNELS, "supply", "command_b", *LOOP_OWN)
    assert layout_constants(layout) == [("CH_SUPPLY", 5), ("CH_COMMAND_B", 6),
                                        ("CH_SETPOINT", 7), ("CH_FEEDFORWARD", 8),
                                        ("CH_DISTURBANCE", 9)]
    assert in_order({"supply": Constant(1.0)}, layout)[5] is not None


@pytest.mark.parametrize(("extras", "message"), [
    (("supply", "supply"), r"channels \['supply'\] are declared twice"),
    (("drive",), r"channels \['drive'\] are declared twice"),
    (("supply pressure",), r"channel 'supply pressure': a channel's name must be a name"),
], ids=["twice", "a-fixed-one", "not-a-name"])
def test_a_layout_refuses_a_channel_twice_or_a_name_that_is_none(extras, message):
    from pneumact.core.channels import channel_layout
    from pneumact.errors import ArgumentError

    with pytest.raises(ArgumentError, match=message):
        channel_layout(extras)


def test_an_input_may_ride_on_an_extra_channel_but_not_on_a_non_name():
    """An input names any channel (a model's extra: checked against its layout when it
    is routed); a channel that cannot be a name is refused naming it."""
    from pneumact.core.channels import InputChannel
    from pneumact.errors import ArgumentError

    assert InputChannel("supply", "Pa", 1e5, 1e7, record_signals=("supply",),
                        channel="supply").channel == "supply"
    with pytest.raises(ArgumentError, match=r"channel = 'supply-a': must be a channel's name"):
        InputChannel("supply", "Pa", 1e5, 1e7, record_signals=("supply",), channel="supply-a")
