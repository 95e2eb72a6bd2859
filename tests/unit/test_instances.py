"""Components with instances (issue 41, item 1): a component placed twice in one model
under instance names has its parameters named by instance (``chamber_a.V_dead``), each with
the catalogue entry of its kind; unknown instances, unknown kind parameters and renamed
names are refused in one message naming the value and what is allowed. No kernel is
compiled here."""

from __future__ import annotations

import dataclasses
import re

import pytest

import pneumact as pa
from conftest import load_quietly
from pneumact import sensitivity as sa
from pneumact import simulation  # noqa: F401 - registers the catalogue's explanations
from pneumact.core.assembly import Assembly
from pneumact.core.component import Block, Part, required_parameters
from pneumact.models.cylinder import CHAMBER_BLOCK, CYLINDER_BLOCK
from pneumact.parameters import load_params, params_to_toml
from pneumact.parameters.catalogue import catalogue

DEAD = ("chamber_a.V_dead", "chamber_b.V_dead")


@dataclasses.dataclass(frozen=True, eq=False)
class _Parts:
    """A model that is only its components (the assembly's layout needs no kernel)."""

    components: tuple[Part, ...]
    template = "pneumact.models.actuator_template"

    def parts(self) -> tuple[Part, ...]:
        return self.components


def _two_chambers(second: str = "chamber_b") -> tuple[Part, ...]:
    body = Part(role="body", block=Block.of("m", settings=("n_setting",)),
                settings={"n_setting": 1.0})
    return (body, Part(role="chamber", instance="chamber_a", block=CHAMBER_BLOCK, label="A"),
            Part(role="chamber", instance=second, block=CHAMBER_BLOCK, label="B"))


def test_an_instance_s_parameter_has_its_kind_s_catalogue_entry():
    """chamber_a.V_dead and chamber_b.V_dead: the kind's unit, ranges and meaning (the
    instance's description added); the kind's local name alone is no parameter."""
    specs = catalogue()
    kind = specs["chamber_a.V_dead"]
    for name in DEAD:
        spec = specs[name]
        assert spec.name == name and spec.unit == "m^3" and spec.group == "cylinder"
        assert (spec.minimum, spec.strict_minimum, spec.maximum, spec.plausible) == (
            kind.minimum, kind.strict_minimum, kind.maximum, kind.plausible)
        assert spec.description.startswith("dead volume of a cylinder chamber")
    assert "cap side" in specs["chamber_a.V_dead"].description
    assert "rod side" in specs["chamber_b.V_dead"].description
    assert "V_dead" not in specs


def test_the_assembly_names_an_instance_s_entries_by_instance():
    """Two placements of one chamber block: slots chamber_a.V_dead and chamber_b.V_dead,
    blocks (and their kernel constants) named by instance, settings still filled."""
    model = _Parts(_two_chambers())
    assembly = Assembly(model)
    assert assembly.parameter_names == ("m", *DEAD)
    assert assembly.block_ranges == {"body": (0, 2), "chamber_a": (2, 3),
                                     "chamber_b": (3, 4)}
    constants = dict(assembly.kernel_spec().constants)
    assert (constants["CHAMBER_A_LO"], constants["CHAMBER_B_LO"]) == (2, 3)
    assert required_parameters(model.parts()) == ("m", *DEAD)


def test_one_instance_name_placed_twice_is_refused_naming_both():
    with pytest.raises(pa.ComponentError, match=r"components 'A' and 'B' both claim the "
                                                r"instance 'chamber_a'"):
        Assembly(_Parts(_two_chambers(second="chamber_a")))


@pytest.mark.parametrize("instance", ["chamber-a", "chamber.a", "1chamber"])
def test_an_instance_name_that_is_no_identifier_is_refused(instance):
    with pytest.raises(pa.ComponentError, match=rf"Part\(role='chamber'\): instance = "
                                                rf"'{re.escape(instance)}': must be a name "
                                                rf"of letters, digits and underscores"):
        Part(role="chamber", instance=instance, block=CHAMBER_BLOCK)


def test_the_cylinder_places_its_chambers_as_instances(cylinder_set):
    """The cylinder's chambers are two instances of one chamber block; no per-chamber
    parameter is left in the cylinder's own block."""
    cylinder = pa.Cylinder(cylinder_set)
    chambers = [part for part in cylinder.parts() if part.role == "chamber"]
    assert [part.instance for part in chambers] == ["chamber_a", "chamber_b"]
    assert all(part.block is CHAMBER_BLOCK for part in chambers)
    assert not any("dead" in name for name in CYLINDER_BLOCK.parameters)
    assert set(DEAD) <= set(cylinder.required)


def test_the_single_chamber_actuator_keeps_its_names(vgt):
    names = Assembly(pa.Actuator(vgt, valve=pa.CommandValve())).parameter_names
    assert {"V0", "A_d", "m", "sigma0"} <= set(names)
    assert not any("." in name for name in names)


@pytest.mark.parametrize(("name", "words"), [
    ("V_dead_a", "unknown parameter 'V_dead_a' in replace() on parameter set "
                 "'iso15552-32': renamed: use 'chamber_a.V_dead'"),
    ("V_dead_b", "renamed: use 'chamber_b.V_dead'"),
    ("chamber_c.V_dead", "unknown parameter 'chamber_c.V_dead' in replace() on parameter "
                         "set 'iso15552-32': no component instance 'chamber_c'; instances: "
                         "chamber_a, chamber_b"),
    ("chamber_a.V0", "'V0' is no parameter of chamber_a, a chamber; a chamber's "
                     "parameters: V_dead"),
])
def test_unknown_instances_and_old_names_are_refused_saying_what_is_allowed(
        name, words, cylinder_set):
    with pytest.raises(pa.ParameterError) as error:
        cylinder_set.replace({name: 1e-6})
    assert words in str(error.value)


def test_old_names_are_refused_by_studies_and_by_the_model(cylinder_set):
    """A study's variations name the new name; a fit's, a run's or a sensitivity's names
    (checked by the assembly) say it too, the catalogue's explanation beside the closest
    match, and list the model's parameters, the instances' among them."""
    with pytest.raises(pa.ParameterError, match=r"unknown parameter 'V_dead_a' in the "
                                                r"variations: renamed: use "
                                                r"'chamber_a.V_dead'"):
        sa.Problem.around(cylinder_set, {"V_dead_a": 0.05})
    with pytest.raises(pa.ParameterError, match=r"free: 'V_dead_a' is not a parameter of "
                                                r"Cylinder.*\(renamed: use "
                                                r"'chamber_a.V_dead'\).*chamber_a.V_dead, "
                                                r"chamber_b.V_dead"):
        Assembly(pa.Cylinder(cylinder_set)).check_parameters(["V_dead_a"], "free")
    with pytest.raises(pa.ParameterError, match=r"\(no component instance 'chamber_c'; "
                                                r"instances: chamber_a, chamber_b, valve_a, "
                                                r"valve_b, friction_piston, friction_rod, "
                                                r"sensor_position, sensor_pressure_a, "
                                                r"sensor_pressure_b; did you mean "
                                                r"'chamber_b.V_dead'\?\)"):
        Assembly(pa.Cylinder(cylinder_set)).check_parameters(["chamber_c.V_dead"], "free")


def test_set_files_give_an_instance_s_parameters_as_dotted_keys_or_a_table(
        tmp_path, cylinder_set):
    """``chamber_a.V_dead = ...`` and ``[parameters.chamber_a]`` read alike; a written set
    reads back to the same values."""
    written = tmp_path / "written.toml"
    written.write_text(params_to_toml(cylinder_set), encoding="utf-8")
    assert dict(load_params(written).values) == dict(cylinder_set.values)
    text = params_to_toml(cylinder_set.replace({"chamber_b.V_dead": 2e-5}))
    lines = [line for line in text.splitlines() if not line.startswith("chamber_")]
    lines += ["[parameters.chamber_a]", 'V_dead = { value = "8 cm^3" }',
              "[parameters.chamber_b]", 'V_dead = "20 cm^3"']
    table = tmp_path / "table.toml"
    table.write_text("\n".join(lines) + "\n", encoding="utf-8")
    loaded = load_params(table)
    assert (loaded["chamber_a.V_dead"], loaded["chamber_b.V_dead"]) == pytest.approx(
        (8e-6, 2e-5))


def test_a_set_file_with_an_unknown_instance_is_refused(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[parameters]\nchamber_x.V_dead = "8 cm^3"\n', encoding="utf-8")
    with pytest.raises(pa.ParameterError, match=r"unknown parameter 'chamber_x.V_dead' in "
                                                r"bad.toml: no component instance "
                                                r"'chamber_x'"):
        load_params(path)


@pytest.fixture(scope="module")
def cylinder_set():
    return load_quietly("iso15552-32")
