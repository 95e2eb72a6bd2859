"""Numbers a person reads: SI values in display units (lengths in mm or µm, pressures
in kPa, forces in N), for terminal tables and reports. Files stay SI with ``name [unit]``
headers; only what is shown converts, here, with pint's factors.

``display_unit`` is the one choice of unit; ``display_frame`` applies it to a table:
columns headed ``name [unit]`` and long tables with a ``unit`` column (a row per
quantity: each row in its own unit).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

import numpy as np

from ..plotting import DISPLAY_UNITS, SMALL_LENGTH, shown_unit

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["SMALL_LENGTH", "display_frame", "display_unit", "display_value", "pretty_unit",
           "signal_summary"]

#: SI units (as pneumact writes them) -> the unit shown; simple units from the figures'
#: table (``plotting.DISPLAY_UNITS``), products of them here
_SHOWN: dict[str, str] = {
    **{si: shown for si, (shown, _) in DISPLAY_UNITS.items()},
    "Pa*m": "kPa*mm", "Pa·m": "kPa*mm", "m*s": "mm*s", "m^2*s": "mm^2*s",
    "Pa^2*s": "kPa^2*s", "Pa*s": "kPa*s", "Pa/s": "kPa/s", "m/s^2": "mm/s^2",
}  # parameters (N/m, N*s/m, m^2) stay as the sets and the paper write them
#: the same with µm for small lengths
_SHOWN_SMALL: dict[str, str] = {"m*s": "µm*s"}
#: the columns of a long table (a ``unit`` column) that carry a value in that unit
VALUE_COLUMNS = ("value", "measured", "model", "difference", "rms", "min", "max", "first",
                 "last", "estimate", "stderr", "nominal", "low", "high", "lower", "upper", "truth")
_HEADER = re.compile(r"^(?P<name>.*?)\s*\[(?P<unit>[^\]]*)\]$")


@functools.cache
def _factor(si: str, shown: str) -> float:
    from .quantities import unit_registry

    ureg = unit_registry()
    return float(ureg.Quantity(1.0, si.replace("·", "*")).to(shown.replace("µ", "u"))
                 .magnitude)


def display_unit(si: str, values: Iterable[float] | float = ()) -> tuple[str, float]:
    """(unit shown, factor from SI) for values in ``si``; lengths whose magnitudes are all
    below ``SMALL_LENGTH`` (``values``, when given) in µm (the figures' choice,
    ``plotting.shown_unit``). A unit without a display choice is shown as it is."""
    si = str(si).strip()
    if si in DISPLAY_UNITS:
        return shown_unit(si, values)
    shown = _SHOWN.get(si)
    if shown is None:
        return si, 1.0
    finite = np.abs(np.asarray(values, dtype=float).ravel())
    finite = finite[np.isfinite(finite) & (finite > 0)]
    if si in _SHOWN_SMALL and finite.size and finite.max() < SMALL_LENGTH:
        shown = _SHOWN_SMALL[si]
    return shown, _factor(si, shown)


def pretty_unit(unit: str) -> str:
    """``kPa^2*s`` as ``kPa²·s``: the unit as a person writes it."""
    return str(unit).replace("^2", "²").replace("^3", "³").replace("**2", "²").replace("*", "·")


def display_value(value: float, si: str) -> tuple[float, str]:
    """(value in its display unit, the unit written for a person)."""
    shown, factor = display_unit(si, value)
    return float(value) * factor, pretty_unit(shown)


def display_frame(frame: pd.DataFrame, units: Mapping[str, str] | None = None
                  ) -> pd.DataFrame:
    """A copy of ``frame`` for a person to read: a column headed ``name [unit]`` (or named
    in ``units``, column -> SI unit) in its display unit, headed ``name [shown]``; in a
    long table with a ``unit`` column, each row's ``VALUE_COLUMNS`` in the row's display
    unit, and the ``unit`` column saying it. Other columns as they are."""
    out = frame.copy()
    units = dict(units or {})
    renames = {}
    for column in frame.columns:
        match = _HEADER.match(str(column))
        si = units.get(column) or (match["unit"] if match else None)
        if not si or not _numeric(frame[column]):
            continue
        name = match["name"] if match else str(column)
        shown, factor = display_unit(si, frame[column].to_numpy(float))
        out[column] = frame[column].to_numpy(float) * factor
        renames[column] = f"{name} [{pretty_unit(shown)}]"
    if "unit" in frame.columns:
        values = [c for c in VALUE_COLUMNS if c in frame.columns]
        shown_units = []
        for i, si in enumerate(frame["unit"].astype(str)):
            numbers = {c: v for c in values if _number(v := frame[c].iloc[i])}
            shown, factor = display_unit(si, list(numbers.values()))
            for c, v in numbers.items():
                out.iloc[i, out.columns.get_loc(c)] = float(v) * factor
            shown_units.append(pretty_unit(shown))
        out["unit"] = shown_units
    return out.rename(columns=renames)


def _numeric(series) -> bool:
    import pandas as pd

    return bool(pd.api.types.is_numeric_dtype(series)) and not \
        pd.api.types.is_bool_dtype(series)


def _number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


def signal_summary(signals: Mapping[str, np.ndarray], units: Mapping[str, str]
                   ) -> pd.DataFrame:
    """Per signal: its first, smallest, largest and last value (SI, with a ``unit``
    column: ``display_frame`` shows it in display units): a record or a run at a
    glance, without its arrays."""
    import pandas as pd

    rows = [{"signal": name, "unit": units.get(name, ""), "first": float(v[0]),
             "min": float(np.min(v)), "max": float(np.max(v)), "last": float(v[-1])}
            for name, v in signals.items() if np.size(v)]
    return pd.DataFrame(rows, columns=["signal", "unit", "first", "min", "max", "last"])
