"""Tables on disk: CSV with ``name [unit]`` headers or Parquet with units in its
metadata, read and written; every write is atomic.

Inside pneumact everything is SI. ``write_table`` writes a frame with the unit of each
column; ``read_table`` reads it back with the units, unconverted (``records`` converts
measured records to SI). ``atomic_write`` is how every output file of pneumact is
written: to a temporary file beside the target, moved over it only on success.
"""

from __future__ import annotations

import contextlib
import csv
import gzip
import importlib
import json
import os
import re
import shutil
import tempfile
import threading
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pneumact.errors import DataError
from pneumact.files import atomic_write

if TYPE_CHECKING:  # pandas is imported where a table is read or a frame written: a
    import pandas as pd  # simulation's CSV is written without it (start-up, issue 20)

__all__ = ["RUN_LISTING", "UNITS_METADATA_KEY", "atomic_write", "parse_cell", "partial_folder",
           "read_table", "staged_folder", "write_columns", "write_files", "write_table"]

PathLike = str | os.PathLike[str]

#: Parquet schema-metadata key holding ``{column: unit}`` as JSON.
UNITS_METADATA_KEY = b"pneumact.units"

_SUFFIXES = (".csv", ".parquet")
_CELL_RE = re.compile(r"^\s*(?P<name>.*?)\s*(?:\[(?P<u1>[^\[\]]*)\]|\((?P<u2>[^()]*)\))\s*$")
_WS_TOKEN_RE = re.compile(r"\s*([^\s\[\]()]+(?:\s*(?:\[[^\[\]]*\]|\([^()]*\)))?)")


def _float_kw() -> dict[str, Any]:
    """pandas >= 3 parses floats round-trip exactly by default and deprecates the option."""
    import pandas as pd

    return {"float_precision": "round_trip"} if int(pd.__version__.split(".")[0]) < 3 else {}


# --------------------------------------------------------------------------- writing


#: The list of what the last run wrote into an output folder (hidden, JSON), so that the
#: next run into that folder replaces exactly those files and leaves any other alone.
RUN_LISTING = ".pneumact-run.json"
PARTIAL_SUFFIX = ".pneumact-partial"

_OPEN_STAGES: set[Path] = set()
_STAGES_LOCK = threading.Lock()


def partial_folder(out_dir: PathLike) -> Path:
    """Where an interrupted resumable run into ``out_dir`` is kept: a hidden sibling."""
    out = Path(out_dir).resolve()
    return out.parent / f".{out.name}{PARTIAL_SUFFIX}"


#: the lock a run holds on its output folder while it writes (a hidden sibling: JSON with
#: the process id, host and start time), so that a second run into the same folder is
#: told another run holds it instead of being advised to overwrite the running one
LOCK_SUFFIX = ".pneumact-lock"
_HELD_LOCKS: dict[Path, int] = {}  # this process's locks (re-entered, not refused)


def lock_file(out_dir: PathLike) -> Path:
    """The lock file of output folder ``out_dir``: a hidden sibling."""
    out = Path(out_dir).resolve()
    return out.parent / f".{out.name}{LOCK_SUFFIX}"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # a process of another user, or a platform that cannot tell: alive
    return True


def _lock_holder(lock: Path) -> dict | None:
    """The holder of ``lock`` if it is alive (or on another host); None when the lock
    is stale (its process ended without removing it) or unreadable half-written."""
    import socket

    try:
        holder = json.loads(lock.read_text(encoding="utf-8"))
        pid = int(holder["pid"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if holder.get("host") not in (None, socket.gethostname()):
        return holder
    return holder if _pid_alive(pid) else None


@contextlib.contextmanager
def folder_lock(out_dir: PathLike, display: object = None) -> Iterator[None]:
    """Hold the lock of output folder ``out_dir`` for the block: refused (an
    ``ArgumentError`` naming the process) while another live run holds it; a stale lock
    (its process is gone) is taken over; re-entered freely within this process."""
    import socket
    import time

    from pneumact.errors import ArgumentError

    lock = lock_file(out_dir)
    with _STAGES_LOCK:
        if lock in _HELD_LOCKS:
            _HELD_LOCKS[lock] += 1
            mine = False
        else:
            mine = True
    if mine:
        record = json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                             "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
        for _ in range(3):
            try:
                fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = _lock_holder(lock)
                if holder is not None:
                    raise ArgumentError(
                        f"{display or out_dir}: another run (pid {holder.get('pid')} on "
                        f"{holder.get('host')}, started {holder.get('started')}) is writing "
                        "this folder",
                        api_hint="wait for it to finish or write elsewhere",
                        cli_hint="wait for it to finish or choose another --out "
                                 f"(should that run be gone, remove {lock})") from None
                with contextlib.suppress(OSError):
                    lock.unlink()  # stale: its process is gone
                continue
            with os.fdopen(fd, "w", encoding="utf-8") as handle:
                handle.write(record)
            break
        else:
            raise ArgumentError(f"{display or out_dir}: could not take the lock {lock}")
        with _STAGES_LOCK:
            _HELD_LOCKS[lock] = 1
    try:
        yield
    finally:
        with _STAGES_LOCK:
            _HELD_LOCKS[lock] -= 1
            last = _HELD_LOCKS[lock] == 0
            if last:
                del _HELD_LOCKS[lock]
        if last:
            with contextlib.suppress(OSError):
                lock.unlink()


def _inside_open_stage(path: Path) -> bool:
    resolved = path.resolve()
    with _STAGES_LOCK:
        return any(resolved == s or s in resolved.parents for s in _OPEN_STAGES)


def _listing(folder: Path) -> dict:
    try:
        listing = json.loads((folder / RUN_LISTING).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return listing if isinstance(listing, dict) else {}


def _listed(folder: Path) -> list[str]:
    """The entries the run that wrote ``folder`` listed (plain names only)."""
    names = _listing(folder).get("files")
    if not isinstance(names, list):
        return []
    return [n for n in names if isinstance(n, str) and n and n not in (".", "..")
            and "/" not in n and os.sep not in n]


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


def _link_or_copy(src: str, dst: str) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def _seed(stage: Path, out: Path) -> None:
    """The previous run's files, hard-linked into a fresh stage (files pneumact writes are
    replaced, never changed in place, so sharing them is safe): what a resume reuses."""
    names = _listed(out) or [p.name for p in out.iterdir() if not p.name.startswith(".")]
    for name in names:
        src = out / name
        if src.is_dir():
            shutil.copytree(src, stage / name, copy_function=_link_or_copy)
        elif src.is_file():
            _link_or_copy(str(src), str(stage / name))


def _commit(stage: Path, out: Path, replace: bool, resumable: bool = False) -> list[str]:
    """Move the stage's entries into ``out``: the whole stage becomes ``out`` when it did
    not exist; else the previous run's entries are moved aside first (and restored if a
    move fails), then removed. With ``replace`` False the entries are only added."""
    entries = sorted(p.name for p in stage.iterdir() if p.name != RUN_LISTING)
    if replace:
        import time

        from ..version import __version__

        listing = {"files": entries, "pneumact": __version__, "resumable": resumable,
                   "written": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        (stage / RUN_LISTING).write_text(json.dumps(listing, indent=1), encoding="utf-8")
    if replace and not out.exists():
        os.rename(stage, out)
        return entries
    out.mkdir(parents=True, exist_ok=True)
    incoming = [*entries, RUN_LISTING] if replace else entries
    outgoing = sorted(set(_listed(out) if replace else []) | set(incoming))
    backup = Path(tempfile.mkdtemp(prefix=f".{out.name}.pneumact-old-", dir=out.parent))
    moved_out: list[str] = []
    moved_in: list[str] = []
    try:
        for name in outgoing:
            if (out / name).exists() or (out / name).is_symlink():
                os.rename(out / name, backup / name)
                moved_out.append(name)
        for name in incoming:
            os.rename(stage / name, out / name)
            moved_in.append(name)
    except BaseException:
        for name in moved_in:
            with contextlib.suppress(OSError):
                os.rename(out / name, stage / name)
        for name in moved_out:
            with contextlib.suppress(OSError):
                os.rename(backup / name, out / name)
        raise
    finally:
        shutil.rmtree(backup, ignore_errors=True)
    shutil.rmtree(stage, ignore_errors=True)
    return entries


@contextlib.contextmanager
def staged_folder(out_dir: PathLike, *, resumable: bool = False, resume: bool = False,
                  overwrite: bool = False) -> Iterator[Path]:
    """Build a run's outputs in a sibling folder, then swap them into ``out_dir``.

    Yields the staging folder (in the same parent directory, so every move is a rename).
    On success its entries replace the previous run's in ``out_dir``: the files that run
    listed are removed even where the new run does not write them, and files no pneumact
    run wrote are left alone. On failure ``out_dir`` is left exactly as it was.

    A ``resumable`` run stages in a fixed hidden sibling (``.NAME.pneumact-partial``),
    kept when the run is interrupted (Ctrl-C, a kill, a crash) so that ``resume``
    continues it, and removed when it stops on a user's mistake (a pneumact error)
    unless it was already there. ``resume`` seeds a fresh stage with the previous
    complete run (hard links); ``overwrite`` discards a kept interrupted run. Inside
    another run's stage (a command writing several parts) a non-resumable stage only
    adds its files.
    """
    from pneumact.checks import check_out_dir

    display = check_out_dir("out_dir", out_dir)
    out = display.resolve()  # "." has a parent to stage in
    out.parent.mkdir(parents=True, exist_ok=True)
    nested = not resumable and _inside_open_stage(out)
    with contextlib.ExitStack() as locked:
        if not nested:
            locked.enter_context(folder_lock(out, display))
        yield from _staged(display, out, nested, resumable, resume, overwrite)


def _staged(display: Path, out: Path, nested: bool, resumable: bool, resume: bool,
            overwrite: bool) -> Iterator[Path]:
    """``staged_folder``'s work, once the folder's lock is held."""
    from pneumact.errors import ArgumentError, PneumactError

    existed = False
    if resumable:
        stage = partial_folder(out)
        existed = stage.exists()
        if existed and overwrite:
            shutil.rmtree(stage)
            existed = False
        elif existed and not resume:
            raise ArgumentError(
                f"{display}: the interrupted run kept in {stage.name} beside it would be "
                "lost",
                api_hint="continue it (resume=True) or start again (overwrite=True)",
                cli_hint="continue it (--resume) or start again (--overwrite)")
        if not existed and not (resume or overwrite) and _listing(out).get("resumable"):
            raise ArgumentError(
                f"{display} holds the kept runs of an earlier run",
                api_hint="continue them (resume=True) or start again (overwrite=True)",
                cli_hint="continue them (--resume) or start again (--overwrite)")
        if not existed:
            stage.mkdir()
            if resume and out.is_dir():
                _seed(stage, out)
    else:
        stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.pneumact-stage-", dir=out.parent))
    key = stage.resolve()
    with _STAGES_LOCK:
        _OPEN_STAGES.add(key)
    try:
        yield stage
    except PneumactError:
        if not existed:
            shutil.rmtree(stage, ignore_errors=True)
        raise
    except BaseException:
        if not resumable:
            shutil.rmtree(stage, ignore_errors=True)
        raise
    finally:
        with _STAGES_LOCK:
            _OPEN_STAGES.discard(key)
    try:
        _commit(stage, out, replace=not nested, resumable=resumable)
    except BaseException:
        if not resumable:
            shutil.rmtree(stage, ignore_errors=True)
        raise


def write_files(out_dir: PathLike, writers: Mapping[str, Any]) -> list[Path]:
    """Write a set of files together: ``writers`` maps each file name to a function that
    writes it to a given path. They run in order in one staging folder beside
    ``out_dir`` (so a later one may read the files of earlier ones beside its path, a
    report embedding them), and the set replaces the previous run's files in
    ``out_dir`` only when all are written (``staged_folder``): no partial set of
    outputs, no stale file of the run before."""
    for name in writers:
        if not name or Path(name).name != name:
            raise ValueError(f"write_files: {name!r} is not a plain file name")
    with staged_folder(out_dir) as stage:
        for name, write in writers.items():
            write(stage / name)
            if not (stage / name).exists():
                raise FileNotFoundError(f"write_files: nothing was written to {name}")
    return [Path(out_dir) / name for name in writers]


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
    unit_of = _checked_units(target, names, units)
    if suffix == ".csv":
        cells = _csv_header(target, names, unit_of)
        if all(_plain_number(dtype) for dtype in frame.dtypes):
            _write_csv_numbers(target, cells, [frame[n].to_numpy() for n in names])
        else:
            with atomic_write(target) as tmp:
                frame.to_csv(tmp, index=False, header=cells, lineterminator="\n",
                             encoding="utf-8")
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


def write_columns(columns: Mapping[str, np.ndarray], path: PathLike,
                  units: Mapping[str, str]) -> Path:
    """``write_table`` for numeric columns given as arrays (``time`` first, say): a CSV is
    written without pandas, byte for byte as ``write_table`` writes it, so that a run's
    CSV costs no pandas import (start-up of ``pneumact simulate``)."""
    target = Path(path)
    if _check_suffix(target) != ".csv":
        import pandas as pd

        return write_table(pd.DataFrame(dict(columns)), target, units)
    names = list(columns)
    arrays = [np.asarray(columns[n]) for n in names]
    if len({a.shape for a in arrays}) > 1 or any(a.ndim != 1 for a in arrays):
        raise DataError(f"{target}: columns must be 1-D arrays of one length; got "
                        + ", ".join(f"{n} {a.shape}" for n, a in zip(names, arrays,
                                                                     strict=True)))
    if not all(_plain_number(a.dtype) for a in arrays):
        import pandas as pd

        return write_table(pd.DataFrame(dict(zip(names, arrays, strict=True))), target, units)
    cells = _csv_header(target, names, _checked_units(target, names, units))
    _write_csv_numbers(target, cells, arrays)
    return target


def _plain_number(dtype) -> bool:
    """A column ``_write_csv_numbers`` writes as pandas does: float64, integers, bools."""
    return dtype == np.float64 or getattr(dtype, "kind", "") in "iub"


def _checked_units(target: Path, names: Sequence[Any], units: Mapping[str, str]) -> dict:
    """The unit of each named column, after checking names are unique non-empty strings
    and that every unit names a column."""
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
    return {n: str(units[n]).strip() for n in names if n in units and str(units[n]).strip()}


def _csv_header(target: Path, names: Sequence[str], unit_of: Mapping[str, str]) -> list[str]:
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
    return cells


def _write_csv_numbers(target: Path, cells: Sequence[str], arrays: Sequence[np.ndarray]):
    """Numeric columns as pandas' ``to_csv`` writes them: the shortest text that reads back
    exactly (Python's ``repr`` of each float), NaN as an empty cell."""
    def text(array: np.ndarray) -> list[str]:
        out = [repr(v) for v in array.tolist()]
        if array.dtype.kind == "f":
            for i in np.flatnonzero(np.isnan(array)):
                out[i] = ""
        return out

    rows = zip(*(text(a) for a in arrays), strict=True)
    with atomic_write(target) as tmp, open(tmp, "w", encoding="utf-8", newline="") as f:
        f.write(_csv_line(cells))
        f.writelines(",".join(row) + "\n" for row in rows)


def _csv_line(cells: Sequence[str]) -> str:
    """One CSV line, quoted as pandas quotes (minimal quoting)."""
    import io

    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(cells)
    return buffer.getvalue()


# --------------------------------------------------------------------------- reading


def require_file(path: Path) -> None:
    if not path.exists():
        raise DataError(f"{path}: file not found")
    if path.is_dir():
        raise DataError(f"{path}: is a folder; a file is expected here")
    if not path.is_file():
        raise DataError(f"{path}: is not a file")


def parse_cell(cell: str) -> tuple[str, str | None]:
    """Split a header cell ``name [unit]`` or ``name (unit)`` into (name, unit or None)."""
    match = _CELL_RE.match(cell)
    if match is None:
        return cell.strip(), None
    unit = match["u1"] if match["u1"] is not None else match["u2"]
    unit = unit.strip()
    return match["name"], unit or None


def _open_text(path: Path):
    """A text file (gzip-compressed when it ends in .gz), a UTF-8 BOM skipped."""
    if path.suffix.lower() == ".gz":
        return gzip.open(path, "rt", encoding="utf-8-sig", newline="")
    return open(path, encoding="utf-8-sig", newline="")


def _first_lines(path: Path) -> tuple[int, str, str]:
    """(0-based index, text) of the first non-blank line (the header, or the first row),
    and the text of the next non-blank line ('' if none)."""
    found: list[tuple[int, str]] = []
    try:
        with _open_text(path) as fh:
            for index, line in enumerate(fh):
                if line.strip():
                    found.append((index, line.rstrip("\r\n")))
                    if len(found) == 2:
                        break
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: is not UTF-8 text ({exc.reason} at byte {exc.start})") from exc
    except (OSError, EOFError) as exc:  # gzip.BadGzipFile is an OSError
        raise DataError(f"{path}: cannot read as gzip-compressed text ({exc})") from exc
    if not found:
        raise DataError(f"{path}: file is empty")
    return found[0][0], found[0][1], found[1][1] if len(found) > 1 else ""


def _first_line(path: Path) -> tuple[int, str]:
    """(0-based index, text) of the first non-blank line: the header, or the first row."""
    index, line, _ = _first_lines(path)
    return index, line


#: a number written with a decimal comma, as a field of a ';'-separated line
_DECIMAL_COMMA_RE = re.compile(r"(?:^|;)\s*[-+]?\d*,\d")


def _dialect(line: str, following: str) -> tuple[str, str]:
    """(separator, decimal mark) of a text table from its first two lines: ';' with
    decimal commas (a spreadsheet in a German or French locale), ',' or whitespace."""
    if ";" in line:
        return ";", "," if _DECIMAL_COMMA_RE.search(following or line) else "."
    if "," in line:
        return ",", "."
    return r"\s+", "."


def _split_header(path: Path, line: str, sep: str) -> list[str]:
    """Header cells of ``line``; in whitespace mode ``time [s]`` stays one cell."""
    if sep != r"\s+":
        return [c.strip() for c in next(csv.reader([line], delimiter=sep))]
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


def drop_unnamed_empty(path: Path, frame: pd.DataFrame, cells: list[str]
                       ) -> tuple[pd.DataFrame, list[str]]:
    """Drop the columns without a header name that hold nothing (a spreadsheet's
    trailing separators: 'a,b,'); an unnamed column that holds data is refused."""
    unnamed = [i for i, c in enumerate(cells) if not c.strip()]
    if not unnamed:
        return frame, cells
    for i in unnamed:
        column = frame.iloc[:, i]
        text = column.astype(object).map(lambda v: "" if v is None or v != v else str(v))
        filled = np.flatnonzero(text.str.strip().to_numpy() != "")
        if filled.size:
            raise DataError(f"{path}: column {i + 1} has no name in the header but holds "
                            f"data ({text.iloc[filled[0]].strip()} at data row "
                            f"{filled[0] + 1}); name it, e.g. 'force [N]', or delete it")
    keep = [i for i in range(len(cells)) if i not in unnamed]
    frame = frame.iloc[:, keep]
    frame.columns = list(range(len(keep)))
    return frame, [cells[i] for i in keep]


def read_text(
    path: Path, names: Sequence[str] | None, *, numeric: bool
) -> tuple[pd.DataFrame, list[str]]:
    """Read a CSV/whitespace text file; return the cells (by position) and header cells.

    ',' or ';' separated (';' with decimal commas too, as spreadsheets write them in
    many locales), or whitespace; gzip-compressed when the name ends in .gz; a UTF-8
    BOM is skipped; header columns without a name and without data are dropped.
    With ``numeric`` the fast path parses floats; if a cell is not a number it rereads
    everything as text so the caller can report exactly which cell is wrong.
    """
    import pandas as pd

    first, line, following = _first_lines(path)
    sep, decimal = _dialect(line, following)
    if names is None:
        cells = _split_header(path, line, sep)
        skip = first + 1
    else:
        cells = [str(n) for n in names]
        found = (len(next(csv.reader([line], delimiter=sep))) if sep != r"\s+"
                 else len(line.split()))
        if found != len(cells):
            raise DataError(
                f"{path}: names= gives {len(cells)} column names but the file has "
                f"{found} columns in its first line"
            )
        skip = first
    kwargs: dict[str, Any] = dict(
        sep=sep,
        decimal=decimal,
        header=None,
        skiprows=skip,
        names=list(range(len(cells))),
        index_col=False,
        encoding="utf-8-sig",
        skipinitialspace=True,
        **_float_kw(),
    )
    try:
        if numeric:
            try:
                frame = pd.read_csv(path, dtype="float64", **kwargs)
            except pd.errors.ParserError:
                raise
            except ValueError:
                frame = pd.read_csv(path, dtype=str, keep_default_na=False, **kwargs)
                if decimal == ",":  # the text reread keeps the commas: make them points
                    frame = frame.apply(lambda c: c.str.replace(",", ".", regex=False))
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
    return drop_unnamed_empty(path, frame, cells)


def read_excel(path: Path) -> tuple[pd.DataFrame, list[str]]:
    """The first sheet of an Excel workbook (.xlsx, with the optional openpyxl): its
    first non-empty row is the header; (cells by position, header cells)."""
    import pandas as pd

    if path.suffix.lower() == ".xls":
        raise DataError(f"{path}: an old Excel workbook (.xls) is not read; save the sheet "
                        "as .xlsx or as CSV (UTF-8)")
    try:
        importlib.import_module("openpyxl")  # optional: pandas reads .xlsx through it
    except ImportError:
        raise DataError(f"{path}: an Excel workbook (.xlsx): reading it needs the optional "
                        "package openpyxl (pip install openpyxl); or save the sheet as CSV "
                        "(UTF-8)") from None
    try:
        sheet = pd.read_excel(path, sheet_name=0, header=None, dtype=object)
    except Exception as exc:  # openpyxl and zipfile raise several unrelated types
        raise DataError(f"{path}: cannot read as an Excel workbook ({exc})") from exc
    sheet = sheet.dropna(how="all")
    if sheet.empty:
        raise DataError(f"{path}: the first sheet is empty")
    cells = ["" if v is None or v != v else str(v).strip() for v in sheet.iloc[0]]
    frame = sheet.iloc[1:].reset_index(drop=True)
    frame.columns = list(range(len(cells)))
    return drop_unnamed_empty(path, frame, cells)


def read_parquet(path: Path) -> tuple[pd.DataFrame, dict[str, str]]:
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
    require_file(source)
    if source.suffix.lower() == ".parquet":
        return read_parquet(source)
    frame, cells = read_text(source, None, numeric=False)
    parsed = [parse_cell(c) for c in cells]
    names = [n for n, _ in parsed]
    check_unique(source, names)
    frame.columns = names
    return frame, {n: u for n, u in parsed if u is not None}


def check_unique(path: Path, names: Sequence[str]) -> None:
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise DataError(f"{path}: duplicate column names {duplicates}; names must be unique")
