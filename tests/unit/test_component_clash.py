"""The model assembly refuses two components that claim one role or bind one kernel name
(issue 41, item 1): the kernel would otherwise take the last one's silently."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

import pneumact as pa
from pneumact.core.assembly import Assembly
from pneumact.core.component import Block, Part, StateSpec


@dataclass(frozen=True, eq=False)
class _Parts:
    """A model that is only its components (the check runs before the template is read)."""

    components: tuple[Part, ...]
    template = "pneumact.models.actuator_template"

    def parts(self) -> tuple[Part, ...]:
        return self.components


def _part(role: str, label: str, functions=None, constants=None) -> Part:
    return Part(role=role, block=Block.of(f"{label}_value"),
                states=(StateSpec(f"{label}_state", "1"),), functions=functions or {},
                constants=constants or {}, label=label)


def test_two_components_with_one_role_are_refused_naming_both():
    model = _Parts((_part("valve", "first valve"), _part("mechanics", "diaphragm"),
                    _part("valve", "second valve")))
    with pytest.raises(pa.ComponentError,
                       match=r"'first valve' and 'second valve' both claim the role 'valve'"):
        Assembly(model)


def test_two_components_binding_one_function_name_are_refused_naming_both():
    first = _part("valve", "command valve", functions={"valve_rates": "m:command_rates"})
    second = _part("extra", "iso valve", functions={"valve_rates": "m:iso_rates"})
    with pytest.raises(pa.ComponentError,
                       match=r"'command valve' and 'iso valve' both claim the kernel "
                             r"function 'valve_rates'"):
        Assembly(_Parts((first, second)))


def test_a_constant_and_a_function_of_one_name_clash_too():
    first = _part("valve", "valve", constants={"VALVE_PRESSURE_STATE": "m:STATE"})
    second = _part("other", "other", functions={"VALVE_PRESSURE_STATE": "m:f"})
    with pytest.raises(pa.ComponentError, match=r"'valve' and 'other' both claim the kernel "
                                                r"function 'VALVE_PRESSURE_STATE'"):
        Assembly(_Parts((first, second)))


def test_a_component_without_a_label_is_named_by_its_role():
    with pytest.raises(pa.ComponentError, match=r"'valve' and 'valve' both claim the role"):
        Assembly(_Parts((Part(role="valve", block=Block()), Part(role="valve", block=Block()))))


def test_distinct_components_assemble(vgt):
    """The shipped models have no clash (their layout is what the components declare)."""
    for valve in (pa.PressureSource(), pa.CommandValve(), pa.PressureRegulator()):
        assembly = Assembly(pa.Actuator(vgt, valve=valve))
        assert [part.role for part in assembly.parts] == ["mechanics", "friction", "valve"]
    first = _part("valve", "a", functions={"valve_rates": "m:a"})
    second = _part("other", "b", functions={"other_rates": "m:b"})
    assert len(Assembly(_Parts((first, second))).parts) == 2
