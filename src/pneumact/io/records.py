"""Measured records: a bench file (CSV, whitespace text or Parquet) read, checked, in SI.

A header cell ``name [unit]`` (or ``name (unit)``) gives each column's unit; known
names (time, pressure, pressure_gauge, position, velocity, force, friction, command,
setpoint) are matched case-insensitively and converted to SI. Every problem (missing file
or column, unknown unit or wrong dimension, a non-numeric, empty or NaN cell, time not
strictly increasing, fewer than 2 rows) raises one ``DataError`` naming the file, the
column, the data row (1-based) and what is allowed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from pneumact.errors import DataError
from pneumact.io.tables import (
    PathLike,
    check_unique,
    parse_cell,
    read_parquet,
    read_text,
    require_file,
)
from pneumact.io.units import KNOWN, convert_column, same_unit

__all__ = ["Record", "read_record", "read_signal_csv"]

#: Signals ``read_signal_csv`` accepts as the one input signal of a simulation.
INPUT_SIGNALS = ("pressure", "command", "setpoint", "force", "velocity", "position")
_NA_STRINGS = {"nan", "na", "n/a", "#n/a", "null", "none", "-nan"}


@dataclass(frozen=True, eq=False)
class Record:
    """A measured record in SI: ``time`` (s) and named ``signals`` with their ``units``.

    Known signals are converted to: pressure and setpoint Pa absolute, position m,
    velocity m/s, force and friction N, command dimensionless ("1"). Arrays are
    read-only float64 (copy them to modify). ``units`` holds the SI unit of each signal
    (``""`` for a column that had no unit and was kept unconverted).
    """

    time: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    source: str = ""

    def __getitem__(self, name: str) -> np.ndarray:
        """``record["pressure"]``; ``record["time"]`` gives the time axis."""
        if name == "time":
            return self.time
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"{self.source}: no signal {name!r}; available: time, "
                           f"{', '.join(self.signals)}") from None

    def __contains__(self, name: object) -> bool:
        return name == "time" or name in self.signals

    def __len__(self) -> int:
        """Number of samples."""
        return len(self.time)

    def to_pandas(self) -> pd.DataFrame:
        """Signals as columns over a ``time`` index (s); units in ``frame.attrs["units"]``."""
        frame = pd.DataFrame({name: np.array(values) for name, values in self.signals.items()},
                             index=pd.Index(np.array(self.time), name="time"))
        frame.attrs["units"] = {"time": "s", **self.units}
        return frame


# --------------------------------------------------------------------------- steps
def _label(name: str, file_name: str) -> str:
    return f"column {name!r}" + (f" (file column {file_name!r})" if file_name != name else "")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _numeric(path: Path, label: str, values: pd.Series) -> np.ndarray:
    """Column as float64, or a DataError for the first non-numeric / missing cell."""
    if values.dtype == bool or pd.api.types.is_numeric_dtype(values.dtype):
        array = values.to_numpy(dtype="float64", na_value=np.nan)
    else:
        text = values.astype(object).map(lambda v: "" if v is None else str(v).strip())
        parsed = pd.to_numeric(text, errors="coerce")
        na_like = text.str.lower().isin(_NA_STRINGS) | (text == "")
        bad = np.flatnonzero(parsed.isna().to_numpy() & ~na_like.to_numpy())
        if bad.size:
            row = int(bad[0])
            raise DataError(
                f"{path}: {label} has a non-numeric value {text.iloc[row]!r} at data row "
                f"{row + 1} ({bad.size} such cell{'s' * (bad.size > 1)}); only numbers are "
                "allowed")
        array = parsed.to_numpy(dtype="float64", na_value=np.nan)
    missing = np.flatnonzero(~np.isfinite(array))
    if missing.size:
        row = int(missing[0])
        raise DataError(
            f"{path}: {label} has {missing.size} empty, NaN or infinite cell"
            f"{'s' * (missing.size > 1)}, the first at data row {row + 1}; every cell must "
            "hold a finite number")
    return array


def _match_column(names: Sequence[str], cells: Sequence[str], wanted: str) -> int | None:
    """Index of the file column called ``wanted`` (exact, full cell, then case-insensitive)."""
    for candidates in (names, cells):
        if wanted in candidates:
            return list(candidates).index(wanted)
    folded = [i for i, n in enumerate(names) if n.casefold() == wanted.casefold()]
    return folded[0] if len(folded) == 1 else None


def _check_time(path: Path, label: str, raw: np.ndarray, unit: str) -> None:
    """Time must be strictly increasing; report the first offending row (1-based)."""
    steps = np.diff(raw)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0])
        what = "repeats" if steps[i] == 0 else "goes back"
        raise DataError(
            f"{path}: {label} is not strictly increasing: data row {i + 2} has "
            f"{raw[i + 1]:.10g}{unit} after {raw[i]:.10g}{unit} in row {i + 1} (time {what}; "
            f"{bad.size} such step{'s' * (bad.size > 1)}); times must increase row by row")


def _load(source: Path, names: Sequence[str] | None):
    """(frame, header cells, parsed (name, unit) per column) of a text or Parquet file."""
    if source.suffix.lower() == ".parquet":
        if names is not None:
            raise DataError(f"{source}: names= is for text files without a header, not Parquet")
        frame, file_units = read_parquet(source)
        cells = [str(c) for c in frame.columns]
        return frame, cells, [(c, file_units.get(c)) for c in cells]
    frame, cells = read_text(source, names, numeric=True)
    return frame, cells, [parse_cell(c) for c in cells]


def _our_names(source: Path, file_names, cells, columns, listing, hint) -> list[str]:
    """Our name of each file column: the explicit mapping, then known names, then as is."""
    ours: list[str | None] = [None] * len(cells)
    for our, theirs in (columns or {}).items():
        index = _match_column(file_names, cells, theirs)
        if index is None:
            raise DataError(f"{source}: columns= maps {our!r} to file column {theirs!r}, which "
                            f"does not exist; the file has: {listing}{hint}")
        if ours[index] is not None:
            raise DataError(f"{source}: columns= maps both {ours[index]!r} and {our!r} to file "
                            f"column {theirs!r}; map each file column once")
        ours[index] = our
    for known in KNOWN:
        if known in (columns or {}) or known in ours:
            continue
        index = _match_column(file_names, file_names, known)
        if index is not None and ours[index] is None:
            ours[index] = known
    final = [o if o is not None else n for o, n in zip(ours, file_names, strict=True)]
    clashes = sorted({n for n in final if final.count(n) > 1})
    if clashes:
        raise DataError(f"{source}: after applying columns= the names {clashes} occur twice; "
                        "map the other file column to a different name too")
    return final


def _units_of(source: Path, final, file_names, cells, header_units, units, listing):
    """Each column's unit: the header's, or units= where the header has none (they must
    agree where both are given)."""
    resolved: list[str | None] = list(header_units)
    used: set[str] = set()
    for i, (name, file_name) in enumerate(zip(final, file_names, strict=True)):
        for key in (name, file_name, cells[i]):
            if units and key in units:
                used.add(key)
                given = str(units[key]).strip() or None
                label = _label(name, file_name)
                if resolved[i] is None:
                    resolved[i] = given
                elif given is not None and not same_unit(source, label, resolved[i], given):
                    raise DataError(f"{source}: {label} has unit {resolved[i]!r} in the header "
                                    f"but units= says {given!r}; give one or make them agree")
                break
    unused = sorted(set(units or {}) - used)
    if unused:
        raise DataError(f"{source}: units= names {unused}, which match no column; the file "
                        f"has: {listing}")
    return resolved


def read_record(path: PathLike, columns: Mapping[str, str] | None = None,
                units: Mapping[str, str] | None = None, required: Sequence[str] = ("time",),
                names: Sequence[str] | None = None, p_atm: float | None = None) -> Record:
    """Read a measured record (CSV, whitespace text or Parquet), check it, convert to SI.

    - Header cells ``name [unit]`` or ``name (unit)`` give each column's unit; ``units``
      gives it (keyed by our or the file's name) for columns whose header has none.
    - ``columns`` maps our names to the file's names when they differ, e.g.
      ``{"pressure": "p_act"}``.
    - ``names`` means the file has no header: these are its column names.
    - Pressures are absolute; a ``pressure_gauge`` column is relative to atmosphere and
      needs ``p_atm`` [Pa]: it becomes the absolute ``pressure``.
    - ``time`` is always required, plus ``required``.
    """
    source = Path(path)
    require_file(source)
    frame, cells, parsed = _load(source, names)
    file_names = [n for n, _ in parsed]
    check_unique(source, file_names)
    listing = ", ".join(cells) or "(none)"
    hint = ""
    if names is None and cells and all(_is_number(c) for c in cells):
        hint = "; the file seems to have no header: pass names=[...]"
    final = _our_names(source, file_names, cells, columns, listing, hint)
    gauge = "pressure_gauge" in final
    hint = hint or "; map a differently named column with columns={...}"
    for name in ("time", *required):
        if not (name in final or (name == "pressure" and gauge)):
            raise DataError(f"{source}: required column {name!r} is missing; the file has: "
                            f"{listing}{hint}")
    if gauge and p_atm is None:
        raise DataError(f"{source}: column 'pressure_gauge' is relative to atmosphere; give "
                        "p_atm [Pa] (e.g. p_atm=101325) to read it as absolute pressure")
    resolved = _units_of(source, final, file_names, cells, [u for _, u in parsed], units,
                         listing)
    if len(frame) < 2:
        raise DataError(f"{source}: has {len(frame)} data row{'s' * (len(frame) != 1)}; a "
                        "record needs at least 2")
    signals: dict[str, np.ndarray] = {}
    signal_units: dict[str, str] = {}
    time = None
    for i, (name, file_name) in enumerate(zip(final, file_names, strict=True)):
        label = _label(name, file_name)
        raw = _numeric(source, label, frame.iloc[:, i])
        values, si = convert_column(source, label, name, resolved[i], raw)
        values = np.ascontiguousarray(values, dtype=np.float64)
        if name == "time":
            _check_time(source, label, raw, f" {resolved[i]}" if resolved[i] else "")
            time = values
        elif name == "pressure_gauge":
            if "pressure" in final:
                raise DataError(f"{source}: has both 'pressure' and 'pressure_gauge'; keep one")
            signals["pressure"] = values + float(p_atm)
            signal_units["pressure"] = "Pa"
        else:
            signals[name] = values
            signal_units[name] = si
    for array in (time, *signals.values()):
        array.setflags(write=False)
    return Record(time=time, signals=signals, units=signal_units, source=str(source))


def read_signal_csv(path: PathLike, *, columns: Mapping[str, str] | None = None,
                    units: Mapping[str, str] | None = None, p_atm: float | None = None
                    ) -> tuple[str, np.ndarray, np.ndarray]:
    """Read one input signal against time (for ``pneumact simulate --input``).

    The file needs ``time`` and exactly one of pressure, command, setpoint, force,
    velocity, position (other columns are ignored). Returns ``(name, time [s], values
    [SI])``; ``columns``, ``units`` and ``p_atm`` are passed to :func:`read_record`.
    """
    record = read_record(path, columns=columns, units=units, p_atm=p_atm)
    found = [name for name in INPUT_SIGNALS if name in record.signals]
    allowed = ", ".join(INPUT_SIGNALS)
    if len(found) != 1:
        what = "no input signal column" if not found else f"{len(found)} input signal columns"
        have = ", ".join(["time", *record.signals])
        raise DataError(f"{path}: has {what} ({', '.join(found) or 'columns: ' + have}); an "
                        f"input file needs time and exactly one of: {allowed}")
    name = found[0]
    return name, record.time, record.signals[name]
