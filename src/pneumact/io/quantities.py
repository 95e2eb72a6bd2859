"""Unit strings at the boundary: "60 cm^3" -> 6e-05 (m^3), with pint.

Inside pneumact every value is SI. A value written in a parameter file or given from
Python as a string carries its unit; it is converted here, once. Building a pint
registry costs about half a second, so a value already written in the parameter's own
SI unit ("0.63 kg" for a mass) is read without pint, and the registry is created only
when a conversion is really needed.
"""

from __future__ import annotations

import math
import re
import threading
from typing import TYPE_CHECKING, NoReturn

import numpy as np

from pneumact.errors import ParameterError

if TYPE_CHECKING:
    import pint

__all__ = ["KIND", "NUMBER_THEN_UNIT", "kind", "parse_value", "unit_registry"]

_REGISTRY: pint.UnitRegistry | None = None
_REGISTRY_LOCK = threading.Lock()

#: What each SI unit of the catalogue measures, for "which is not a volume [m^3]".
KIND: dict[str, str] = {
    "kg": "a mass",
    "m": "a length",
    "m^2": "an area",
    "m^3": "a volume",
    "N": "a force",
    "Pa": "a pressure",
    "m/s": "a velocity",
    "N/m": "a stiffness",
    "N*s/m": "a damping coefficient",
    "N*s/m^2": "a contact damping coefficient",
    "s": "a time",
    "K": "a temperature",
    "J/(kg*K)": "a specific gas constant",
}

NUMBER_THEN_UNIT = re.compile(
    r"\s*([+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|nan|inf(?:inity)?))\s*(.*?)\s*",
    re.IGNORECASE,
)


def unit_registry() -> pint.UnitRegistry:
    """The package's single pint registry, created on first use (pint is slow to load)."""
    global _REGISTRY
    if _REGISTRY is None:
        with _REGISTRY_LOCK:
            if _REGISTRY is None:
                import pint

                _REGISTRY = pint.UnitRegistry()
    return _REGISTRY


def kind(unit: str) -> str:
    return KIND.get(unit, f"convertible to {unit}")


def _fail(message: str) -> NoReturn:
    raise ParameterError(message)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


def parse_value(name: str, value: float | str, unit: str, *,
                bare_number_is_si: bool = True) -> float:
    """Convert one given value of parameter ``name`` (SI unit ``unit``) to its SI float.

    Strings carry a unit ("60 cm^3"); numbers are SI when ``bare_number_is_si`` (the
    Python API), otherwise (parameter files) only dimensionless parameters may be bare
    numbers. Raises ParameterError naming the parameter, the value and what is allowed.
    """
    if isinstance(value, str):
        return _parse_string(name, value, unit)
    if not _is_number(value):
        example = f"'1 {unit}'" if unit else "1.4"
        _fail(f"parameter '{name}' = {value!r}: must be a number or a string with a unit, "
              f"e.g. {example}")
    if unit and not bare_number_is_si:
        _fail(f"parameter '{name}' = {value!r} has no unit; {kind(unit)} needs one: "
              f'write "{value} {unit}"')
    return float(value)


def _parse_string(name: str, text: str, unit: str) -> float:
    example = f"'1 {unit}'" if unit else "'1.4'"
    match = NUMBER_THEN_UNIT.fullmatch(text)
    if match is None:
        _fail(f"parameter '{name}' = '{text}': expected a number followed by a unit, "
              f"e.g. {example}")
    magnitude = float(match.group(1))
    unit_text = match.group(2)
    if not unit_text:
        if unit:
            _fail(f"parameter '{name}' = '{text}' has no unit; {kind(unit)} needs one: "
                  f"write '{match.group(1)} {unit}'")
        return magnitude
    if unit_text.replace(" ", "") == unit:  # already the SI unit: no conversion needed
        return magnitude
    factor = si_prefix_factor(unit_text, unit)
    if factor is not None:  # "60 cm^3" for m^3, "10 kPa" for Pa: no need to load pint
        return float(f"{magnitude * factor:.15g}")
    return _convert(name, text, magnitude, unit_text, unit, example)


#: SI prefixes and their factors (a unit like "cm^3" is (1e-2 m)^3).
SI_PREFIXES = {"Y": 1e24, "Z": 1e21, "E": 1e18, "P": 1e15, "T": 1e12, "G": 1e9, "M": 1e6,
               "k": 1e3, "h": 1e2, "da": 1e1, "d": 1e-1, "c": 1e-2, "m": 1e-3, "u": 1e-6,
               "µ": 1e-6, "μ": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15}
_SIMPLE_UNIT = re.compile(r"([A-Za-z]+)(?:\^(\d+))?")
_PREFIXED = re.compile(r"(da|[YZEPTGMkhdcmuµμnpf])([A-Za-z]+)(?:(?:\^|\*\*)(\d+))?")


def si_prefix_factor(unit_text: str, unit: str) -> float | None:
    """Factor to SI when ``unit_text`` is an SI prefix on the parameter's own simple unit
    (a symbol with an optional power: m, m^3, Pa, N, s), else None (pint decides)."""
    simple = _SIMPLE_UNIT.fullmatch(unit)
    given = _PREFIXED.fullmatch(unit_text.strip())
    if simple is None or given is None or simple.group(1) == "kg":
        return None
    prefix, symbol, power = given.groups()
    if symbol != simple.group(1) or (power or "1") != (simple.group(2) or "1"):
        return None
    return SI_PREFIXES[prefix] ** int(power or "1")


def _convert(name: str, text: str, magnitude: float, unit_text: str, unit: str,
             example: str) -> float:
    ureg = unit_registry()
    import pint

    try:
        units = ureg.parse_units(unit_text)
    except pint.UndefinedUnitError as exc:
        names = exc.unit_names if isinstance(exc.unit_names, str) else ", ".join(exc.unit_names)
        _fail(f"parameter '{name}' = '{text}': unknown unit '{names}'")
    except Exception:  # pint raises assorted errors (Assertion, Token, Value) on bad syntax
        _fail(f"parameter '{name}' = '{text}': cannot read unit '{unit_text}', "
              f"expected something like {example}")
    quantity = ureg.Quantity(magnitude, units)
    target = unit or "dimensionless"
    if quantity.dimensionality != ureg.parse_units(target).dimensionality:
        what = "dimensionless" if not unit else f"{kind(unit)} [{unit}]"
        _fail(f"parameter '{name}' = '{text}' has unit {units}, which is not {what}")
    si = float(quantity.to(target).magnitude)
    if math.isfinite(si):
        # "60 cm^3" -> 6.000000000000001e-05: drop the conversion's last-bit noise so the
        # same value written in different units loads to the same float.
        si = float(f"{si:.15g}")
    return si
