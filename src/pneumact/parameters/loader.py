"""Parameter sets as data: load TOML files, convert units to SI, validate, warn.

A parameter set holds only the values its source gives, converted to SI floats, with the
original text, source and note of each. Defaults live in the catalogue (``spec.py``) and
are filled in when a value is read (``ps["delta"]``) or the kernel vector is built.

Units policy:

* In a TOML file every dimensional value is a string with its unit ("60 cm^3",
  "4 N*s/m", "100 kPa", "20 degC"); a bare TOML number is accepted only for a
  dimensionless parameter (``delta = { value = 1 }``). A unit-less number in a file is
  the classic way to be off by 1e6, so it is refused with a message showing the fix.
* In Python (``ParameterSet.from_dict``, ``ParameterSet.replace``, the constructor) the
  API speaks SI: numbers are SI values, strings are parsed with their units.

Unit strings are parsed by one lazily created pint ``UnitRegistry`` (``unit_registry()``):
importing pint and building a registry costs a few hundred ms, so nothing here touches
pint until a string value has to be converted.
"""

from __future__ import annotations

import difflib
import math
import os
import re
import threading
import tomllib
import warnings
from collections.abc import Iterable, Iterator, Mapping, ValuesView
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np

from pneumact.errors import ParameterError, PassivityWarning
from pneumact.parameters.spec import (
    I_POLYTROPIC,
    PARAMETERS,
    SPECS,
    VECTOR_LENGTH,
)

if TYPE_CHECKING:
    import pandas as pd
    import pint

__all__ = [
    "ParameterInfo",
    "ParameterSet",
    "available_params",
    "load_params",
    "lugre_passivity_problem",
    "parse_value",
    "unit_registry",
    "validate",
]

# --------------------------------------------------------------------------- units

_REGISTRY: pint.UnitRegistry | None = None
_REGISTRY_LOCK = threading.Lock()


def unit_registry() -> pint.UnitRegistry:
    """The package's single pint registry, created on first use (pint is slow to load)."""
    global _REGISTRY
    if _REGISTRY is None:
        with _REGISTRY_LOCK:
            if _REGISTRY is None:
                import pint

                _REGISTRY = pint.UnitRegistry()
    return _REGISTRY


# What each SI unit of the catalogue measures, for "which is not a volume [m^3]".
_KIND: dict[str, str] = {
    "kg": "a mass",
    "m": "a length",
    "m^2": "an area",
    "m^3": "a volume",
    "N": "a force",
    "Pa": "a pressure",
    "m/s": "a velocity",
    "N/m": "a stiffness",
    "N*s/m": "a damping coefficient",
    "s": "a time",
    "K": "a temperature",
    "J/(kg*K)": "a specific gas constant",
}

_NUMBER_THEN_UNIT = re.compile(
    r"\s*([+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|nan|inf(?:inity)?))\s*(.*?)\s*",
    re.IGNORECASE,
)


def _kind(unit: str) -> str:
    return _KIND.get(unit, f"convertible to {unit}")


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )


def _fmt(name: str, value: float) -> str:
    """'m = -1 kg' style rendering of an SI value, for messages."""
    unit = SPECS[name].unit if name in SPECS else ""
    return f"{name} = {value:g} {unit}".rstrip()


def parse_value(name: str, value: float | str, *, bare_number_is_si: bool = True) -> float:
    """Convert one given value of parameter ``name`` to its SI float.

    Strings carry a unit ("60 cm^3"); numbers are SI when ``bare_number_is_si`` (the
    Python API), otherwise (TOML files) only dimensionless parameters may be bare numbers.
    Raises ParameterError naming the parameter, the value and what is allowed.
    """
    spec = SPECS.get(name)
    if spec is None:
        _fail(_unknown_name(name, ""))
    if isinstance(value, str):
        return _parse_string(name, value)
    if not _is_number(value):
        example = f"'1 {spec.unit}'" if spec.unit else "1.4"
        _fail(
            f"parameter '{name}' = {value!r}: must be a number or a string with a unit, "
            f"e.g. {example}"
        )
    if spec.unit and not bare_number_is_si:
        _fail(
            f"parameter '{name}' = {value!r} has no unit; {_kind(spec.unit)} needs one: "
            f'write "{value} {spec.unit}"'
        )
    return float(value)


def _fail(message: str) -> NoReturn:
    raise ParameterError(message)


def _parse_string(name: str, text: str) -> float:
    spec = SPECS[name]
    example = f"'1 {spec.unit}'" if spec.unit else "'1.4'"
    match = _NUMBER_THEN_UNIT.fullmatch(text)
    if match is None:
        _fail(
            f"parameter '{name}' = '{text}': expected a number followed by a unit, e.g. {example}"
        )
    magnitude = float(match.group(1))
    unit_text = match.group(2)
    if not unit_text:
        if spec.unit:
            _fail(
                f"parameter '{name}' = '{text}' has no unit; {_kind(spec.unit)} needs one: "
                f"write '{match.group(1)} {spec.unit}'"
            )
        return magnitude
    ureg = unit_registry()
    import pint

    try:
        units = ureg.parse_units(unit_text)
    except pint.UndefinedUnitError as exc:
        names = exc.unit_names if isinstance(exc.unit_names, str) else ", ".join(exc.unit_names)
        _fail(f"parameter '{name}' = '{text}': unknown unit '{names}'")
    except Exception:  # pint raises assorted errors (Assertion, Token, Value) on bad syntax
        _fail(
            f"parameter '{name}' = '{text}': cannot read unit '{unit_text}', "
            f"expected something like {example}"
        )
    quantity = ureg.Quantity(magnitude, units)
    target = spec.unit or "dimensionless"
    if quantity.dimensionality != ureg.parse_units(target).dimensionality:
        what = "dimensionless" if not spec.unit else f"{_kind(spec.unit)} [{spec.unit}]"
        _fail(f"parameter '{name}' = '{text}' has unit {units}, which is not {what}")
    si = float(quantity.to(target).magnitude)
    if units != ureg.parse_units(target) and math.isfinite(si):
        # "60 cm^3" -> 6.000000000000001e-05: drop the conversion's last-bit noise so the
        # same value written in different units loads to the same float.
        si = float(f"{si:.15g}")
    return si


# --------------------------------------------------------------------------- names


def _unknown_name(
    name: str, where: str, known: Iterable[str] | None = None, what: str = "parameter"
) -> str:
    """'unknown parameter 'Fss' in vgt-paper.toml (did you mean 'Fs'?)'."""
    candidates = list(SPECS if known is None else known)
    lowered = {c.lower(): c for c in candidates}
    guess = lowered.get(name.lower())
    if guess is None:
        close = difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)
        guess = lowered[close[0]] if close else None
    text = f"unknown {what} '{name}'" + (f" in {where}" if where else "")
    if guess is not None:
        return f"{text} (did you mean '{guess}'?)"
    return f"{text} (known: {', '.join(candidates)})"


# --------------------------------------------------------------------------- validation


def _range_problem(name: str, value: float, shown: str) -> str | None:
    spec = SPECS[name]
    lo, hi, strict = spec.minimum, spec.maximum, spec.strict_minimum
    below = lo is not None and (value <= lo if strict else value < lo)
    above = hi is not None and value > hi
    if not (below or above):
        return None
    if lo is not None and hi is not None:
        allowed = f"must be in {'(' if strict else '['}{lo:g}, {hi:g}]"
    elif lo is not None:
        allowed = f"must be {'>' if strict else '>='} {lo:g}"
    else:
        allowed = f"must be <= {hi:g}"
    return f"{shown}: {allowed}"


def _problems(
    values: Mapping[str, Any], where: str, given: Mapping[str, str] | None = None
) -> list[str]:
    """Every problem of a set of given SI values, one line each (empty list: valid).

    ``given`` (name -> original text) adds "(given as '-300 degC')" where a unit was
    converted, so the user recognises the value they wrote.
    """
    problems: list[str] = []
    usable: dict[str, float] = {}

    def fmt(name: str, value: float) -> str:
        shown = _fmt(name, value)
        text = (given or {}).get(name)
        if text is not None:
            match = _NUMBER_THEN_UNIT.fullmatch(text)
            if match is None or match.group(2) != SPECS[name].unit:
                shown += f" (given as '{text}')"
        return shown

    for name, value in values.items():
        if name not in SPECS:
            problems.append(_unknown_name(name, where))
        elif not _is_number(value):
            problems.append(f"{name} = {value!r}: must be a number (SI value)")
        elif not math.isfinite(value):
            problems.append(f"{fmt(name, float(value))}: must be a finite number")
        else:
            problem = _range_problem(name, float(value), fmt(name, float(value)))
            if problem:
                problems.append(problem)
            else:
                usable[name] = float(value)

    def get(name: str) -> float | None:
        # Relations use what a model would use: the given value, else the default. A
        # value that already failed above is left out so it is reported only once.
        if name in values:
            return usable.get(name)
        return SPECS[name].default

    fs, fc = get("Fs"), get("Fc")
    if fs is not None and fc is not None and fs < fc:
        problems.append(
            f"{fmt('Fs', fs)}: must be >= Fc = {fc:g} N "
            "(static friction is at least the Coulomb friction)"
        )
    p_res, p_atm = get("p_res"), get("p_atm")
    if p_res is not None and p_atm is not None and p_res >= p_atm:
        problems.append(
            f"{fmt('p_res', p_res)}: must be < p_atm = {p_atm:g} Pa "
            "(the vacuum reservoir is below atmospheric pressure)"
        )
    beta, gamma = get("bw_beta"), get("bw_gamma")
    if beta is not None and gamma is not None and abs(gamma) > beta:
        problems.append(
            f"{fmt('bw_gamma', gamma)}: must be within [-bw_beta, bw_beta] = [{-beta:g}, {beta:g}]"
        )
    v0, a_d, x_max = get("V0"), get("A_d"), get("x_max")
    if v0 is not None and a_d is not None and x_max is not None and v0 <= a_d * x_max:
        problems.append(
            f"{fmt('V0', v0)}: must be > A_d*x_max = {a_d * x_max:g} m^3 "
            "(the chamber volume V0 - A_d*x must stay positive over the stroke)"
        )
    return problems


def _message(header: str, problems: list[str]) -> str:
    if len(problems) == 1:
        return f"{header}: {problems[0]}"
    return f"{header} ({len(problems)} problems):\n  " + "\n  ".join(problems)


def validate(values: Mapping[str, float], set_name: str) -> None:
    """Check given SI values: names, finiteness, catalogue ranges, physical relations.

    Collects every problem and raises one ParameterError with one line per problem
    (field, value, what is allowed). Relations (Fs >= Fc, p_res < p_atm,
    |bw_gamma| <= bw_beta, V0 > A_d*x_max) are checked only when their parameters have a
    value (given, or a catalogue default).
    """
    problems = _problems(values, f"parameter set '{set_name}'")
    if problems:
        raise ParameterError(_message(f"invalid parameter set '{set_name}'", problems))


# --------------------------------------------------------------------------- passivity
#
# Passivity of the LuGre map v -> F_f (Barabanov & Ortega 2000, "Necessary and sufficient
# conditions for passivity of the LuGre friction model", IEEE TAC 45(4), 830-832; restated
# as eq. (7) in Astrom & Canudas de Wit 2008, "Revisiting the LuGre friction model", IEEE
# Control Systems Magazine 28(6)):
#
#     sigma1 <= sigma2 * Fc / (Fs - Fc)        (equivalently sigma2 >= sigma1*(Fs - Fc)/Fc)
#
# Checked here, not only quoted. With y = sigma0*z, w = sgn(v)*y and the storage
# S = y^2/(2*sigma0):  F*v - dS/dt = |v|*w^2/g + v^2*(sigma1 + sigma2 - sigma1*w/g).
# Since |y| <= Fs (invariant set) and g >= Fc, the bracket is >= sigma2 - sigma1*(Fs-Fc)/Fc,
# so the condition is sufficient. It is also necessary: from y = Fs (stuck at break-away),
# a jump to a large speed V (g = Fc) gives F = Fs + V*(sigma2 - sigma1*(Fs - Fc)/Fc), whose
# power is negative and unbounded in V when the condition fails. A numerical check of this
# case confirmed it, and showed that the weaker "sigma1 < 4*sigma2*Fc/(Fs - Fc)" sometimes
# quoted is NOT sufficient (sigma1 = 2, sigma2 = 0.4, Fc = 1, Fs = 1.5 generates energy).
#
# Typical identified sets (the paper's, Canudas de Wit's) break it: sigma1 is chosen for
# presliding damping, not passivity. That is a warning, not an error.

_PASSIVITY_SOURCE = "Barabanov & Ortega 2000, IEEE TAC 45(4); Astrom & Canudas de Wit 2008, eq. 7"


def lugre_passivity_problem(values: Mapping[str, float]) -> str | None:
    """Describe how a LuGre parameter set breaks passivity, or None if it does not.

    Needs sigma0, Fc and Fs given; sigma1 and sigma2 fall back to their defaults (0),
    which is what the LuGre model would use.
    """
    if not all(name in values for name in ("sigma0", "Fc", "Fs")):
        return None
    s1 = float(values.get("sigma1", SPECS["sigma1"].default or 0.0))
    s2 = float(values.get("sigma2", SPECS["sigma2"].default or 0.0))
    fc, fs = float(values["Fc"]), float(values["Fs"])
    if fs <= fc:
        return None  # no Stribeck drop: passive for any sigma1 >= 0
    bound = s2 * fc / (fs - fc)
    if s1 <= bound * (1.0 + 1e-12):
        return None
    return (
        f"sigma1 = {s1:g} N*s/m breaks the LuGre passivity condition "
        f"sigma1 <= sigma2*Fc/(Fs - Fc) = {s2:g}*{fc:g}/({fs:g} - {fc:g}) = {bound:.4g} N*s/m "
        f"({_PASSIVITY_SOURCE}): the friction model can deliver net energy at fast slip "
        "onsets"
    )


def _warn_passivity(ps: ParameterSet, stacklevel: int) -> None:
    problem = lugre_passivity_problem(ps._values)
    if problem:
        warnings.warn(
            f"parameter set '{ps.name}': {problem}", PassivityWarning, stacklevel=stacklevel + 1
        )


# --------------------------------------------------------------------------- the set


@dataclass(frozen=True)
class ParameterInfo:
    """Where a given value came from: original text (e.g. "60 cm^3"), source, note."""

    given: str
    source: str
    note: str = ""


class _GivenValues(Mapping[str, float]):
    """Read-only view of the given SI values; also callable, so ``ps.values()`` still
    behaves as ``Mapping.values()`` for code that treats a ParameterSet as a Mapping."""

    __slots__ = ("_data",)

    def __init__(self, data: dict[str, float]) -> None:
        self._data = data

    def __getitem__(self, key: str) -> float:
        return self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __call__(self) -> ValuesView[float]:
        return ValuesView(self)

    def __repr__(self) -> str:
        return repr(self._data)


def _number_text(name: str, value: float) -> str:
    return f"{float(value)!r} {SPECS[name].unit}".rstrip()


def _restore(
    name: str,
    description: str,
    provenance: dict[str, str],
    values: dict[str, float],
    info: dict[str, ParameterInfo],
    source_path: Path | None,
) -> ParameterSet:
    """Unpickle without re-validating or warning (the set was valid when pickled)."""
    ps = object.__new__(ParameterSet)
    ps._init(name, description, provenance, values, info, source_path)
    return ps


class ParameterSet(Mapping[str, float]):
    """An immutable, validated parameter set in SI units.

    As a Mapping it holds the GIVEN values only (``len``, iteration, ``in``), but
    ``ps[name]`` falls back to the catalogue default and raises ParameterError (also a
    KeyError) when there is neither. ``info[name]`` tells where a given value came from.
    The constructor takes SI numbers and validates them; it does not warn about
    passivity (``load_params``, ``from_dict`` and ``replace`` do).
    """

    __slots__ = (
        "_description",
        "_info",
        "_info_view",
        "_name",
        "_provenance",
        "_source_path",
        "_values",
        "_values_view",
    )

    def __init__(
        self,
        values: Mapping[str, float],
        *,
        name: str = "custom",
        description: str = "",
        provenance: Mapping[str, str] | None = None,
        info: Mapping[str, ParameterInfo] | None = None,
        source_path: Path | None = None,
    ) -> None:
        given = {n: i.given for n, i in (info or {}).items()}
        problems = _problems(values, f"parameter set '{name}'", given)
        if problems:
            where = f" ({source_path})" if source_path is not None else ""
            raise ParameterError(_message(f"invalid parameter set '{name}'{where}", problems))
        ordered = {p.name: float(values[p.name]) for p in PARAMETERS if p.name in values}
        info = info or {}
        full_info = {
            n: info[n] if n in info else ParameterInfo(_number_text(n, v), "", "")
            for n, v in ordered.items()
        }
        self._init(name, description, dict(provenance or {}), ordered, full_info, source_path)

    def _init(
        self,
        name: str,
        description: str,
        provenance: dict[str, str],
        values: dict[str, float],
        info: dict[str, ParameterInfo],
        source_path: Path | None,
    ) -> None:
        setter = object.__setattr__
        setter(self, "_name", str(name))
        setter(self, "_description", str(description))
        setter(self, "_provenance", {str(k): str(v) for k, v in provenance.items()})
        setter(self, "_values", values)
        setter(self, "_info", info)
        setter(self, "_source_path", source_path)
        setter(self, "_values_view", _GivenValues(values))
        setter(self, "_info_view", MappingProxyType(info))

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"ParameterSet is immutable; use replace() (tried to set {key})")

    def __delattr__(self, key: str) -> None:
        raise AttributeError(f"ParameterSet is immutable (tried to delete {key})")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (
            _restore,
            (
                self._name,
                self._description,
                dict(self._provenance),
                dict(self._values),
                dict(self._info),
                self._source_path,
            ),
        )

    # -- attributes
    @property
    def name(self) -> str:
        """Set name, e.g. 'vgt-paper'."""
        return self._name

    @property
    def description(self) -> str:
        """One-line description of the set."""
        return self._description

    @property
    def provenance(self) -> dict[str, str]:
        """Source and notes of the set as a whole (a copy)."""
        return dict(self._provenance)

    @property
    def source_path(self) -> Path | None:
        """The TOML file the set was read from, if any."""
        return self._source_path

    @property
    def values(self) -> _GivenValues:  # type: ignore[override]
        """Given values only, name -> SI float (read-only; ``values()`` also works)."""
        return self._values_view

    @property
    def info(self) -> Mapping[str, ParameterInfo]:
        """name -> ParameterInfo (original text, source, note) of each given value."""
        return self._info_view

    # -- Mapping over the given values
    def __getitem__(self, name: str) -> float:
        value = self._values.get(name)
        if value is not None:
            return value
        spec = SPECS.get(name)
        if spec is None:
            raise _MissingParameterError(_unknown_name(name, f"parameter set '{self._name}'"))
        if spec.default is None:
            raise _MissingParameterError(
                f"parameter '{name}' is not given in parameter set '{self._name}' "
                "and has no default"
            )
        return spec.default

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __contains__(self, name: object) -> bool:
        return name in self._values

    def __repr__(self) -> str:
        return f"ParameterSet({self._name!r}, {len(self._values)} given)"

    # -- derived sets
    @classmethod
    def from_dict(
        cls,
        values: Mapping[str, float | str],
        name: str = "custom",
        *,
        description: str = "",
    ) -> ParameterSet:
        """Build a validated set from Python: numbers are SI, strings carry units."""
        parsed, info = _parse_entries(values, f"parameter set '{name}'", "from_dict")
        ps = cls(parsed, name=name, description=description, info=info)
        _warn_passivity(ps, stacklevel=2)
        return ps

    def replace(
        self, values: Mapping[str, float | str] | None = None, /, **kw: float | str
    ) -> ParameterSet:
        """A validated copy with values changed or added (numbers SI, strings with units).

        Warns about passivity only if the change breaks it (a set loaded with the warning
        does not warn again on every replace, e.g. in an identification loop).
        """
        changes = {**(values or {}), **kw}
        parsed, info = _parse_entries(
            changes, f"replace() on parameter set '{self._name}'", "replace()"
        )
        ps = ParameterSet(
            {**self._values, **parsed},
            name=self._name,
            description=self._description,
            provenance=self._provenance,
            info={**self._info, **info},
            source_path=self._source_path,
        )
        if lugre_passivity_problem(self._values) is None:
            _warn_passivity(ps, stacklevel=2)
        return ps

    # -- use by models
    def require(self, names: Iterable[str], model: str) -> None:
        """Raise one ParameterError listing every name that has neither value nor default."""
        wanted = list(dict.fromkeys(names))
        unknown = [n for n in wanted if n not in SPECS]
        if unknown:
            raise ParameterError(
                "; ".join(_unknown_name(n, f"the requirements of {model}") for n in unknown)
            )
        wanted_set = set(wanted)
        missing = [
            p.name
            for p in PARAMETERS
            if p.name in wanted_set and p.name not in self._values and p.default is None
        ]
        if missing:
            raise ParameterError(
                f"parameter set '{self._name}' lacks {', '.join(missing)} needed by {model} "
                "(add them to the parameter file, or use ParameterSet.replace)"
            )

    def vector(self, polytropic_index: float = 1.0) -> np.ndarray:
        """Kernel parameter vector in PARAMETERS order (given, else default, else NaN),
        with the chamber law's polytropic index in slot I_POLYTROPIC."""
        if not (math.isfinite(polytropic_index) and polytropic_index > 0.0):
            raise ParameterError(
                f"polytropic_index = {polytropic_index!r}: must be a finite number > 0 "
                "(1 isothermal, gamma adiabatic)"
            )
        vec = np.full(VECTOR_LENGTH, np.nan)
        for i, spec in enumerate(PARAMETERS):
            value = self._values.get(spec.name, spec.default)
            if value is not None:
                vec[i] = value
        vec[I_POLYTROPIC] = polytropic_index
        return vec

    def to_frame(self) -> pd.DataFrame:
        """Table of the set: given parameters, then defaults in use (source 'default')."""
        import pandas as pd

        rows = []
        for spec in PARAMETERS:
            if spec.name in self._values:
                meta = self._info[spec.name]
                rows.append(
                    (
                        spec.name,
                        self._values[spec.name],
                        spec.unit,
                        meta.given,
                        meta.source,
                        spec.description,
                    )
                )
        for spec in PARAMETERS:
            if spec.name not in self._values and spec.default is not None:
                rows.append(
                    (spec.name, float(spec.default), spec.unit, "", "default", spec.description)
                )
        return pd.DataFrame(
            rows, columns=["name", "value", "unit", "given", "source", "description"]
        )


class _MissingParameterError(ParameterError, KeyError):
    """A value that is neither given nor defaulted; a KeyError too, so Mapping.get works."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def _parse_entries(
    values: Mapping[str, Any], where: str, source: str
) -> tuple[dict[str, float], dict[str, ParameterInfo]]:
    """Python-side values (numbers SI, strings with units) -> SI floats and their info."""
    problems: list[str] = []
    parsed: dict[str, float] = {}
    info: dict[str, ParameterInfo] = {}
    for name, raw in values.items():
        if name not in SPECS:
            problems.append(_unknown_name(name, where))
            continue
        try:
            parsed[name] = parse_value(name, raw, bare_number_is_si=True)
        except ParameterError as exc:
            problems.append(str(exc))
            continue
        given = raw if isinstance(raw, str) else _number_text(name, parsed[name])
        info[name] = ParameterInfo(given, source, "")
    if problems:
        raise ParameterError(_message(f"cannot use values for {where}", problems))
    return parsed, info


# --------------------------------------------------------------------------- files

_TOP_KEYS = ("name", "description", "provenance", "parameters")
_ENTRY_KEYS = ("value", "source", "note")


def _sets_dir() -> Any:
    return resources.files(__package__).joinpath("sets")


def _shipped() -> dict[str, Any]:
    """Shipped set name (file stem) -> resource."""
    found = {}
    for entry in _sets_dir().iterdir():
        if entry.name.endswith(".toml") and entry.is_file():
            found[entry.name[: -len(".toml")]] = entry
    return dict(sorted(found.items()))


def _read_toml(data: bytes, label: str) -> dict[str, Any]:
    try:
        return tomllib.loads(data.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"cannot parse parameter file {label}: {exc}") from None


def _from_document(
    doc: dict[str, Any], label: str, default_name: str, source_path: Path | None
) -> ParameterSet:
    file_name = Path(label).name
    problems: list[str] = []
    for key in doc:
        if key not in _TOP_KEYS:
            problems.append(_unknown_name(key, file_name, _TOP_KEYS, what="key"))
    name = doc.get("name", default_name)
    description = doc.get("description", "")
    provenance = doc.get("provenance", {})
    if not isinstance(name, str) or not name:
        problems.append(f"name = {name!r}: must be a non-empty string")
        name = default_name
    if not isinstance(description, str):
        problems.append(f"description = {description!r}: must be a string")
        description = ""
    if not isinstance(provenance, dict) or not all(isinstance(v, str) for v in provenance.values()):
        problems.append('[provenance]: must be a table of strings (source = "...", ...)')
        provenance = {}
    table = doc.get("parameters")
    if not isinstance(table, dict):
        problems.append(
            'missing [parameters] table: write e.g. m = { value = "0.63 kg", '
            'source = "...", note = "..." }'
        )
        table = {}

    values: dict[str, float] = {}
    info: dict[str, ParameterInfo] = {}
    for pname, entry in table.items():
        if pname not in SPECS:
            problems.append(_unknown_name(pname, file_name))
            continue
        source, note = "", ""
        if isinstance(entry, dict):
            bad = [k for k in entry if k not in _ENTRY_KEYS]
            for key in bad:
                problems.append(_unknown_name(key, f"parameter '{pname}'", _ENTRY_KEYS, what="key"))
            if "value" not in entry:
                problems.append(f"parameter '{pname}': missing value = \"...\"")
                continue
            raw, source, note = entry["value"], entry.get("source", ""), entry.get("note", "")
            if not isinstance(source, str) or not isinstance(note, str):
                problems.append(f"parameter '{pname}': source and note must be strings")
                continue
        else:
            raw = entry  # shorthand: m = "0.63 kg"
        try:
            values[pname] = parse_value(pname, raw, bare_number_is_si=False)
        except ParameterError as exc:
            problems.append(str(exc))
            continue
        info[pname] = ParameterInfo(raw if isinstance(raw, str) else repr(raw), source, note)
    if problems:
        raise ParameterError(_message(f"cannot load parameter file {label}", problems))
    return ParameterSet(
        values,
        name=name,
        description=description,
        provenance=provenance,
        info=info,
        source_path=source_path,
    )


def _looks_like_path(text: str) -> bool:
    seps = [s for s in (os.sep, os.altsep, "/") if s]
    return text.endswith(".toml") or any(s in text for s in seps)


def _load(name_or_path: str | Path) -> ParameterSet:
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
            raise ParameterError(
                f"unknown parameter set '{text}'{hint}; available: {', '.join(shipped)} "
                "(or give a path to a .toml file)"
            )
    path = Path(name_or_path)
    if not path.is_file():
        raise ParameterError(f"parameter file '{path}' not found")
    doc = _read_toml(path.read_bytes(), str(path))
    return _from_document(doc, str(path), path.stem, path.resolve())


def load_params(name_or_path: str | Path) -> ParameterSet:
    """Load a shipped set by name ("vgt-paper") or a TOML file by path, in SI, validated.

    Raises ParameterError for an unknown set, a malformed file, an unknown parameter, a
    bad unit or an inconsistent set; warns (PassivityWarning, once) if the LuGre
    parameters break the passivity condition.
    """
    ps = _load(name_or_path)
    _warn_passivity(ps, stacklevel=2)
    return ps


def available_params() -> list[tuple[str, str]]:
    """(name, description) of every parameter set shipped with pneumact."""
    result = []
    for name, resource in _shipped().items():
        doc = _read_toml(resource.read_bytes(), f"{name}.toml")
        description = doc.get("description", "")
        result.append((name, description if isinstance(description, str) else ""))
    return result
