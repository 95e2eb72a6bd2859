"""Units of measured records: pint converts each column to SI at the boundary.

Known signal names (time, pressure, position, velocity, force, friction, command,
setpoint: a regulator's, in Pa; position_setpoint: a position controller's, in m; spool:
a 5/3 valve's command; load: a cylinder's load force, in N) are
converted to their SI unit; other columns to coherent SI. Pressures are
absolute unless the column is named ``pressure_gauge`` (then ``records`` adds p_atm);
a gauge-style unit spelling such as ``barg`` or ``kPa (g)`` is refused with a message
saying how to give it.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pneumact.core.units import SIGNAL_UNITS
from pneumact.errors import DataError
from pneumact.io.quantities import unit_registry

if TYPE_CHECKING:
    import pint

__all__ = ["KNOWN_SIGNALS", "convert_column", "parse_unit", "same_unit"]

_PRESSURE = "a pressure unit (read as absolute) such as kPa, bar, mbar, psi, Pa"
_GAUGE = "a pressure unit (gauge: relative to atmosphere) such as kPa, bar, mbar, psi, Pa"
#: Known signal names -> (pint target unit, what the user may give).
_TARGETS: dict[str, tuple[str, str]] = {
    "time": ("s", "a time unit such as s, ms or min"),
    "pressure": ("Pa", _PRESSURE),
    "pressure_gauge": ("Pa", _GAUGE),
    "setpoint": ("Pa", _PRESSURE),
    "position": ("m", "a length unit such as m, mm or um"),
    "position_setpoint": ("m", "a length unit such as m, mm or um"),
    "velocity": ("m/s", "a velocity unit such as m/s or mm/s"),
    "force": ("N", "a force unit such as N or kN"),
    "friction": ("N", "a force unit such as N or kN"),
    "command": ("dimensionless", "a dimensionless unit: 1, - or % (or no unit)"),
    "spool": ("dimensionless", "a dimensionless unit: 1, - or % (or no unit)"),
    "command_a": ("dimensionless", "a dimensionless unit: 1, - or % (or no unit)"),
    "command_b": ("dimensionless", "a dimensionless unit: 1, - or % (or no unit)"),
    "load": ("N", "a force unit such as N, kN or lbf"),
    "supply": ("Pa", _PRESSURE),
}
#: Known signal names -> (SI unit label, pint target unit, what the user may give); the
#: SI label is the one of ``core.units`` (one unit per signal name everywhere).
KNOWN: dict[str, tuple[str, str, str]] = {
    name: (SIGNAL_UNITS[name], *spec) for name, spec in _TARGETS.items()}

#: Known signal names and the SI unit each is converted to (``core.units``, one table).
KNOWN_SIGNALS: dict[str, str] = SIGNAL_UNITS

#: Coherent SI units used to label extra (unknown-name) columns; the first whose
#: dimension matches is chosen, else the base-unit expression.
_PREFERRED_SI = (
    "1", "s", "m", "kg", "K", "A", "mol", "cd", "N", "Pa", "J", "W", "V", "C", "ohm", "F",
    "T", "Wb", "H", "m/s", "m/s**2", "m**2", "m**3", "kg/s", "kg/m**3", "N/m", "N*s/m",
)  # fmt: skip

_DIMENSIONLESS_SPELLINGS = {"1", "-"}
_GAUGE_RE = re.compile(r"^(?P<base>.+?)\s*(?:\(g\)|\(gauge\)|gauge|g)$", re.IGNORECASE)


def parse_unit(path: Path, label: str, unit: str) -> pint.Unit:
    """Parse ``unit`` with pint, or raise a DataError naming the column."""
    ureg = unit_registry()
    if unit in _DIMENSIONLESS_SPELLINGS:
        return ureg.dimensionless
    try:
        return ureg.Unit(unit)
    except Exception as exc:  # pint raises many types (UndefinedUnitError, TokenError, ...)
        gauge = _gauge_base(unit)
        if gauge:
            raise _gauge_error(path, label, unit, gauge) from exc
        raise DataError(
            f"{path}: {label} has unknown unit {unit!r}; use a unit pint knows, e.g. s, ms, "
            "Pa, kPa, bar, mbar, psi, m, mm, N, m/s, 1 (units are case-sensitive)"
        ) from exc


def _gauge_base(unit: str) -> str | None:
    """``"bar"`` for a gauge-style spelling such as ``barg`` or ``kPa (g)``, else None."""
    match = _GAUGE_RE.match(unit.strip())
    if match is None:
        return None
    try:
        base = unit_registry().Unit(match["base"])
    except Exception:
        return None
    ureg = unit_registry()
    return match["base"] if base.dimensionality == ureg.Pa.dimensionality else None


def _gauge_error(path: Path, label: str, unit: str, base: str) -> DataError:
    return DataError(
        f"{path}: {label} has gauge pressure unit {unit!r}; pneumact reads 'pressure' as "
        f"absolute: name the column 'pressure_gauge [{base}]' (and give p_atm), or add "
        f"atmospheric pressure to the values and give the unit as {base!r}"
    )


def same_unit(path: Path, label: str, a: str, b: str) -> bool:
    return a == b or parse_unit(path, label, a) == parse_unit(path, label, b)


def convert_column(path: Path, label: str, name: str, unit: str | None, raw: np.ndarray
                   ) -> tuple[np.ndarray, str]:
    """One column to SI: known names to their target, others to coherent SI."""
    ureg = unit_registry()
    known = KNOWN.get(name)
    if unit is None:
        if known is None:
            return raw, ""
        if known[1] == "dimensionless":  # a command or spool command: a fraction
            return raw, "1"
        raise DataError(
            f"{path}: {label} has no unit; write the header as '{name} [unit]' with "
            f"{known[2]}", api_hint=f"or pass units={{{name!r}: ...}}")
    parsed = parse_unit(path, label, unit)
    if known is not None:
        si_label, target, allowed = known
        if parsed.dimensionality != ureg.Unit(target).dimensionality:
            gauge = _gauge_base(unit)
            if gauge and target == "Pa":
                raise _gauge_error(path, label, unit, gauge)
            raise DataError(
                f"{path}: {label} has unit {unit!r} of dimension {parsed.dimensionality}; "
                f"{name} needs {allowed}"
            )
        return np.asarray(ureg.Quantity(raw, parsed).to(target).magnitude, float), si_label
    quantity = ureg.Quantity(raw, parsed)
    for candidate in _PREFERRED_SI:
        si = ureg.dimensionless if candidate == "1" else ureg.Unit(candidate)
        if si.dimensionality == parsed.dimensionality:
            return np.asarray(quantity.to(si).magnitude, float), candidate
    base = quantity.to_base_units()
    return np.asarray(base.magnitude, float), f"{base.units:~C}"
