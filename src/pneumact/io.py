"""Reading and writing files: the edge where user units become SI and back.

Inside pneumact everything is SI (s, Pa absolute, m, N). Users' test-bench records are
CSV files in kPa, mm and ms. This module is the one place that converts between the two,
checks the data (missing columns, unknown units, NaN, non-monotonic time) with one clear
:class:`~pneumact.errors.DataError` per mistake, and writes files atomically so that no
half-written output is ever left behind.

Pressures are always read as **absolute**: ``kPa``, ``bar``, ``mbar``, ``psi``, ``Pa``
(and any other pint pressure unit) are taken to mean absolute pressure. A gauge reading
(relative to atmosphere) must be shifted by the caller (``p_abs = p_gauge + p_atm``)
before it is used as an actuator pressure; gauge-style unit spellings such as ``barg`` or
``psig`` are rejected with a message saying so.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import re
import secrets
import threading
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from pneumact.errors import DataError

if TYPE_CHECKING:
    import pint

__all__ = [
    "KNOWN_SIGNALS",
    "UNITS_METADATA_KEY",
    "Record",
    "atomic_write",
    "read_record",
    "read_signal_csv",
    "read_table",
    "write_table",
]

PathLike = str | os.PathLike[str]

#: Parquet schema-metadata key holding ``{column: unit}`` as JSON.
UNITS_METADATA_KEY = b"pneumact.units"

_SUFFIXES = (".csv", ".parquet")

#: Known signal names -> (SI unit label, pint target unit, what the user may give).
_KNOWN: dict[str, tuple[str, str, str]] = {
    "time": ("s", "s", "a time unit such as s, ms or min"),
    "pressure": ("Pa", "Pa", "a pressure unit (read as absolute) such as kPa, bar, mbar, psi, Pa"),
    "setpoint": ("Pa", "Pa", "a pressure unit (read as absolute) such as kPa, bar, mbar, psi, Pa"),
    "position": ("m", "m", "a length unit such as m, mm or um"),
    "velocity": ("m/s", "m/s", "a velocity unit such as m/s or mm/s"),
    "force": ("N", "N", "a force unit such as N or kN"),
    "friction": ("N", "N", "a force unit such as N or kN"),
    "command": ("1", "dimensionless", "a dimensionless unit: 1, - or % (or no unit)"),
}

#: Known signal names and the SI unit each is converted to.
KNOWN_SIGNALS: dict[str, str] = {name: spec[0] for name, spec in _KNOWN.items()}

#: Signals ``read_signal_csv`` accepts as the one input signal of a simulation.
_INPUT_SIGNALS = ("pressure", "command", "setpoint", "force", "velocity", "position")

#: Coherent SI units used to label extra (unknown-name) columns; the first whose
#: dimension matches is chosen, else the base-unit expression.
_PREFERRED_SI = (
    "1", "s", "m", "kg", "K", "A", "mol", "cd", "N", "Pa", "J", "W", "V", "C", "ohm", "F",
    "T", "Wb", "H", "m/s", "m/s**2", "m**2", "m**3", "kg/s", "kg/m**3", "N/m", "N*s/m",
)  # fmt: skip

_DIMENSIONLESS_SPELLINGS = {"1", "-"}
_NA_STRINGS = {"nan", "na", "n/a", "#n/a", "null", "none", "-nan"}
_CELL_RE = re.compile(r"^\s*(?P<name>.*?)\s*(?:\[(?P<u1>[^\[\]]*)\]|\((?P<u2>[^()]*)\))\s*$")
_WS_TOKEN_RE = re.compile(r"\s*([^\s\[\]()]+(?:\s*(?:\[[^\[\]]*\]|\([^()]*\)))?)")
_GAUGE_RE = re.compile(r"^(?P<base>.+?)\s*(?:\(g\)|\(gauge\)|gauge|g)$", re.IGNORECASE)

# pandas >= 3 parses floats round-trip exactly by default and deprecates the option.
_FLOAT_KW: dict[str, Any] = (
    {"float_precision": "round_trip"} if int(pd.__version__.split(".")[0]) < 3 else {}
)

_UREG: pint.UnitRegistry | None = None
_UREG_LOCK = threading.Lock()


def _ureg() -> pint.UnitRegistry:
    """The one pint registry of this module, created on first use (pint is slow to load)."""
    global _UREG
    if _UREG is None:
        with _UREG_LOCK:
            if _UREG is None:
                import pint

                _UREG = pint.UnitRegistry()
    return _UREG


# --------------------------------------------------------------------------- writing


@contextlib.contextmanager
def atomic_write(path: PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; move it onto ``path`` only on success.

    The temporary file (``.<name>.tmp-<random>`` in the same directory, so the final
    ``os.replace`` is atomic) is deleted if the block raises, so a failed or interrupted
    write never leaves a half-written file at ``path`` (an existing file stays intact).
    Parent directories are created first.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.tmp-{secrets.token_hex(6)}")
    try:
        yield tmp
        if not tmp.exists():
            raise FileNotFoundError(f"atomic_write: nothing was written to {tmp} for {target}")
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise


def _check_suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in _SUFFIXES:
        raise DataError(
            f"{path}: unsupported file suffix {path.suffix or '(none)'!r}; "
            f"allowed: {', '.join(_SUFFIXES)}"
        )
    return suffix


def write_table(frame: pd.DataFrame, path: PathLike, units: Mapping[str, str]) -> Path:
    """Write ``frame`` as CSV or Parquet (by suffix), with units, atomically.

    CSV header cells are ``name [unit]`` (e.g. ``time [s]``, ``command [1]``); a column
    without a unit in ``units`` (or with ``""``) gets its plain name. Parquet keeps plain
    column names and stores ``units`` as JSON under the schema-metadata key
    ``pneumact.units``. A named index (e.g. ``time`` from ``Record.to_pandas()``) is
    written as the first column. Floats round-trip exactly through :func:`read_table`.
    """
    target = Path(path)
    suffix = _check_suffix(target)
    if frame.index.name is not None or any(n is not None for n in frame.index.names[1:]):
        frame = frame.reset_index()
    names = list(frame.columns)
    for name in names:
        if not isinstance(name, str) or not name.strip():
            raise DataError(f"{target}: column name {name!r} is not a non-empty string")
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise DataError(f"{target}: duplicate column names {duplicates}; names must be unique")
    unknown = [k for k in units if k not in names]
    if unknown:
        raise DataError(
            f"{target}: units given for {unknown} but the table has no such column; "
            f"columns are {names}"
        )
    unit_of = {n: str(units[n]).strip() for n in names if n in units and str(units[n]).strip()}

    if suffix == ".csv":
        cells = []
        for name in names:
            unit = unit_of.get(name)
            bad = [c for c in "[]()" if c in name] + [c for c in "[]" if unit and c in unit]
            if bad:
                raise DataError(
                    f"{target}: column {name!r} (unit {unit!r}) contains {bad[0]!r}, which "
                    "would make the CSV header 'name [unit]' ambiguous; rename it"
                )
            cells.append(f"{name} [{unit}]" if unit else name)
        with atomic_write(target) as tmp:
            frame.to_csv(tmp, index=False, header=cells, lineterminator="\n", encoding="utf-8")
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.Table.from_pandas(frame, preserve_index=False)
        metadata = dict(table.schema.metadata or {})
        metadata[UNITS_METADATA_KEY] = json.dumps(unit_of).encode("utf-8")
        table = table.replace_schema_metadata(metadata)
        with atomic_write(target) as tmp:
            pq.write_table(table, tmp)
    return target


# --------------------------------------------------------------------------- reading


def _require_file(path: Path) -> None:
    if not path.exists():
        raise DataError(f"{path}: file not found")
    if not path.is_file():
        raise DataError(f"{path}: is not a file")


def _parse_cell(cell: str) -> tuple[str, str | None]:
    """Split a header cell ``name [unit]`` or ``name (unit)`` into (name, unit or None)."""
    match = _CELL_RE.match(cell)
    if match is None:
        return cell.strip(), None
    unit = match["u1"] if match["u1"] is not None else match["u2"]
    unit = unit.strip()
    return match["name"], unit or None


def _first_line(path: Path) -> tuple[int, str]:
    """(0-based index, text) of the first non-blank line: the header, or the first row."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            for index, line in enumerate(fh):
                if line.strip():
                    return index, line.rstrip("\r\n")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: is not UTF-8 text ({exc.reason} at byte {exc.start})") from exc
    raise DataError(f"{path}: file is empty")


def _split_header(path: Path, line: str, sep: str) -> list[str]:
    """Header cells of ``line``; in whitespace mode ``time [s]`` stays one cell."""
    if sep == ",":
        return [c.strip() for c in next(csv.reader([line]))]
    cells, pos = [], 0
    while pos < len(line.rstrip()):
        match = _WS_TOKEN_RE.match(line, pos)
        if match is None:
            raise DataError(
                f"{path}: cannot parse header {line.strip()!r} near {line[pos:].strip()!r}; "
                "write cells as 'name', 'name [unit]' or 'name (unit)'"
            )
        cells.append(match[1])
        pos = match.end()
    return cells


def _read_text(
    path: Path, names: Sequence[str] | None, *, numeric: bool
) -> tuple[pd.DataFrame, list[str]]:
    """Read a CSV/whitespace text file; return the cells (by position) and header cells.

    With ``numeric`` the fast path parses floats; if a cell is not a number it rereads
    everything as text so the caller can report exactly which cell is wrong.
    """
    first, line = _first_line(path)
    sep = "," if "," in line else r"\s+"
    if names is None:
        cells = _split_header(path, line, sep)
        skip = first + 1
    else:
        cells = [str(n) for n in names]
        found = len(next(csv.reader([line]))) if sep == "," else len(line.split())
        if found != len(cells):
            raise DataError(
                f"{path}: names= gives {len(cells)} column names but the file has "
                f"{found} columns in its first line"
            )
        skip = first
    kwargs: dict[str, Any] = dict(
        sep=sep,
        header=None,
        skiprows=skip,
        names=list(range(len(cells))),
        index_col=False,
        encoding="utf-8-sig",
        skipinitialspace=True,
        **_FLOAT_KW,
    )
    try:
        if numeric:
            try:
                frame = pd.read_csv(path, dtype="float64", **kwargs)
            except pd.errors.ParserError:
                raise
            except ValueError:
                frame = pd.read_csv(path, dtype=str, keep_default_na=False, **kwargs)
        else:
            frame = pd.read_csv(path, **kwargs)
    except pd.errors.ParserError as exc:
        raise DataError(
            f"{path}: malformed table ({str(exc).strip()}); every row needs "
            f"{len(cells)} fields like the header"
        ) from exc
    except pd.errors.EmptyDataError:
        frame = pd.DataFrame({i: pd.Series(dtype="float64") for i in range(len(cells))})
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: is not UTF-8 text ({exc.reason} at byte {exc.start})") from exc
    return frame, cells


def _read_parquet(path: Path) -> tuple[pd.DataFrame, dict[str, str]]:
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
    except Exception as exc:  # pyarrow raises several unrelated types for a bad file
        raise DataError(f"{path}: cannot read as Parquet ({exc})") from exc
    units: dict[str, str] = {}
    raw = (table.schema.metadata or {}).get(UNITS_METADATA_KEY)
    if raw is not None:
        try:
            units = {str(k): str(v) for k, v in json.loads(raw).items()}
        except (ValueError, AttributeError) as exc:
            raise DataError(
                f"{path}: schema metadata 'pneumact.units' is not a JSON object of "
                f"column -> unit ({exc})"
            ) from exc
    frame = table.to_pandas()
    return frame, {k: v for k, v in units.items() if k in frame.columns}


def read_table(path: PathLike) -> tuple[pd.DataFrame, dict[str, str]]:
    """Read a table written by :func:`write_table`: (frame with plain names, units).

    CSV header cells ``name [unit]`` are split into name and unit; Parquet units come
    from the ``pneumact.units`` schema metadata. Values are not converted.
    """
    source = Path(path)
    _require_file(source)
    if source.suffix.lower() == ".parquet":
        return _read_parquet(source)
    frame, cells = _read_text(source, None, numeric=False)
    parsed = [_parse_cell(c) for c in cells]
    names = [n for n, _ in parsed]
    _check_unique(source, names)
    frame.columns = names
    return frame, {n: u for n, u in parsed if u is not None}


def _check_unique(path: Path, names: Sequence[str]) -> None:
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise DataError(f"{path}: duplicate column names {duplicates}; names must be unique")


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
            raise KeyError(
                f"{self.source}: no signal {name!r}; available: time, {', '.join(self.signals)}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name == "time" or name in self.signals

    def __len__(self) -> int:
        """Number of samples."""
        return len(self.time)

    def to_pandas(self) -> pd.DataFrame:
        """Signals as columns over a ``time`` index (s); units in ``frame.attrs["units"]``."""
        frame = pd.DataFrame(
            {name: np.array(values) for name, values in self.signals.items()},
            index=pd.Index(np.array(self.time), name="time"),
        )
        frame.attrs["units"] = {"time": "s", **self.units}
        return frame


def _label(name: str, file_name: str) -> str:
    return f"column {name!r}" + (f" (file column {file_name!r})" if file_name != name else "")


def _parse_unit(path: Path, label: str, unit: str) -> pint.Unit:
    """Parse ``unit`` with pint, or raise a DataError naming the column."""
    ureg = _ureg()
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
        base = _ureg().Unit(match["base"])
    except Exception:
        return None
    return match["base"] if base.dimensionality == _ureg().Pa.dimensionality else None


def _gauge_error(path: Path, label: str, unit: str, base: str) -> DataError:
    return DataError(
        f"{path}: {label} has gauge pressure unit {unit!r}; pneumact reads pressures as "
        f"absolute: add atmospheric pressure to the values and give the unit as {base!r}"
    )


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
                "allowed"
            )
        array = parsed.to_numpy(dtype="float64", na_value=np.nan)
    missing = np.flatnonzero(~np.isfinite(array))
    if missing.size:
        row = int(missing[0])
        raise DataError(
            f"{path}: {label} has {missing.size} empty, NaN or infinite cell"
            f"{'s' * (missing.size > 1)}, the first at data row {row + 1}; every cell must "
            "hold a finite number"
        )
    return array


def _match_column(names: Sequence[str], cells: Sequence[str], wanted: str) -> int | None:
    """Index of the file column called ``wanted`` (exact, full cell, then case-insensitive)."""
    for candidates in (names, cells):
        if wanted in candidates:
            return list(candidates).index(wanted)
    folded = [i for i, n in enumerate(names) if n.casefold() == wanted.casefold()]
    return folded[0] if len(folded) == 1 else None


def _convert(
    path: Path, label: str, name: str, unit: str | None, raw: np.ndarray
) -> tuple[np.ndarray, str]:
    """Convert one column to SI: known names to their target, others to coherent SI."""
    ureg = _ureg()
    known = _KNOWN.get(name)
    if unit is None:
        if known is None:
            return raw, ""
        if name == "command":
            return raw, "1"
        raise DataError(
            f"{path}: {label} has no unit; write the header as '{name} [unit]' or pass "
            f"units={{{name!r}: ...}}; allowed: {known[2]}"
        )
    parsed = _parse_unit(path, label, unit)
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


def read_record(
    path: PathLike,
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    required: Sequence[str] = ("time",),
    names: Sequence[str] | None = None,
) -> Record:
    """Read a measured record (CSV, whitespace text or Parquet), check it, convert to SI.

    - Header cells ``name [unit]`` or ``name (unit)`` give each column's unit; ``units``
      gives it (keyed by our or the file's name) for columns whose header has none.
    - ``columns`` maps our names to the file's names when they differ, e.g.
      ``{"pressure": "p_act"}``. Known names (time, pressure, position, velocity, force,
      friction, command, setpoint) are matched case-insensitively and converted to SI
      (see :class:`Record`); other columns keep their name and are converted to coherent
      SI (a column with no unit is kept as is, unit ``""``).
    - ``names`` means the file has no header: these are its column names (``name [unit]``
      allowed).
    - Pressures are read as absolute (see the module docstring).
    - ``time`` is always required, plus ``required``.

    Every problem (missing file or column, unknown unit or wrong dimension, a non-numeric,
    empty or NaN cell, time not strictly increasing, fewer than 2 rows) raises one
    :class:`DataError` naming the file, the column, the data row (1-based) and what is
    allowed.
    """
    source = Path(path)
    _require_file(source)
    if source.suffix.lower() == ".parquet":
        if names is not None:
            raise DataError(f"{source}: names= is for text files without a header, not Parquet")
        frame, file_units = _read_parquet(source)
        cells = [str(c) for c in frame.columns]
        parsed = [(c, file_units.get(c)) for c in cells]
    else:
        frame, cells = _read_text(source, names, numeric=True)
        parsed = [_parse_cell(c) for c in cells]
    file_names = [n for n, _ in parsed]
    header_units = [u for _, u in parsed]
    _check_unique(source, file_names)
    listing = ", ".join(cells) or "(none)"
    no_header_hint = ""
    if names is None and cells and all(_is_number(c) for c in cells):
        no_header_hint = "; the file seems to have no header: pass names=[...]"

    # Our name of each file column: explicit mapping, then known names, then as is.
    ours: list[str | None] = [None] * len(cells)
    for our, theirs in (columns or {}).items():
        index = _match_column(file_names, cells, theirs)
        if index is None:
            raise DataError(
                f"{source}: columns= maps {our!r} to file column {theirs!r}, which does not "
                f"exist; the file has: {listing}{no_header_hint}"
            )
        if ours[index] is not None:
            raise DataError(
                f"{source}: columns= maps both {ours[index]!r} and {our!r} to file column "
                f"{theirs!r}; map each file column once"
            )
        ours[index] = our
    for known in _KNOWN:
        if known in (columns or {}) or known in ours:
            continue
        index = _match_column(file_names, file_names, known)
        if index is not None and ours[index] is None:
            ours[index] = known
    final = [o if o is not None else n for o, n in zip(ours, file_names, strict=True)]
    clashes = sorted({n for n in final if final.count(n) > 1})
    if clashes:
        raise DataError(
            f"{source}: after applying columns= the names {clashes} occur twice; map the other "
            "file column to a different name too"
        )
    for name in ("time", *required):
        if name not in final:
            raise DataError(
                f"{source}: required column {name!r} is missing; the file has: {listing}"
                f"{no_header_hint or '; map a differently named column with columns={...}'}"
            )

    # Units: header first; units= fills gaps and must agree with the header.
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
                elif given is not None and not _same_unit(source, label, resolved[i], given):
                    raise DataError(
                        f"{source}: {label} has unit {resolved[i]!r} in the header but "
                        f"units= says {given!r}; give one or make them agree"
                    )
                break
    unused = sorted(set(units or {}) - used)
    if unused:
        raise DataError(
            f"{source}: units= names {unused}, which match no column; the file has: {listing}"
        )

    if len(frame) < 2:
        raise DataError(
            f"{source}: has {len(frame)} data row{'s' * (len(frame) != 1)}; a record needs at "
            "least 2"
        )

    signals: dict[str, np.ndarray] = {}
    signal_units: dict[str, str] = {}
    time: np.ndarray | None = None
    for i, (name, file_name) in enumerate(zip(final, file_names, strict=True)):
        label = _label(name, file_name)
        raw = _numeric(source, label, frame.iloc[:, i])
        values, si = _convert(source, label, name, resolved[i], raw)
        values = np.ascontiguousarray(values, dtype=np.float64)
        if name == "time":
            _check_time(source, label, raw, f" {resolved[i]}" if resolved[i] else "")
            time = values
        else:
            signals[name] = values
            signal_units[name] = si
    assert time is not None  # "time" is always required above
    for array in (time, *signals.values()):
        array.setflags(write=False)
    return Record(time=time, signals=signals, units=signal_units, source=str(source))


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _same_unit(path: Path, label: str, a: str, b: str) -> bool:
    return a == b or _parse_unit(path, label, a) == _parse_unit(path, label, b)


def _check_time(path: Path, label: str, raw: np.ndarray, unit: str) -> None:
    """Time must be strictly increasing; report the first offending row (1-based)."""
    steps = np.diff(raw)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0])
        raise DataError(
            f"{path}: {label} is not strictly increasing: data row {i + 2} has "
            f"{raw[i + 1]:.10g}{unit} after {raw[i]:.10g}{unit} in row {i + 1} "
            f"({bad.size} such step{'s' * (bad.size > 1)}); times must increase row by row"
        )


def read_signal_csv(
    path: PathLike,
    *,
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
) -> tuple[str, np.ndarray, np.ndarray]:
    """Read one input signal against time (for ``pneumact simulate --input``).

    The file needs ``time`` and exactly one of pressure, command, setpoint, force,
    velocity, position (other columns are ignored). Returns ``(name, time [s], values
    [SI])``; ``columns`` and ``units`` are passed to :func:`read_record`.
    """
    record = read_record(path, columns=columns, units=units)
    found = [name for name in _INPUT_SIGNALS if name in record.signals]
    allowed = ", ".join(_INPUT_SIGNALS)
    if len(found) != 1:
        what = "no input signal column" if not found else f"{len(found)} input signal columns"
        have = ", ".join(["time", *record.signals])
        raise DataError(
            f"{path}: has {what} ({', '.join(found) or 'columns: ' + have}); an input file "
            f"needs time and exactly one of: {allowed}"
        )
    name = found[0]
    return name, record.time, record.signals[name]
