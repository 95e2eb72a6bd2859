"""Parameter sets as files: the shipped TOML sets, user TOML files, and writing them back.

In a parameter file every dimensional value is a string with its unit ("60 cm^3",
"4 N*s/m"); a bare number is accepted only for a dimensionless parameter. A unit-less
number in a file is the classic way to be off by 1e6, so it is refused with a message
showing the fix. Each value may carry its ``source`` and a ``note``. A component
instance's parameters are dotted keys (``chamber_a.V_dead = ...``) or its table
(``[parameters.chamber_a]``), both read as ``chamber_a.V_dead``.
"""

from __future__ import annotations

import difflib
import os
import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any, TypeAlias

from pneumact.core.component import instance_entry
from pneumact.errors import ArgumentTypeError, ParameterError
from pneumact.io.quantities import parse_value
from pneumact.parameters.catalogue import catalogue
from pneumact.parameters.parameter_set import ParameterInfo, ParameterSet
from pneumact.parameters.validation import (
    check_plausibility,
    message,
    unknown_name,
    warn_passivity,
)

__all__ = ["ParameterSetLike", "as_parameter_set", "available_params", "load_params",
           "params_to_toml", "write_params"]

#: what takes the place of a parameter set in a call: the set, a shipped set's name or the
#: path of a .toml file (``as_parameter_set`` turns it into the set)
ParameterSetLike: TypeAlias = ParameterSet | str | os.PathLike[str]

_TOP_KEYS = ("name", "description", "provenance", "parameters")
_ENTRY_KEYS = ("value", "source", "note")


def _sets_dir() -> Any:
    return resources.files("pneumact.parameters").joinpath("sets")


def _shipped() -> dict[str, Any]:
    """Shipped set name (file stem) -> resource."""
    found = {}
    for entry in _sets_dir().iterdir():
        if entry.name.endswith(".toml") and entry.is_file():
            found[entry.name[: -len(".toml")]] = entry
    return dict(sorted(found.items()))


def _read_toml(data: bytes, label: str) -> dict[str, Any]:
    try:
        return tomllib.loads(data.decode("utf-8-sig"))  # a BOM (Windows editors) skipped
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"cannot parse parameter file {label}: {exc}") from None


def _header(doc: dict[str, Any], file_name: str, default_name: str, found: list[str]):
    """(name, description, provenance) of a parameter document, problems into ``found``."""
    for key in doc:
        if key not in _TOP_KEYS:
            found.append(unknown_name(key, file_name, _TOP_KEYS, what="key"))
    name = doc.get("name", default_name)
    description = doc.get("description", "")
    provenance = doc.get("provenance", {})
    if not isinstance(name, str) or not name:
        found.append(f"name = {name!r}: must be a non-empty string")
        name = default_name
    if not isinstance(description, str):
        found.append(f"description = {description!r}: must be a string")
        description = ""
    if not isinstance(provenance, dict) or not all(isinstance(v, str)
                                                   for v in provenance.values()):
        found.append('[provenance]: must be a table of strings (source = "...", ...)')
        provenance = {}
    return name, description, provenance


def _entries(table: dict[str, Any], file_name: str, found: list[str]
             ) -> tuple[dict[str, float], dict[str, ParameterInfo]]:
    specs = catalogue()
    values: dict[str, float] = {}
    info: dict[str, ParameterInfo] = {}
    for pname, entry in _flattened(table, specs).items():
        if pname not in specs:
            found.append(unknown_name(pname, file_name))
            continue
        source, note = "", ""
        if isinstance(entry, dict):
            for key in (k for k in entry if k not in _ENTRY_KEYS):
                found.append(unknown_name(key, f"parameter '{pname}'", _ENTRY_KEYS, what="key"))
            if "value" not in entry:
                found.append(f"parameter '{pname}': missing value = \"...\"")
                continue
            raw, source, note = entry["value"], entry.get("source", ""), entry.get("note", "")
            if not isinstance(source, str) or not isinstance(note, str):
                found.append(f"parameter '{pname}': source and note must be strings")
                continue
        else:
            raw = entry  # shorthand: m = "0.63 kg"
        try:
            values[pname] = parse_value(pname, raw, specs[pname].unit, bare_number_is_si=False)
        except ParameterError as exc:
            found.append(str(exc))
            continue
        info[pname] = ParameterInfo(raw if isinstance(raw, str) else repr(raw), source, note)
    return values, info


def _flattened(table: dict[str, Any], specs: Mapping[str, Any]) -> dict[str, Any]:
    """``table`` with each instance's table (``[parameters.chamber_a]``, or the dotted
    keys ``chamber_a.V_dead = ...``, which TOML reads as one) as entries
    ``chamber_a.V_dead``: a key that is no parameter and holds a table of no entry's
    keys."""
    flat: dict[str, Any] = {}
    for key, entry in table.items():
        if (key not in specs and isinstance(entry, dict)
                and not any(k in _ENTRY_KEYS for k in entry)):
            flat.update({instance_entry(key, local): e for local, e in entry.items()})
        else:
            flat[key] = entry
    return flat


def _from_document(doc: dict[str, Any], label: str, default_name: str,
                   source_path: Path | None) -> ParameterSet:
    file_name = Path(label).name
    found: list[str] = []
    name, description, provenance = _header(doc, file_name, default_name, found)
    table = doc.get("parameters")
    if not isinstance(table, dict):
        found.append('missing [parameters] table: write e.g. m = { value = "0.63 kg", '
                     'source = "...", note = "..." }')
        table = {}
    values, info = _entries(table, file_name, found)
    if found:
        raise ParameterError(message(f"cannot load parameter file {label}", found))
    return ParameterSet(values, name=name, description=description, provenance=provenance,
                        info=info, source_path=source_path)


def _looks_like_path(text: str) -> bool:
    seps = [s for s in (os.sep, os.altsep, "/") if s]
    return text.endswith(".toml") or any(s in text for s in seps)


#: formats a parameter file is sometimes written in, which pneumact does not read
_OTHER_FORMATS = {".json": "JSON", ".yaml": "YAML", ".yml": "YAML", ".csv": "CSV",
                  ".xlsx": "an Excel workbook"}


def _refuse_not_a_file(path: Path) -> None:
    """A folder, or a file in another format than TOML, named for what it is."""
    if path.is_dir():
        inside = sorted(p.name for p in path.glob("*.toml"))
        hint = f" (it holds {', '.join(inside[:3])})" if inside else ""
        raise ParameterError(f"'{path}' is a folder; a parameter file (.toml) is expected"
                             f"{hint}")
    kind = _OTHER_FORMATS.get(path.suffix.lower())
    if kind is not None and path.is_file():
        raise ParameterError(
            f"parameter file '{path}' is {kind}: parameter sets are TOML files, one value "
            'with its unit per line under [parameters], e.g. k = { value = "12850 N/m", '
            'source = "datasheet" } (pneumact params show vgt-paper shows a whole set)')


def _load(name_or_path: str | os.PathLike[str]) -> ParameterSet:
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or _looks_like_path(text) or text not in _shipped():
        _refuse_not_a_file(Path(name_or_path))  # a shipped name wins over a folder of it
    if not isinstance(name_or_path, Path) and not _looks_like_path(str(name_or_path)):
        shipped = _shipped()
        resource = shipped.get(str(name_or_path))
        if resource is not None:
            doc = _read_toml(resource.read_bytes(), f"{name_or_path}.toml")
            path = Path(str(resource)) if isinstance(resource, Path) else None
            return _from_document(doc, f"{name_or_path}.toml", str(name_or_path), path)
        if not Path(str(name_or_path)).is_file():
            text = str(name_or_path)
            close = difflib.get_close_matches(text, list(shipped), n=1, cutoff=0.6)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise ParameterError(f"unknown parameter set '{text}'{hint}; available: "
                                 f"{', '.join(shipped)} (or give a path to a .toml file)")
    path = Path(name_or_path)
    if not path.is_file():
        raise ParameterError(f"parameter file '{path}' not found")
    doc = _read_toml(path.read_bytes(), str(path))
    return _from_document(doc, str(path), path.stem, path.resolve())


def load_params(name_or_path: str | os.PathLike[str]) -> ParameterSet:
    """Load a shipped set by name ("vgt-paper") or a TOML file by path, in SI, validated.

    Raises ParameterError for an unknown set, a malformed file, an unknown parameter, a
    bad unit, an impossible value or an inconsistent set; warns (PlausibilityWarning)
    about a legal value outside the range real actuators have (often a unit typed
    wrong), and (PassivityWarning, once per process) if the LuGre parameters break the
    passivity condition. A ParameterSet is returned as it is.
    """
    if isinstance(name_or_path, ParameterSet):
        return name_or_path
    if not isinstance(name_or_path, (str, os.PathLike)) or isinstance(name_or_path, bytes):
        raise ArgumentTypeError(
            f"load_params: name_or_path = {name_or_path!r}: must be a shipped set name "
            f"({', '.join(_shipped())}) or the path of a .toml file, not "
            f"{type(name_or_path).__name__}")
    ps = _load(name_or_path)
    check_plausibility(ps.values, ps.name, stacklevel=2,
                       given={n: i.given for n, i in ps.info.items()},
                       source=ps.source_path)
    warn_passivity(ps.values, ps.name, stacklevel=2)
    return ps


def as_parameter_set(value, where: str) -> ParameterSet:
    """A ParameterSet from what a function was given: a set as it is, a shipped set's
    name or a .toml path loaded (``Actuator("vgt-paper")`` reads as
    ``Actuator(load_params("vgt-paper"))``); anything else is refused, naming the type."""
    if isinstance(value, ParameterSet):
        return value
    if isinstance(value, (str, os.PathLike)) and not isinstance(value, bytes):
        return load_params(value)
    hint = (" (from a dict: ParameterSet.from_dict(values))"
            if isinstance(value, Mapping) else "")
    raise ArgumentTypeError(f"{where}: params = {value!r:.60}: must be a ParameterSet, "
                            "e.g. pa.load_params('vgt-paper'), or a set name or .toml path, "
                            f"not {type(value).__name__}{hint}")


def available_params() -> list[tuple[str, str]]:
    """(name, description) of every parameter set shipped with pneumact."""
    result = []
    for name, resource in _shipped().items():
        doc = _read_toml(resource.read_bytes(), f"{name}.toml")
        description = doc.get("description", "")
        result.append((name, description if isinstance(description, str) else ""))
    return result


def _toml_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def params_to_toml(params: ParameterSet, provenance: Mapping[str, str] | None = None) -> str:
    """The text of a parameter file that ``load_params`` reads back to the same values.

    Values are written in SI with their unit (``repr`` of the float, so nothing is lost);
    each keeps its source and note. ``provenance`` adds to (or replaces entries of) the
    set's own provenance table.
    """
    specs = catalogue()
    lines = [f"name = {_toml_string(params.name)}",
             f"description = {_toml_string(params.description)}", "", "[provenance]"]
    for key, text in {**params.provenance, **dict(provenance or {})}.items():
        lines.append(f"{key} = {_toml_string(text)}")
    lines += ["", "[parameters]"]
    for name, value in params.values.items():
        unit = specs[name].unit
        text = f"{value!r} {unit}".rstrip() if unit else repr(value)
        info = params.info[name]
        lines.append(f"{name} = {{ value = {_toml_string(text)}, source = "
                     f"{_toml_string(info.source)}, note = {_toml_string(info.note)} }}")
    return "\n".join(lines) + "\n"


def write_params(params: ParameterSet, path: str | os.PathLike[str],
                 provenance: Mapping[str, str] | None = None) -> Path:
    """Write ``params`` as a TOML parameter file, atomically; returns the path."""
    from pneumact.io.tables import atomic_write

    target = Path(path)
    with atomic_write(target) as tmp:
        tmp.write_text(params_to_toml(params, provenance), encoding="utf-8")
    return target
