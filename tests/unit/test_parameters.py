"""Unit tests of pneumact.parameters: shipped sets, unit parsing, validation, warnings."""

from __future__ import annotations

import math
import pickle
import warnings
from pathlib import Path

import numpy as np
import pytest

from pneumact.errors import ParameterError, PassivityWarning, PlausibilityWarning
from pneumact.io.quantities import SI_PREFIXES, si_prefix_factor
from pneumact.parameters import (
    ParameterSet,
    available_params,
    catalogue,
    load_params,
    params_to_toml,
    parse_value,
    row_problems,
    unit_registry,
    write_params,
)
from reference import SHIPPED_VALUE_RTOL, UNIT_CONVERSION_RTOL

# Paper Table I (+ eq. 8) in SI, and the assumed values documented in vgt-paper.toml.
VGT_PAPER = {
    "m": 0.63,
    "F0": 32.68,
    "k": 12850.0,
    "sigma2": 4.0,
    "Fs": 3.2,
    "Fc": 2.6,
    "sigma0": 1e5,
    "sigma1": 214.0,
    "vs": 0.0005,
    "V0": 60e-6,
    "A_d": 2.92246e-3,
    "p_atm": 1e5,
    "delta": 1.0,
    "gamma": 1.4,
    "R": 287.0,
    "T": 293.15,
    "x_max": 0.020,
    "p_res": 10e3,
    "A_res": 1.5e-6,
    "A_atm": 1.5e-6,
}
CANUDAS_1995 = {
    "sigma0": 1e5,
    "sigma1": math.sqrt(1e5),
    "sigma2": 0.4,
    "Fc": 1.0,
    "Fs": 1.5,
    "vs": 0.001,
    "delta": 2.0,
    "m": 1.0,
    "k_drive": 2.0,
    "v_drive": 0.1,
}
PASSIVE_LUGRE = {"sigma0": 1e5, "sigma1": 0.5, "sigma2": 0.4, "Fc": 1.0, "Fs": 1.5}
NON_PASSIVE_LUGRE = {**PASSIVE_LUGRE, "sigma1": 2.0}  # < 4*sigma2*Fc/(Fs-Fc) = 3.2 still


def _load_quietly(name_or_path: str | Path) -> ParameterSet:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        return load_params(name_or_path)


def _write(tmp_path: Path, body: str, name: str = "bad.toml") -> Path:
    path = tmp_path / name
    path.write_text(body, encoding="utf-8")
    return path


def _toml(**values: str) -> str:
    """A small valid LuGre set, with entries overridden or added as TOML value strings."""
    entries = {
        "m": '"0.63 kg"',
        "sigma0": '"1e5 N/m"',
        "sigma1": '"0.5 N*s/m"',
        "sigma2": '"0.4 N*s/m"',
        "Fc": '"1 N"',
        "Fs": '"1.5 N"',
        "vs": '"1 mm/s"',
        **values,
    }
    lines = [f'{k} = {{ value = {v}, source = "test" }}' for k, v in entries.items()]
    return 'name = "test"\ndescription = "test set"\n[parameters]\n' + "\n".join(lines) + "\n"


# ------------------------------------------------------------------ shipped sets


@pytest.mark.parametrize(
    ("name", "expected"), [("vgt-paper", VGT_PAPER), ("canudas1995", CANUDAS_1995)]
)
def test_shipped_set_loads_in_si(name: str, expected: dict[str, float]) -> None:
    ps = _load_quietly(name)
    assert ps.name == name
    assert set(ps) == set(expected)
    for key, value in expected.items():
        assert ps[key] == pytest.approx(value, rel=SHIPPED_VALUE_RTOL), key
    assert ps.source_path is not None and ps.source_path.name == f"{name}.toml"
    assert ps.provenance["source"]


def test_vgt_paper_units_and_provenance() -> None:
    ps = _load_quietly("vgt-paper")
    assert ps["V0"] == 6e-5  # "60 cm^3", exact after conversion
    assert ps.info["V0"].given == "60 cm^3"
    assert ps.info["m"].source == "paper Table I"
    assert ps.info["delta"].source == "paper eq. 8"
    for assumed in ("gamma", "R", "T", "x_max", "p_res", "A_res", "A_atm"):
        assert ps.info[assumed].source == "assumed"
        assert ps.info[assumed].note
    # the documented quick checks: 15.6 mm at 20 kPa, chamber volume stays positive
    x_20kpa = ((ps["p_atm"] - 20e3) * ps["A_d"] - ps["F0"]) / ps["k"]
    assert 15.5e-3 < x_20kpa < 15.7e-3 < ps["x_max"]
    assert ps["V0"] > ps["A_d"] * ps["x_max"]


def test_canudas_has_no_actuator_parameters() -> None:
    ps = _load_quietly("canudas1995")
    assert not {"A_d", "V0", "p_atm", "x_max", "A_res", "A_atm"} & set(ps)


def test_available_params_lists_shipped_sets() -> None:
    names = dict(available_params())
    assert {"vgt-paper", "canudas1995"} <= set(names)
    assert all(names.values())
    for name in names:  # the file's name field agrees with the file name
        assert _load_quietly(name).name == name


def test_same_value_in_other_units_loads_equal(tmp_path: Path) -> None:
    a = _load_quietly(_write(tmp_path, _toml(V0='"60 cm^3"', T='"20 degC"'), "a.toml"))
    b = _load_quietly(_write(tmp_path, _toml(V0='"6e-5 m^3"', T='"293.15 K"'), "b.toml"))
    assert a["V0"] == b["V0"] == 6e-5
    assert a["T"] == pytest.approx(b["T"], rel=UNIT_CONVERSION_RTOL)
    assert a.info["V0"].given == "60 cm^3"


def test_unknown_set_name_lists_available() -> None:
    with pytest.raises(ParameterError) as err:
        load_params("vgt-papr")
    msg = str(err.value)
    assert "vgt-papr" in msg and "vgt-paper" in msg and "canudas1995" in msg


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="not found"):
        load_params(tmp_path / "nope.toml")


# ------------------------------------------------------------------ bad files


@pytest.mark.parametrize(
    ("entry", "must_contain"),
    [
        ({"Fss": '"1.5 N"'}, ["Fss", "did you mean 'Fs'"]),  # misspelled name
        ({"V0": '"60 blorps"'}, ["V0", "60 blorps", "unknown unit 'blorps'"]),
        ({"V0": '"60 cm"'}, ["V0", "60 cm", "centimeter", "volume", "m^3"]),  # wrong dimension
        ({"V0": "6e-5"}, ["V0", "6e-05", "no unit"]),  # bare number for a dimensional value
        ({"delta": '"2 m"'}, ["delta", "2 m", "dimensionless"]),
    ],
)
def test_bad_entry_in_file(tmp_path: Path, entry: dict[str, str], must_contain: list[str]) -> None:
    path = _write(tmp_path, _toml(**entry))
    with pytest.raises(ParameterError) as err:
        load_params(path)
    for text in must_contain:
        assert text in str(err.value)


def test_misspelled_name_message_format(tmp_path: Path) -> None:
    path = _write(tmp_path, _toml(Fss='"1.5 N"'), "vgt-paper.toml")
    with pytest.raises(ParameterError) as err:
        load_params(path)
    assert "unknown parameter 'Fss' in vgt-paper.toml (did you mean 'Fs'?)" in str(err.value)


@pytest.mark.parametrize(
    ("entry", "must_contain"),
    [
        ({"Fs": '"0.5 N"'}, ["Fs = 0.5 N", "Fc = 1 N"]),  # Fs < Fc
        ({"m": '"-1 kg"'}, ["m = -1 kg: must be >= 1e-09 kg"]),  # negative mass
        ({"p_atm": '"100 kPa"', "p_res": '"100 kPa"'}, ["p_res = 100000 Pa", "p_atm"]),
        ({"bw_gamma": '"0.8"'}, ["bw_gamma = 0.8", "[-0.5, 0.5]"]),
        (
            {"V0": '"50 cm^3"', "A_d": '"29.2246 cm^2"', "x_max": '"20 mm"'},
            ["V0 = 5e-05 m^3", "A_d*x_max"],
        ),
    ],
)
def test_inconsistent_file(tmp_path: Path, entry: dict[str, str], must_contain: list[str]) -> None:
    path = _write(tmp_path, _toml(**entry))
    with pytest.raises(ParameterError) as err:
        load_params(path)
    for text in must_contain:
        assert text in str(err.value)


def test_all_problems_reported_at_once(tmp_path: Path) -> None:
    path = _write(tmp_path, _toml(m='"-1 kg"', Fs='"0.5 N"', vs='"nan m/s"'))
    with pytest.raises(ParameterError) as err:
        load_params(path)
    lines = str(err.value).splitlines()
    assert len(lines) == 4  # header + one line per problem
    assert any("m = -1 kg" in line for line in lines)
    assert any("Fs = 0.5 N" in line for line in lines)
    assert any("vs = nan m/s" in line and "finite" in line for line in lines)


def test_malformed_toml(tmp_path: Path) -> None:
    path = _write(tmp_path, 'name = "x"\n[parameters]\nm = { value = "1 kg" \n')
    with pytest.raises(ParameterError) as err:
        load_params(path)
    assert "bad.toml" in str(err.value) and "line" in str(err.value)


def test_unknown_entry_key_and_missing_table(tmp_path: Path) -> None:
    path = _write(tmp_path, '[parameters]\nm = { value = "1 kg", sorce = "x" }\n')
    with pytest.raises(ParameterError, match="did you mean 'source'"):
        load_params(path)
    path = _write(tmp_path, 'name = "x"\n[paramters]\nm = "1 kg"\n')
    with pytest.raises(ParameterError, match="did you mean 'parameters'"):
        load_params(path)


# ------------------------------------------------------------------ the ParameterSet API


def test_mapping_over_given_values_with_default_fallback() -> None:
    ps = _load_quietly("canudas1995")
    assert "k_stop" not in ps and len(ps) == len(CANUDAS_1995)
    assert ps["k_stop"] == catalogue()["k_stop"].default  # default when read
    assert dict(ps.values) == dict(ps.items())
    with pytest.raises(ParameterError) as err:
        ps["A_d"]
    msg = str(err.value)
    assert "A_d" in msg and "canudas1995" in msg and "no default" in msg
    assert ps.get("A_d") is None


def test_require_lists_every_missing_name() -> None:
    ps = _load_quietly("canudas1995")
    ps.require(["m", "sigma0", "k_stop"], "LuGre rig")  # given or defaulted: fine
    with pytest.raises(ParameterError) as err:
        ps.require(["p_atm", "m", "V0", "A_d", "gamma"], "Actuator")
    assert "parameter set 'canudas1995' lacks A_d, p_atm, V0 needed by Actuator" in str(err.value)


def test_replace_validates_and_copies() -> None:
    ps = _load_quietly("vgt-paper")
    heavier = ps.replace(m=0.7, x_max="15 mm")
    assert heavier["m"] == 0.7 and heavier["x_max"] == 0.015
    assert ps["m"] == 0.63  # original unchanged
    assert heavier.info["m"].source == "replace()"
    with pytest.raises(ParameterError, match=r"m = -1 kg: must be >= 1e-09 kg"):
        ps.replace(m=-1.0)
    with pytest.raises(ParameterError, match=r"Fs = 2 N.*Fc"):
        ps.replace({"Fs": 2.0})
    with pytest.raises(ParameterError, match=r"unknown parameter 'Fss'.*did you mean 'Fs'"):
        ps.replace(Fss=3.0)


def test_a_unit_slip_by_a_thousand_is_refused_naming_it(tmp_path: Path) -> None:
    """12850 N/mm for a spring of 12850 N/m is legal (below k's hard limit) but can only
    be a slip: refused like kPa typed as Pa, naming the value meant; just outside the
    plausible range is only a warning."""
    ps = _load_quietly("vgt-paper")
    for call in (lambda: ps.replace(k="12850 N/mm"), lambda: ps.replace(k=1.285e7),
                 lambda: load_params(Path(__file__).parents[1] / "data" / "bad"
                                     / "k_in_n_per_mm.toml"),
                 lambda: ParameterSet.from_dict({"p_res": "50 Pa"})):
        with pytest.raises(ParameterError, match=r"unit slip by a factor 1000: did you mean"):
            call()
    with pytest.raises(ParameterError, match=r"k = 1\.285e\+07 N/m \(given as '12850 N/mm'\)"
                       r".*did you mean 12850 N/m\?"):
        ps.replace(k="12850 N/mm")
    with pytest.warns(PlausibilityWarning, match="outside the plausible range"):
        ps.replace(k=2e6)  # odd, but it could be meant: a warning
    assert ps.replace(k="12.85 kN/m")["k"] == 12850.0


def test_a_bom_is_read_and_other_formats_or_a_folder_are_named(tmp_path: Path) -> None:
    """A TOML file saved with a BOM (Windows editors) loads; JSON, YAML and a folder are
    refused naming what they are and what is expected."""
    shipped = Path(__file__).parents[2] / "src/pneumact/parameters/sets/vgt-paper.toml"
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + shipped.read_bytes())
    assert _load_quietly(bom).values == _load_quietly("vgt-paper").values
    for suffix, kind in ((".json", "is JSON"), (".yaml", "is YAML")):
        other = tmp_path / f"set{suffix}"
        other.write_text("k: 12850 N/m\n", encoding="utf-8")
        with pytest.raises(ParameterError, match=f"{kind}: parameter sets are TOML files"):
            load_params(other)
    with pytest.raises(ParameterError, match=r"is a folder; a parameter file .* is expected"):
        load_params(tmp_path)


def test_immutable_and_picklable() -> None:
    ps = _load_quietly("vgt-paper")
    with pytest.raises(AttributeError):
        ps.name = "other"  # type: ignore[misc]
    with pytest.raises(TypeError):
        ps.values["m"] = 1.0  # type: ignore[index]
    clone = pickle.loads(pickle.dumps(ps))
    assert clone == ps and clone.info == ps.info and clone.name == ps.name


def test_from_dict_numbers_are_si_strings_have_units() -> None:
    ps = ParameterSet.from_dict({"m": 0.63, "V0": "60 cm^3", "x_max": "2 cm"}, name="mine")
    assert ps.name == "mine"
    assert ps["m"] == 0.63 and ps["V0"] == 6e-5 and ps["x_max"] == 0.02
    with pytest.raises(ParameterError, match="m = -1 kg"):
        ParameterSet.from_dict({"m": -1.0})


def test_toml_round_trip_keeps_values_sources_and_adds_provenance(tmp_path: Path) -> None:
    ps = _load_quietly("vgt-paper").replace(Fc=2.5123456789012345)
    path = write_params(ps, tmp_path / "identified.toml", {"identified": "stage (b), test"})
    back = _load_quietly(path)
    assert dict(back.values) == dict(ps.values)  # bit for bit
    assert back.info["m"].source == "paper Table I"
    assert back.provenance["identified"] == "stage (b), test"
    assert "identified" in params_to_toml(ps, {"identified": "x"})


def test_shipped_sets_name_their_source_not_a_machine_path() -> None:
    for name, _ in available_params():
        text = (Path(load_params.__code__.co_filename).parent / "sets" / f"{name}.toml"
                ).read_text(encoding="utf-8")
        assert "/work/" not in text and "shared/" not in text, name


def test_every_parameter_is_declared_by_a_component_module() -> None:
    specs = catalogue()
    for name in ("sigma0", "Fc", "A_d", "V0", "reg_kp", "k_drive", "c_stop", "bw_n"):
        assert name in specs
    assert specs["c_stop"].unit == "N*s/m^2"  # Hunt-Crossley damping on the penetration


@pytest.mark.parametrize("unit", ["m", "m^2", "m^3", "Pa", "N", "s"])
@pytest.mark.parametrize("prefix", sorted(SI_PREFIXES))
def test_si_prefix_fast_path_equals_pint(unit: str, prefix: str) -> None:
    ureg = unit_registry()
    base, _, power = unit.partition("^")
    text = f"{prefix}{base}" + (f"^{power}" if power else "")
    pint_text = text.replace("µ", "u").replace("μ", "u")
    expected = float(ureg.Quantity(3.7, ureg.parse_units(pint_text)).to(unit).magnitude)
    assert si_prefix_factor(text, unit) is not None
    assert parse_value("x", f"3.7 {text}", unit) == pytest.approx(expected,
                                                                   rel=UNIT_CONVERSION_RTOL)


def test_units_pint_must_convert_are_not_taken_by_the_fast_path() -> None:
    assert si_prefix_factor("bar", "Pa") is None
    assert si_prefix_factor("kN*s/m", "N*s/m") is None
    assert si_prefix_factor("g", "kg") is None
    assert parse_value("p_atm", "1 bar", "Pa") == pytest.approx(1e5, rel=UNIT_CONVERSION_RTOL)


def test_row_problems_check_ranges_and_relations_by_column() -> None:
    base = dict(_load_quietly("vgt-paper").values)
    values = np.array([[2.0, 3.0], [2.0, 1.0], [-1.0, 3.0], [np.nan, 3.0]])
    found = row_problems(base, ("Fc", "Fs"), values)
    assert found[0] is None
    assert "Fs = 1 N: must be >= Fc = 2 N" in found[1]
    assert "Fc = -1 N: must be >= 0 N" in found[2]
    assert "Fc = nan N: must be a finite number" in found[3]


def test_to_frame() -> None:
    ps = _load_quietly("canudas1995")
    frame = ps.to_pandas()
    assert list(frame.columns) == ["name", "value", "unit", "given", "source", "description"]
    given = frame.iloc[: len(ps)]
    assert set(given["name"]) == set(ps)
    assert (frame.iloc[len(ps) :]["source"] == "default").all()
    row = frame.set_index("name").loc["sigma1"]
    assert row["unit"] == "N*s/m" and row["given"] == "316.227766 N*s/m"


# ------------------------------------------------------------------ passivity warning


def test_passivity_warning_fires_when_condition_broken() -> None:
    with pytest.warns(PassivityWarning) as record:
        ParameterSet.from_dict(NON_PASSIVE_LUGRE, name="loose")
    assert len(record) == 1
    msg = str(record[0].message)
    assert "sigma1 = 2" in msg and "sigma2*Fc/(Fs - Fc)" in msg and "0.8" in msg


def test_no_passivity_warning_when_condition_holds() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", PassivityWarning)
        ps = ParameterSet.from_dict(PASSIVE_LUGRE, name="tight")
        ps.replace(sigma1=0.8)  # on the boundary: still passive


def test_shipped_sets_warn_once_per_load() -> None:
    for name in ("vgt-paper", "canudas1995"):
        with warnings.catch_warnings(record=True) as record:
            warnings.simplefilter("always")
            ps = load_params(name)
        assert [w.category for w in record] == [PassivityWarning]
        # already warned: changing an unrelated value does not warn again
        with warnings.catch_warnings():
            warnings.simplefilter("error", PassivityWarning)
            ps.replace(m=2.0)
