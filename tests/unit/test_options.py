"""The option objects (``pneumact.options``) and the model protocol (issue 20, item 4).

Option objects are frozen, check themselves with one message naming the field, the value
and what is allowed, and a plain value that means one thing stands for one. Every model
declares what the simulation asks of it (``simulation.Model``): no attribute probes.
"""

from __future__ import annotations

import dataclasses

import pytest

import pneumact as pa
from pneumact.errors import ArgumentError, ArgumentTypeError


@pytest.mark.parametrize(("cls", "value", "expected"), [
    (pa.Executor, 4, pa.Executor(workers=4)),
    (pa.Executor, "tcp://127.0.0.1:8786", pa.Executor(scheduler="tcp://127.0.0.1:8786")),
    (pa.Executor, None, pa.Executor()),
    (pa.Checkpoint, "runs", pa.Checkpoint("runs")),
    (pa.Multistart, 4, pa.Multistart(starts=4)),
    (pa.Profile, ["sigma0"], pa.Profile(names=("sigma0",))),
    (pa.Profile, "sigma0", pa.Profile(names=("sigma0",))),
    (pa.Offsets, ["position"], pa.Offsets(signals=("position",))),
    (pa.Optimizer, "soft_l1", pa.Optimizer(loss="soft_l1")),
    (pa.Bounds, {"Fc": (1.0, 5.0)}, pa.Bounds(ranges={"Fc": (1.0, 5.0)})),
    (pa.Weights, {"position": 2.0}, pa.Weights(signals={"position": 2.0})),
])
def test_a_plain_value_stands_for_its_option_object(cls, value, expected):
    made = cls.of(value)
    assert made == expected
    assert cls.of(made) is made  # an object passes through


def test_option_objects_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        pa.Multistart(2).starts = 3  # type: ignore[misc]


@pytest.mark.parametrize(("make", "words"), [
    (lambda: pa.Executor(workers=0), ("Executor", "workers = 0", ">= 1")),
    (lambda: pa.Executor(scheduler="nowhere"), ("scheduler", "'nowhere'", "tcp://")),
    (lambda: pa.Checkpoint("x", resume=True, overwrite=True), ("resume", "overwrite")),
    (lambda: pa.Multistart(-1), ("starts = -1", ">= 0")),
    (lambda: pa.Multistart(2, seed=-1), ("seed = -1",)),
    (lambda: pa.Profile(["Fc"], points=2), ("points = 2", ">= 3")),
    (lambda: pa.Optimizer(loss="l3"), ("loss = 'l3'", "soft_l1")),
    (lambda: pa.Optimizer(f_scale=0.0), ("f_scale",)),
    (lambda: pa.Optimizer(jacobian="exact"), ("jacobian = 'exact'", "2-point")),
    (lambda: pa.Bounds({"Fc": (5.0, 1.0)}), ("Fc", "low < high")),
    (lambda: pa.Weights(records=[1.0, -1.0]), ("records[1]",)),
    (lambda: pa.Offsets(["position"], records=[-2]), ("records[0] = -2",)),
    (lambda: pa.Multistart.of("4"), ("multistart = '4'", "Multistart(...)",
                                     "a number of starts")),
])
def test_a_bad_option_is_one_message_naming_field_value_and_allowed(make, words):
    with pytest.raises((ArgumentError, ArgumentTypeError)) as caught:
        make()
    for word in words:
        assert word in str(caught.value), (word, str(caught.value))


def _models():
    from conftest import load_quietly
    from pneumact.control import PID, ClosedLoop

    params = load_quietly("vgt-paper")
    rig = pa.FrictionRig(load_quietly("canudas1995"), drive="force")
    return {
        "source": pa.Actuator(params, valve=pa.PressureSource()),
        "command": pa.Actuator(params, valve=pa.CommandValve()),
        "regulator": pa.Actuator(params, valve=pa.PressureRegulator()),
        "rig": rig,
        "loop": ClosedLoop(rig, PID(kp=3.0)),
    }


@pytest.mark.parametrize(("name", "input_signal", "plant_kind", "stroke"), [
    ("source", "pressure", "pressure", True), ("command", "command", "command", True),
    ("regulator", "setpoint", "pressure", True), ("rig", "force", "force", False),
    ("loop", "position_setpoint", "force", False)])
def test_every_model_declares_the_protocol(name, input_signal, plant_kind, stroke):
    from pneumact.simulation.simulate import Model

    model = _models()[name]
    assert isinstance(model, Model)
    assert model.input_signal == input_signal  # what fit and validate read from a record
    assert model.plant_kind == plant_kind
    assert (model.stroke is not None) is stroke
    assert model.input_signal in model.input_signals
    assert model.driven_by(model.input_signal) is model


def test_an_actuator_is_driven_by_each_record_signal_behind_its_valve():
    actuator = _models()["source"]
    assert actuator.input_signals == ("setpoint", "pressure", "command")
    for signal, valve in (("setpoint", pa.PressureRegulator), ("command", pa.CommandValve)):
        driven = actuator.driven_by(signal)
        assert isinstance(driven.valve, valve) and driven.input_signal == signal


def test_what_is_not_a_model_is_refused():
    from pneumact.simulation.simulate import check_model

    with pytest.raises(ArgumentTypeError, match="must be a model"):
        check_model(object())
