"""Measured records: a bench file (CSV, whitespace text or Parquet) read, checked, in SI.

A header cell ``name [unit]`` (or ``name (unit)``) gives each column's unit; known
names (time, pressure, pressure_gauge, position, velocity, force, friction, command,
setpoint) are matched case-insensitively and converted to SI. Every problem (missing file
or column, unknown unit or wrong dimension, a non-numeric, empty or NaN cell, time not
strictly increasing, fewer than 2 rows) raises one ``DataError`` naming the file, the
column, the data row (1-based) and what is allowed.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from pneumact.checks import check_atmosphere, check_names, check_path
from pneumact.errors import ArgumentTypeError, DataError
from pneumact.io.report import ResultVocabulary
from pneumact.io.tables import (
    PathLike,
    check_unique,
    parse_cell,
    read_excel,
    read_parquet,
    read_text,
    require_file,
)
from pneumact.io.units import KNOWN, convert_column, same_unit

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["Record", "as_records", "read_record", "read_records", "read_signal_csv",
           "refuse_duplicates"]

#: A record's measured chamber pressure, absolute [Pa] (a ``pressure_gauge`` column is
#: read into it): what an imposed pressure drives a run with, and what a run's chamber
#: pressure is compared against.
PRESSURE_SIGNAL = "pressure"
#: Signals ``read_signal_csv`` accepts as the one input signal of a simulation.
INPUT_SIGNALS = (PRESSURE_SIGNAL, "command", "setpoint", "force", "velocity", "position")
#: the files a record is read from (their suffix is not part of its name)
RECORD_SUFFIXES = (".csv", ".csv.gz", ".parquet", ".xlsx")
#: Excel workbooks (.xlsx read with the optional openpyxl; .xls refused with a hint)
EXCEL_SUFFIXES = (".xlsx", ".xlsm", ".xls")
_NA_STRINGS = {"nan", "na", "n/a", "#n/a", "null", "none", "-nan"}


def _record_suffix(file_name: str) -> str:
    """The record-file suffix ``file_name`` ends with ('.csv.gz', '.csv', ...), or ''."""
    lowered = file_name.lower()
    return next((s for s in sorted(RECORD_SUFFIXES, key=len, reverse=True)
                 if lowered.endswith(s)), "")


@dataclass(frozen=True, eq=False)
class Record(ResultVocabulary):
    """A measured record in SI: ``time`` (s) and named ``signals`` with their ``units``.

    Like every result: ``to_pandas()``, ``plot()`` (a Figure) and ``write(folder)``
    (signals.csv, signals.png and report.html). ``save(path)`` stays the file-level
    saver: one CSV or Parquet file in chosen units, the form ``read_record`` reads back.

    Known signals are converted to: pressure and setpoint Pa absolute, position m,
    velocity m/s, force and friction N, command dimensionless ("1"). Arrays are
    read-only float64 (copy them to modify). ``units`` holds the SI unit of each signal
    (``""`` for a column that had no unit and was kept unconverted).
    """

    time: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    source: str = ""
    meta: dict[str, str] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The record's name: its file name without folder and suffix ("presliding" for
        bench/presliding.csv), to choose records by name rather than by position. Only a
        record file's suffix goes: "ramp_0.05mm_s" stays whole."""
        name = Path(self.source).name if self.source else ""
        suffix = _record_suffix(name)
        return name[:-len(suffix)] if suffix else name

    @classmethod
    def from_arrays(cls, time, signals: Mapping[str, object],
                    units: Mapping[str, str] | None = None, source: str = "record",
                    meta: Mapping[str, str] | None = None) -> Record:
        """A record from SI arrays (e.g. a simulation or a generated campaign), checked
        like a file: same length, finite, time strictly increasing, at least 2 samples."""
        from pneumact.io.units import KNOWN_SIGNALS

        time = np.array(time, dtype=float)
        if time.ndim != 1 or time.size < 2:
            raise DataError(f"{source}: time must be 1-D with at least 2 samples, got shape "
                            f"{time.shape}")
        arrays = {"time": time, **{k: np.array(v, dtype=float) for k, v in signals.items()}}
        for name, values in arrays.items():
            if values.shape != time.shape:
                raise DataError(f"{source}: signal {name!r} has shape {values.shape}; time has "
                                f"{time.shape}")
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise DataError(f"{source}: signal {name!r} has {bad.size} NaN or infinite "
                                f"value(s), the first at sample {bad[0] + 1}")
        _check_time(Path(source), "time", time, " s")
        for name, values in arrays.items():
            check_physics(source, name, values, f"signal {name!r}")
        units = {n: (units or {}).get(n, KNOWN_SIGNALS.get(n, "")) for n in signals}
        for values in arrays.values():
            values.setflags(write=False)
        return cls(time, {n: arrays[n] for n in signals}, units, source, dict(meta or {}))

    def _derived(self, time: np.ndarray, signals: dict[str, np.ndarray], what: str) -> Record:
        return Record.from_arrays(time, signals, self.units, f"{self.source} ({what})",
                                  self.meta)

    def crop(self, start: float | None = None, stop: float | None = None) -> Record:
        """The samples with ``start <= time <= stop`` [s]."""
        lo = self.time[0] if start is None else float(start)
        hi = self.time[-1] if stop is None else float(stop)
        keep = (self.time >= lo) & (self.time <= hi)
        if np.count_nonzero(keep) < 2:
            raise DataError(f"{self.source}: crop({start}, {stop}) keeps "
                            f"{np.count_nonzero(keep)} samples; the record spans "
                            f"{self.time[0]:.6g}..{self.time[-1]:.6g} s")
        return self._derived(self.time[keep], {n: v[keep] for n, v in self.signals.items()},
                             f"{lo:.6g}..{hi:.6g} s")

    def resample(self, dt: float | None = None, times=None) -> Record:
        """Linear interpolation onto a uniform grid of step ``dt`` [s] or onto ``times``."""
        if (dt is None) == (times is None):
            raise DataError(f"{self.source}: resample needs exactly one of dt or times")
        if dt is not None:
            if not (np.isfinite(dt) and dt > 0):
                raise DataError(f"{self.source}: resample dt = {dt} s; must be > 0")
            grid = np.arange(self.time[0], self.time[-1] + 0.5 * dt, dt)
            grid = grid[grid <= self.time[-1]]
        else:
            grid = np.asarray(times, dtype=float)
            if grid.size and (grid[0] < self.time[0] or grid[-1] > self.time[-1]):
                raise DataError(f"{self.source}: resample times span {grid[0]:.6g}.."
                                f"{grid[-1]:.6g} s, outside the record "
                                f"{self.time[0]:.6g}..{self.time[-1]:.6g} s")
        return self._derived(grid, {n: np.interp(grid, self.time, v)
                                    for n, v in self.signals.items()}, "resampled")

    def require(self, names: Sequence[str], use: str) -> None:
        """One DataError naming every signal ``use`` needs that the record lacks."""
        missing = [n for n in names if n not in self]
        if missing:
            raise DataError(f"{self.source}: {use} needs signal(s) {', '.join(missing)}; the "
                            f"record has: time, {', '.join(self.signals) or '(nothing)'}")

    def check_within_stroke(self, x_max: float, use: str) -> None:
        """A measured position must lie near the stroke [0, x_max] of the model it is
        compared with (a sensor offset of half a stroke is allowed); far outside, it is
        a unit mistake (mm read as m) or another actuator's record."""
        if "position" not in self.signals:
            return
        self.warn_if_saturated(x_max)
        x = self.signals["position"]
        low, high = float(np.min(x)), float(np.max(x))
        margin = 0.5 * x_max
        if low < -margin or high > x_max + margin:
            raise DataError(
                f"{self.source}: position spans {low * 1e3:.6g} to {high * 1e3:.6g} mm, "
                f"which {use} compares with an actuator of stroke 0 to {x_max * 1e3:g} mm; "
                "check the position unit in the header (e.g. 'position [mm]')")

    def saturation(self, x_max: float | None = None) -> str | None:
        """Why the position looks clipped by a saturated sensor, or None: it holds
        exactly its highest value over a stretch (at least 10 samples and 5 % of the
        record) during which the input goes on beyond where the stretch began and comes
        back (by a tenth of its range each way): the actuator moved on, the sensor did
        not. A stick at the input's turning point holds from the turn on, not across it;
        a hold at the end of the stroke ``x_max`` (its stop) is the actuator's own."""
        drive = next((s for s in (PRESSURE_SIGNAL, "setpoint", "command")
                      if s in self.signals), None)
        if "position" not in self.signals or drive is None:
            return None
        x, u = self.signals["position"], self.signals[drive]
        if x_max is not None and x.max() >= x_max * (1.0 - 1e-3):
            return None  # on the stop
        held = np.flatnonzero(np.diff(np.concatenate([[0], (x == x.max()).astype(np.int8),
                                                      [0]])))
        if held.size < 2:
            return None
        starts, ends = held[::2], held[1::2]
        k = int(np.argmax(ends - starts))
        first, last = int(starts[k]), int(ends[k]) - 1
        if last - first + 1 < max(10, 0.05 * x.size):
            return None
        stretch = u[first:last + 1]
        span = float(np.ptp(u))
        for extreme in (float(stretch.max()), float(stretch.min())):
            if span > 0 and min(abs(extreme - u[first]), abs(extreme - u[last])) > 0.1 * span:
                return (f"{self.source or 'record'}: position holds exactly "
                        f"{x.max() * 1e3:.6g} mm, its highest value, from t = "
                        f"{self.time[first]:.6g} to {self.time[last]:.6g} s while the "
                        f"{drive} goes on and comes back: a saturated position sensor? "
                        "the model is compared with a clipped signal there (crop the "
                        "record, or give the sensor more range)")
        return None

    def warn_if_saturated(self, x_max: float | None = None) -> None:
        """A ``PlausibilityWarning`` naming a saturated position sensor (``saturation``)."""
        import warnings

        from pneumact.errors import PlausibilityWarning

        reason = self.saturation(x_max)
        if reason is not None:
            warnings.warn(reason, PlausibilityWarning, stacklevel=2)

    def save(self, path: PathLike, units: Mapping[str, str] | None = None) -> Path:
        """Write CSV or Parquet (by suffix) atomically, each column in ``units`` (e.g.
        ``{"pressure": "kPa", "position": "mm"}``; SI otherwise)."""
        from pneumact.io.quantities import unit_registry
        from pneumact.io.tables import write_table

        ureg = unit_registry()
        frame, file_units = {}, {}
        for name, values in {"time": self.time, **self.signals}.items():
            si = "s" if name == "time" else self.units.get(name, "")
            unit = (units or {}).get(name, si)
            if unit != si and si:
                try:
                    values = ureg.Quantity(np.asarray(values), si if si != "1" else "").to(
                        unit).magnitude
                except Exception as exc:
                    raise DataError(f"save: cannot express {name} [{si}] in {unit!r} ({exc})"
                                    ) from exc
            frame[name] = np.asarray(values)
            file_units[name] = unit
        return write_table(pd.DataFrame(frame), path, file_units)

    report_title = "Record"
    figure_name = "signals"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"signals": self.to_pandas()}

    def report_text(self) -> str:
        return (f"{self.source or 'record'}: {len(self)} samples over "
                f"{self.time[0]:g}..{self.time[-1]:g} s; signals (SI): "
                f"{', '.join(f'{n} [{u}]' for n, u in self.units.items())}.")

    def write(self, out_dir: PathLike, *, call: str = "") -> list[Path]:
        """signals.csv (SI, header ``name [unit]``, readable by ``read_record``),
        signals.png and report.html in ``out_dir``, all or nothing."""
        from pneumact.io.report import figure_png
        from pneumact.io.tables import write_files

        png = figure_png(self.plot())
        return write_files(out_dir, {
            "signals.csv": self.save,
            f"{self.figure_name}.png": lambda p: Path(p).write_bytes(png),
            "report.html": self.report(call, png).write})

    def plot(self, signals: Sequence[str] | None = None) -> Figure:
        """One panel per signal against time, in display units (kPa, mm, N)."""
        from pneumact.plotting import plot_time_series

        return plot_time_series(self, signals)

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

    def __repr__(self) -> str:
        """Short: the name, the samples and time span, the signals; never the arrays."""
        return (f"Record({self.name or self.source!r}, {len(self.time)} samples over "
                f"{self.time[0]:g}..{self.time[-1]:g} s, signals: "
                f"{', '.join(f'{n} [{u}]' if u else n for n, u in self.units.items())})")

    def notebook_table(self) -> pd.DataFrame:
        """Each signal's first, smallest, largest and last value (a notebook's display)."""
        from pneumact.io.display import signal_summary

        return signal_summary(self.signals, self.units)

    def __len__(self) -> int:
        """Number of samples."""
        return len(self.time)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """Signals as columns over a ``time`` index (s); units in ``frame.attrs["units"]``
        (``name``: "signals", the one table, or None)."""
        if name not in (None, "signals"):
            raise DataError(f"to_pandas: name = {name!r}; allowed: signals")
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


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def _rows(mask: np.ndarray) -> str:
    n = int(mask.sum())
    return f"{n} such row{'s' * (n != 1)}"


#: the latest start of a record's time [s] (11.6 days): later is a clock or epoch
#: timestamp (1.7e9 s), whose float spacing (2.4e-7 s) the solver's steps cannot resolve
MAX_TIME_OFFSET = 1e6


def check_physics(source, name: str, values: np.ndarray, label: str | None = None) -> None:
    """What the physics allows of a known signal in SI: an absolute pressure (or pressure
    set-point) > 0 and <= MAX_ABSOLUTE_PRESSURE, not all below 1 kPa (kPa read as Pa); a
    valve command within [0, 1]; a time from 0 to ``MAX_TIME_OFFSET``. One DataError
    naming the first bad row."""
    from pneumact.checks import MAX_ABSOLUTE_PRESSURE, pressure_hint

    label = label or f"column {name!r}"
    if values.size == 0:
        return
    if name == "time" and values[0] < 0:
        raise DataError(f"{source}: {label} starts at {values[0]:.6g} s; times must be >= 0 "
                        "(shift the record's time axis so that it starts at 0)")
    if name == "time" and values[0] > MAX_TIME_OFFSET:
        spacing = float(np.spacing(values[0]))
        raise DataError(
            f"{source}: {label} starts at {values[0]:.6g} s ({values[0] / 86400:.3g} days: "
            f"a clock or epoch timestamp?); at that offset time has a resolution of only "
            f"{spacing:.2g} s, too coarse for the solver's steps: subtract the first time so "
            "that the record starts at 0")
    if name in (PRESSURE_SIGNAL, "setpoint"):
        bad = (values <= 0) | (values > MAX_ABSOLUTE_PRESSURE)
        if bad.any():
            i = _first(bad)
            hint = (pressure_hint(float(values[i]), (1e3, MAX_ABSOLUTE_PRESSURE))
                    if values[i] > 0 else "")
            raise DataError(
                f"{source}: {label} = {values[i]:.6g} Pa at data row {i + 1} "
                f"({_rows(bad)}): an absolute pressure must be in (0, "
                f"{MAX_ABSOLUTE_PRESSURE:g}] Pa" + (f" ({hint})" if hint else "")
                + ("; a gauge pressure (relative to the atmosphere) goes in a column "
                   "named 'pressure_gauge', e.g. 'pressure_gauge [kPa]'" if values[i] <= 0
                   else ""))
        top = float(np.max(values))
        if top < 1e3:
            hint = pressure_hint(top, (1e3, MAX_ABSOLUTE_PRESSURE))
            raise DataError(f"{source}: {label} never exceeds {top:.6g} Pa: no absolute "
                            "pressure of a pneumatic actuator stays below 1 kPa"
                            + (f" ({hint}; give the unit in the header, e.g. "
                               f"'{name} [kPa]')" if hint else ""))
    if name == "command":
        bad = (values < 0.0) | (values > 1.0)
        if bad.any():
            i = _first(bad)
            raise DataError(f"{source}: {label} = {values[i]:.6g} at data row {i + 1} "
                            f"({_rows(bad)}): a valve command is within "
                            "[0, 1] (a percentage needs the unit '%' in the header)")


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
    if source.suffix.lower() in EXCEL_SUFFIXES:
        if names is not None:
            raise DataError(f"{source}: names= is for text files without a header, not Excel")
        frame, cells = read_excel(source)
    else:
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
                header = resolved[i]
                if header is None:
                    resolved[i] = given
                elif given is not None and not same_unit(source, label, header, given):
                    raise DataError(f"{source}: {label} has unit {header!r} in the header "
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

    - Text: ',' or ';' separated (with decimal commas, as spreadsheets write them in many
      locales) or whitespace; ``.csv.gz`` is read compressed; ``.xlsx`` (the first
      sheet) needs the optional openpyxl. Header columns without a name or data go.

    - Header cells ``name [unit]`` or ``name (unit)`` give each column's unit; ``units``
      gives it (keyed by our or the file's name) for columns whose header has none.
    - ``columns`` maps our names to the file's names when they differ, e.g.
      ``{"pressure": "p_act"}``.
    - ``names`` means the file has no header: these are its column names.
    - Pressures are absolute; a ``pressure_gauge`` column is relative to atmosphere and
      needs ``p_atm`` [Pa]: it becomes the absolute ``pressure``.
    - ``time`` is always required, plus ``required``.
    """
    source = check_path("path", path, where="read_record")
    _check_mappings(columns=columns, units=units)
    required = check_names("required", required, where="read_record", what="signal name")
    if names is not None:
        names = check_names("names", names, where="read_record", what="column name",
                            allow_empty=False, error=DataError)
    if p_atm is not None:
        p_atm = check_atmosphere("p_atm", p_atm, where="read_record", error=DataError)
    require_file(source)
    frame, cells, parsed = _load(source, names)
    file_names = [n for n, _ in parsed]
    check_unique(source, file_names)
    listing = ", ".join(cells) or "(none)"
    headless = names is None and cells and all(_is_number(c) for c in cells)
    final = _our_names(source, file_names, cells, columns, listing,
                       "; the file seems to have no header" if headless else "")
    gauge = "pressure_gauge" in final
    for name in ("time", *required):
        if not (name in final or (name == PRESSURE_SIGNAL and gauge)):
            if headless:
                raise DataError(
                    f"{source}: required column {name!r} is missing; the file seems to have "
                    "no header (its first line is numbers: "
                    f"{listing}): add one, e.g. 'time [s],pressure [kPa],position [mm]'",
                    api_hint="or pass names=[...]")
            raise DataError(
                f"{source}: required column {name!r} is missing; the file has: {listing}",
                api_hint="map a differently named column with columns={...}",
                cli_hint=f"rename the file's column to '{name}' (with its unit, e.g. "
                         f"'{name} [{KNOWN[name][0] if name in KNOWN else 'unit'}]')")
    if gauge and p_atm is None:
        raise DataError(f"{source}: column 'pressure_gauge' is relative to atmosphere: an "
                        "atmospheric pressure is needed to read it as absolute pressure",
                        api_hint="give p_atm [Pa], e.g. p_atm=101325",
                        cli_hint="the parameter set's p_atm is used; give --params")
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
            check_physics(source, name, values, label)
            time = values
        elif name == "pressure_gauge":
            assert p_atm is not None  # a gauge column without p_atm was refused above
            if PRESSURE_SIGNAL in final:
                raise DataError(f"{source}: has both 'pressure' and 'pressure_gauge'; keep one")
            signals[PRESSURE_SIGNAL] = values + float(p_atm)
            signal_units[PRESSURE_SIGNAL] = "Pa"
            check_physics(source, PRESSURE_SIGNAL, signals[PRESSURE_SIGNAL],
                          f"{label} + p_atm = {p_atm:g} Pa")
        else:
            check_physics(source, name, values, label)
            signals[name] = values
            signal_units[name] = si
    assert time is not None  # 'time' is a required column (checked above)
    for array in (time, *signals.values()):
        array.setflags(write=False)
    return Record(time=time, signals=signals, units=signal_units, source=str(source))


def _check_mappings(**given) -> None:
    for name, value in given.items():
        if value is None:
            continue
        if not isinstance(value, Mapping) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in value.items()):
            raise ArgumentTypeError(f"read_record: {name} = {value!r:.60}: must be a dict of "
                                    "column name -> " + ("file column name" if name == "columns"
                                                         else "unit") + " (strings)")


def read_signal_csv(path: PathLike, *, columns: Mapping[str, str] | None = None,
                    units: Mapping[str, str] | None = None, p_atm: float | None = None
                    ) -> tuple[str, np.ndarray, np.ndarray]:
    """Read one input signal against time (for ``pneumact simulate --input-csv``).

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


def as_records(records, where: str) -> list[Record]:
    """Records as a list, from what a function was given: one Record, a list of them, or
    paths of files or folders (read with ``read_records``' defaults)."""
    if isinstance(records, Record):
        return [records]
    if isinstance(records, (str, os.PathLike)):
        return read_records(records)
    if not isinstance(records, Sequence) or isinstance(records, bytes):
        raise ArgumentTypeError(f"{where}: records = {records!r:.60}: must be a Record, a list "
                                "of Records (pa.read_records(...)) or paths, not "
                                f"{type(records).__name__}")
    out: list[Record] = []
    for item in records:
        if isinstance(item, Record):
            out.append(item)
        elif isinstance(item, (str, os.PathLike)):
            out.extend(read_records(item))
        else:
            raise ArgumentTypeError(f"{where}: records holds {item!r:.60}: every item must be "
                                    f"a Record or a path, not {type(item).__name__}")
    if not out:
        raise DataError(f"{where}: give at least one record")
    refuse_duplicates(out, where)
    return out


def _file_of(record: Record) -> Path | None:
    """The resolved file a record was read from, or None (built in memory)."""
    path = Path(record.source) if record.source else None
    return path.resolve() if path is not None and path.is_file() else None


def _same_data(a: Record, b: Record) -> bool:
    return (a.time.shape == b.time.shape and set(a.signals) == set(b.signals)
            and np.array_equal(a.time, b.time)
            and all(np.array_equal(a.signals[n], b.signals[n]) for n in a.signals))


def refuse_duplicates(records: Sequence[Record], where: str) -> None:
    """Refuse a record given twice (the same file, or identical data under two names): it
    would count as new data and narrow every interval. Cheap: data are compared only
    between records of equal length and time span."""
    prefix = f"{where}: " if where else ""
    seen: dict[object, int] = {}
    groups: dict[tuple[int, float, float], list[int]] = {}
    for i, record in enumerate(records):
        file = _file_of(record)
        if file is not None and file in seen:
            raise DataError(f"{prefix}record {file} is given twice (records {seen[file] + 1} "
                            f"and {i + 1}): a repeated record counts as new data and narrows "
                            "every interval; give each record once")
        if file is not None:
            seen[file] = i
        key = (record.time.size, float(record.time[0]), float(record.time[-1]))
        for j in groups.get(key, []):
            if _same_data(records[j], record):
                first, second = records[j].source or "record", record.source or "record"
                raise DataError(f"{prefix}records {j + 1} ({first}) and {i + 1} ({second}) "
                                "hold identical data (the same record twice?): a repeated "
                                "record counts as new data and narrows every interval; give "
                                "each record once")
        groups.setdefault(key, []).append(i)


def read_records(paths: PathLike | Sequence[PathLike], **kwargs) -> list[Record]:
    """Several records at once: a list of files, or a folder (its ``*.csv`` and
    ``*.parquet`` files in name order); ``kwargs`` go to :func:`read_record`."""
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    if not isinstance(paths, Sequence) or isinstance(paths, bytes):
        raise ArgumentTypeError(f"read_records: paths = {paths!r:.60}: must be a path (a "
                                "file or a folder) or a list of paths, not "
                                f"{type(paths).__name__}")
    files: list[Path] = []
    for entry in (check_path("paths", p, where="read_records") for p in paths):
        if entry.is_dir():
            found = sorted(p for p in entry.iterdir()  # not Excel's lock files ~$...
                           if _record_suffix(p.name) and not p.name.startswith("~$")
                           and p.is_file())
            if not found:
                raise DataError(f"{entry}: folder holds no record "
                                f"({', '.join(RECORD_SUFFIXES)})")
            files.extend(found)
        else:
            files.append(entry)
    if not files:
        raise DataError("read_records: no record given")
    records = [read_record(f, **kwargs) for f in files]
    refuse_duplicates(records, "")
    return records
