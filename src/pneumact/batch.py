"""Batch simulation: one model and experiment, N parameter sets, all cores or a Dask cluster.

    table = pd.DataFrame({"Fc": [2.0, 2.6, 3.0], "Fs": [3.0, 3.2, 3.5]})      # SI values
    batch = simulate_batch(actuator, experiment, table, features=["stroke", "loop_area"])
    batch.table                    # the parameters + one column per feature + status/error

Each row of ``table`` replaces those entries of the model's parameter vector. The kernel
is prepared once and called directly per set (no ``Result`` objects), and only the
requested scalar features (or the requested signals on the output grid) are kept, so
memory grows with N × what was asked for. A set that fails (invalid values, solver
failure, any exception) gets ``status`` != "ok" and an ``error`` message; the others
finish. Rows are processed in chunks: by threads locally (the kernels release the GIL),
or as tasks on a Dask cluster (``scheduler=``), with identical results.

With ``out_dir`` the batch is resumable: ``manifest.json`` (what the batch is) is written
first, then every finished chunk atomically as ``chunks/chunk-00012.parquet``; a run
started again on the same directory with the same arguments computes only the missing
chunks. At the end ``results.parquet`` and ``summary.csv`` hold the parameters, features,
status and error per row (column ``row`` = position in the input table), and, when
signals were requested, ``signals.parquet`` holds them in long form: one line per set and
output time, columns ``row``, ``time`` and one per signal.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import hashlib
import json
import math
import os
import threading
import time as _time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from . import features as _features
from .errors import DataError, ParameterError, PneumactError
from .experiments.actuator import Experiment
from .models.actuator import rest_position
from .parameters import INDEX, SPECS, ParameterSet, validate
from .simulation.simulate import STATUS_TEXT, prepare
from .simulation.solvers import Rodas4, Solver

__all__ = ["ALL_FEATURES", "FEATURE_UNITS", "BatchResult", "simulate_batch"]

#: Features computed on the pressure-position record (need an actuator).
HYSTERESIS_FEATURES = ("stroke", "loop_width_pressure", "loop_width_position", "loop_area",
                       "breakaway_pressure")
#: Features against a reference record (need ``reference=``).
REFERENCE_FEATURES = ("rms_error", "max_error")
ALL_FEATURES = ("final_position", "max_velocity", *HYSTERESIS_FEATURES, *REFERENCE_FEATURES)
FEATURE_UNITS: dict[str, str] = {
    "final_position": "m", "max_velocity": "m/s", **_features.FEATURE_UNITS,
}
STATUS_OK = "ok"
STATUS_INVALID = "invalid"  # a parameter value out of its range
STATUS_SOLVER = "solver"  # the integrator failed (step underflow, NaN, max_steps)
STATUS_ERROR = "error"  # anything else (e.g. a feature could not be computed)
MANIFEST_FORMAT = "pneumact-batch/1"
MAX_DEFAULT_CHUNK = 250  # rows; keeps progress and checkpoints frequent on big batches


# --------------------------------------------------------------------------- specification


@dataclass(frozen=True, eq=False)
class BatchSpec:
    """Everything a chunk needs besides its rows; picklable, sent once to Dask workers."""

    model: Any
    experiment: Experiment
    solver: Solver
    columns: tuple[str, ...]
    features: tuple[str, ...]
    signals: tuple[str, ...]
    t_eval: np.ndarray | None = None
    reference: tuple[np.ndarray, np.ndarray] | None = None

    def describe(self) -> dict[str, Any]:
        """JSON-able description (large arrays hashed) used for the manifest and caching."""
        model, exp, solver = self.model, self.experiment, self.solver
        channels = model.channels(exp.drive)
        return {
            "model": {
                "type": type(model).__name__,
                "description": model.describe() if hasattr(model, "describe") else repr(model),
                "kernel": model.kernel_key(),
                "parameter_set": getattr(model.params, "name", "custom"),
                "vector": _hash_array(model.vector()),
                "channels": [None if c is None else _hash_array(c.encode())
                             for c in channels[1:]],
            },
            "experiment": {
                "name": exp.name, "quantity": exp.quantity, "t_start": exp.t_start,
                "t_end": exp.t_end, "n_points": int(exp.n_points),
                "drive": _hash_array(exp.drive.encode()),
                "breakpoints": _hash_array(exp.breakpoints()),
            },
            "solver": {
                "type": type(solver).__name__, "rtol": solver.rtol,
                "atol": solver.atol if not isinstance(solver.atol, Mapping)
                else dict(sorted(solver.atol.items())),
                "h_init": solver.h_init, "h_max": repr(solver.h_max),
                "max_steps": int(solver.max_steps),
            },
            "columns": list(self.columns),
            "features": list(self.features),
            "signals": list(self.signals),
            "t_eval": None if self.t_eval is None else _hash_array(self.t_eval),
            "reference": None if self.reference is None
            else [_hash_array(self.reference[0]), _hash_array(self.reference[1])],
        }

    def token(self) -> str:
        return hashlib.sha256(json.dumps(self.describe(), sort_keys=True).encode()).hexdigest()


def _hash_array(values) -> str:
    array = np.ascontiguousarray(np.asarray(values, dtype=np.float64))
    return hashlib.sha256(array.tobytes()).hexdigest()[:32]


@dataclass
class ChunkOutput:
    """What one chunk of rows produced (features, status, error, signals, counters)."""

    start: int
    features: np.ndarray  # n × len(spec.features)
    status: list[str]
    error: list[str]
    signals: dict[str, np.ndarray]  # name -> n × len(t_out)
    steps: int = 0


# --------------------------------------------------------------------------- the runner


class _RowParams(Mapping):
    """A read-only view of one kernel parameter vector by name (for ``state_scales``)."""

    def __init__(self, prm: np.ndarray):
        self._prm = prm

    def __getitem__(self, name: str) -> float:
        return float(self._prm[INDEX[name]])

    def __iter__(self):
        return iter(INDEX)

    def __len__(self) -> int:
        return len(INDEX)


class _Runner:
    """The prepared kernel of one batch, and the per-set loop over a chunk of rows."""

    def __init__(self, spec: BatchSpec):
        self.spec = spec
        model, exp = spec.model, spec.experiment
        (self.kernel, self.prm0, self.sig, self.ptr, self.bp, self.t_out, self.y0,
         self.atol0) = prepare(model, exp, spec.solver, spec.t_eval)
        self.fn = getattr(self.kernel, spec.solver.kernel_function)
        self.col_index = np.array([INDEX[c] for c in spec.columns], dtype=np.int64)
        self.sources = _signal_sources(self.kernel, exp.quantity)
        self.given = dict(model.params)  # the base set's given values, for validation
        self.p0 = float(exp.drive(exp.t_start))
        self.init_columns = _initial_state_columns(model, spec.columns)

    # -- per-row pieces ------------------------------------------------------------------
    def _problem(self, values: np.ndarray) -> str | None:
        """Why this row's values are invalid (catalogue ranges, relations), or None."""
        merged = {**self.given, **{c: float(v) for c, v in zip(self.spec.columns, values,
                                                               strict=True)}}
        try:
            validate(merged, "batch row")
        except ParameterError as exc:
            return str(exc).replace("invalid parameter set 'batch row'", "invalid parameters")
        return None

    def _initial_states(self, prms: np.ndarray, values: np.ndarray, ok: np.ndarray
                        ) -> tuple[np.ndarray, list[str | None]]:
        """Static-equilibrium initial state of every row (mirrors ``initial_state``)."""
        n = prms.shape[0]
        y0 = np.repeat(self.y0[None, :], n, axis=0)
        problems: list[str | None] = [None] * n
        model = self.spec.model
        if not self.init_columns:
            return y0, problems
        if (getattr(model, "model", "") == "actuator" and model.valve.prefix == "source"
                and model.load is None and model.load_map is None):
            y0[:, 0] = _source_equilibrium(self.p0, prms)
            return y0, problems
        cache: dict[tuple, np.ndarray] = {}
        picks = [self.spec.columns.index(c) for c in self.init_columns]
        for i in np.flatnonzero(ok):
            key = tuple(values[i, picks])
            if key not in cache:
                try:
                    changes = {c: float(values[i, j]) for c, j in zip(
                        self.init_columns, picks, strict=True)}
                    params = ParameterSet({**self.given, **changes}, name="batch row")
                    row_model = dataclasses.replace(model, params=params)
                    cache[key] = np.asarray(row_model.initial_state(
                        self.spec.experiment.drive, self.spec.experiment.t_start), dtype=float)
                except Exception as exc:  # reported per row
                    problems[i] = f"initial state: {exc}"
                    continue
            y0[i] = cache[key]
        return y0, problems

    def _atol(self, prm: np.ndarray) -> np.ndarray:
        """Absolute tolerances of one set: the solver's rule with this set's state scales."""
        model = self.spec.model
        if not hasattr(model, "state_scales"):
            return self.atol0
        view = copy.copy(model)
        object.__setattr__(view, "params", _RowParams(prm))
        scales = model.state_scales.__func__(view, prm)
        return self.spec.solver.atol_vector(self.kernel.STATE_NAMES, scales)

    def _features(self, y_out: np.ndarray, out: np.ndarray) -> list[float]:
        spec, t = self.spec, self.t_out

        cache: dict[str, np.ndarray] = {}

        def signal(name: str) -> np.ndarray:
            # Contiguous copies, as in Result: strided views would let BLAS sum the
            # dot products of loop_area in another order (last-bit differences).
            if name not in cache:
                kind, j = self.sources[name]
                cache[name] = np.ascontiguousarray((y_out if kind == "state" else out)[:, j])
            return cache[name]

        values = []
        for name in spec.features:
            if name == "final_position":
                values.append(float(signal("position")[-1]))
            elif name == "max_velocity":
                values.append(float(np.max(np.abs(signal("velocity")))))
            elif name == "stroke":
                values.append(_features.stroke(signal("position")))
            elif name == "breakaway_pressure":
                values.append(_features.breakaway_pressure(t, signal("pressure"),
                                                           signal("position")))
            elif name in REFERENCE_FEATURES:
                fn = getattr(_features, name)
                values.append(fn(t, signal("position"), *spec.reference))
            else:
                values.append(getattr(_features, name)(signal("pressure"), signal("position")))
        return values

    # -- the chunk loop ------------------------------------------------------------------
    def run(self, start: int, values: np.ndarray) -> ChunkOutput:
        """Simulate the rows ``values`` (n × len(columns)); row k is set ``start + k``."""
        spec, solver, kernel = self.spec, self.spec.solver, self.kernel
        values = np.asarray(values, dtype=float).reshape(-1, len(spec.columns))
        n, n_t = values.shape[0], self.t_out.size
        prms = np.repeat(self.prm0[None, :], n, axis=0)
        prms[:, self.col_index] = values
        status = [STATUS_OK] * n
        error = [""] * n
        for i in range(n):
            problem = self._problem(values[i])
            if problem is not None:
                status[i], error[i] = STATUS_INVALID, problem
        ok = np.array([s == STATUS_OK for s in status], dtype=bool)
        y0s, init_problems = self._initial_states(prms, values, ok)
        for i, problem in enumerate(init_problems):
            if problem is not None and status[i] == STATUS_OK:
                status[i], error[i] = STATUS_ERROR, problem
        feats = np.full((n, len(spec.features)), np.nan)
        sigs = {name: np.full((n, n_t), np.nan) for name in spec.signals}
        y_out = np.empty((n_t, kernel.NSTATE))
        out = np.empty((n_t, kernel.NOUT))
        info = np.zeros(8)
        steps = 0
        for i in range(n):
            if status[i] != STATUS_OK:
                continue
            try:
                prm = prms[i]
                y_end = self.fn(y0s[i], prm, self.sig, self.ptr, self.bp, self.t_out,
                                solver.rtol, self._atol(prm), solver.h_init, solver.h_max,
                                solver.max_steps, y_out, out, info)
                steps += int(info[2])
                code = int(info[0])
                if code != 0:
                    state = ", ".join(f"{s}={v:.6g} {u}" for s, v, u in zip(
                        kernel.STATE_NAMES, y_end, kernel.STATE_UNITS, strict=True))
                    status[i] = STATUS_SOLVER
                    error[i] = (f"{type(solver).__name__} failed at t = {info[1]:.9g} s after "
                                f"{int(info[2])} steps: "
                                f"{STATUS_TEXT.get(code, 'unknown failure')}; state: {state}")
                    continue
                feats[i] = self._features(y_out, out)
                for name in spec.signals:
                    kind, j = self.sources[name]
                    sigs[name][i] = (y_out if kind == "state" else out)[:, j]
            except Exception as exc:  # one failing set must not stop the batch
                status[i], error[i] = STATUS_ERROR, f"{type(exc).__name__}: {exc}"
                feats[i] = np.nan
        return ChunkOutput(start, feats, status, error, sigs, steps)


def _signal_sources(kernel, quantity: str) -> dict[str, tuple[str, int]]:
    """Signal name -> ('state' | 'out', column); states win over outputs (as in Result)."""
    sources: dict[str, tuple[str, int]] = {}
    for j, name in enumerate(kernel.STATE_NAMES):
        sources[name] = ("state", j)
    for j, name in enumerate(kernel.OUTPUT_NAMES):
        name = f"drive_{quantity}" if name == "drive" else name
        sources.setdefault(name, ("out", j))
    return sources


def _initial_state_columns(model, columns: Sequence[str]) -> tuple[str, ...]:
    """The table columns the model's initial state depends on."""
    if getattr(model, "model", "") != "actuator":
        return ()
    from .models.actuator import MECHANICS

    relevant = set(MECHANICS) | set(model.valve.required)
    return tuple(c for c in columns if c in relevant)


def _source_equilibrium(p0: float, prms: np.ndarray) -> np.ndarray:
    """Rest position under pressure ``p0`` for each parameter row: the vectorised
    ``Actuator.initial_state`` of an unloaded actuator on a pressure source."""
    net0 = (prms[:, INDEX["p_atm"]] - p0) * prms[:, INDEX["A_d"]] - prms[:, INDEX["F0"]]
    return rest_position(net0, prms[:, INDEX["k"]], prms[:, INDEX["k_stop"]],
                         prms[:, INDEX["x_max"]])


_RUNNERS: dict[str, _Runner] = {}
_RUNNERS_LOCK = threading.Lock()


def run_chunk(spec: BatchSpec, start: int, values: np.ndarray) -> ChunkOutput:
    """Simulate one chunk of rows (the Dask task; the runner is cached per process)."""
    token = spec.token()
    with _RUNNERS_LOCK:
        runner = _RUNNERS.get(token)
        if runner is None:
            runner = _RUNNERS[token] = _Runner(spec)
    return runner.run(start, values)


# --------------------------------------------------------------------------- result


@dataclass
class BatchResult:
    """Results of a batch: ``table`` (parameters + features + status/error, one row per
    set, in input order), ``signals`` (name -> N × len(time) array, NaN for failed sets),
    ``time`` (the output grid), ``stats`` (wall time, sims/s, computed/reused counts)."""

    table: pd.DataFrame
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    time: np.ndarray | None = None
    stats: dict[str, Any] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)

    @property
    def failed(self) -> pd.DataFrame:
        """The rows whose status is not 'ok' (with their error message)."""
        return self.table[self.table["status"] != STATUS_OK]

    def to_pandas(self) -> pd.DataFrame:
        """A copy of ``table`` (units in ``attrs['units']``)."""
        frame = self.table.copy()
        frame.attrs["units"] = dict(self.units)
        return frame

    def __repr__(self) -> str:
        return (f"BatchResult({len(self.table)} sets, {len(self.failed)} failed, "
                f"features={[c for c in self.table.columns if c in FEATURE_UNITS]}, "
                f"signals={list(self.signals)})")


# --------------------------------------------------------------------------- checks


def _check_table(table) -> tuple[tuple[str, ...], np.ndarray]:
    if not isinstance(table, pd.DataFrame):
        raise ParameterError(
            f"table must be a pandas DataFrame (one column per parameter), got "
            f"{type(table).__name__}")
    columns = [str(c) for c in table.columns]
    if not columns:
        raise ParameterError("table has no columns; give one column per parameter name")
    if len(table) == 0:
        raise ParameterError("table has no rows; give one row per parameter set")
    duplicates = sorted({c for c in columns if columns.count(c) > 1})
    if duplicates:
        raise ParameterError(f"table has duplicate parameter columns {duplicates}")
    for name in columns:
        if name not in SPECS:
            close = difflib.get_close_matches(name, list(SPECS), n=1, cutoff=0.6)
            hint = f" (did you mean '{close[0]}'?)" if close else \
                f" (known: {', '.join(SPECS)})"
            raise ParameterError(f"table column '{name}' is not a parameter name{hint}")
    try:
        values = table.to_numpy(dtype=np.float64)
    except (TypeError, ValueError):
        for name in columns:
            converted = pd.to_numeric(table[name], errors="coerce")
            bad = converted.isna() & table[name].notna()
            if bad.any():
                raise ParameterError(
                    f"table column '{name}' row {int(np.flatnonzero(bad)[0])} = "
                    f"{table[name][bad].iloc[0]!r}: must be a number (SI value)") from None
        raise
    return tuple(columns), np.ascontiguousarray(values)


def _check_names(kind: str, wanted: Sequence[str], allowed: Sequence[str]) -> tuple[str, ...]:
    wanted = tuple(dict.fromkeys(str(w) for w in wanted))
    for name in wanted:
        if name not in allowed:
            close = difflib.get_close_matches(name, list(allowed), n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'?" if close else f"allowed: {', '.join(allowed)}"
            raise ParameterError(f"unknown {kind} '{name}' ({hint})")
    return wanted


def _check_reference(reference) -> tuple[np.ndarray, np.ndarray] | None:
    if reference is None:
        return None
    if hasattr(reference, "__getitem__") and not isinstance(reference, (tuple, list)):
        try:
            reference = (reference["time"], reference["position"])
        except (KeyError, IndexError) as exc:
            raise DataError(f"reference record needs 'time' and 'position' ({exc})") from exc
    if len(reference) != 2:
        raise DataError("reference must be (time, position) arrays or a Record with them")
    t, x = (np.asarray(a, dtype=float) for a in reference)
    if t.ndim != 1 or t.shape != x.shape or t.size < 2:
        raise DataError(f"reference time {t.shape} and position {x.shape} must be 1-D arrays "
                        "of the same length (>= 2)")
    return t, x


# --------------------------------------------------------------------------- out_dir


def _chunk_path(out_dir: Path, index: int, signals: bool = False) -> Path:
    return out_dir / "chunks" / f"chunk-{index:05d}{'.signals' if signals else ''}.parquet"


def _table_hash(columns: Sequence[str], values: np.ndarray) -> str:
    digest = hashlib.sha256(json.dumps(list(columns)).encode())
    digest.update(np.ascontiguousarray(values, dtype=np.float64).tobytes())
    return digest.hexdigest()


def _open_out_dir(out_dir: Path, manifest: dict, resume: bool) -> bool:
    """Write the manifest, or check an existing one; True if chunks may be reused."""
    from .io import atomic_write

    path = out_dir / "manifest.json"
    if path.exists():
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except ValueError as exc:
            raise DataError(f"{path}: is not a readable batch manifest ({exc})") from exc
        differs = sorted(k for k in set(old) | set(manifest) if old.get(k) != manifest.get(k))
        if differs:
            raise DataError(
                f"{out_dir} holds a different batch (its manifest differs in: "
                f"{', '.join(differs)}); use another directory or delete it, batches are "
                "never mixed")
        for stale in (out_dir / "chunks").glob(".chunk-*.tmp-*"):  # left by a killed run
            stale.unlink(missing_ok=True)
        return True
    del resume  # nothing to resume: start from scratch
    with atomic_write(path) as tmp:
        tmp.write_text(json.dumps(manifest, indent=1, sort_keys=True), encoding="utf-8")
    return False


def _write_chunk(out_dir: Path, index: int, chunk: ChunkOutput, spec: BatchSpec,
                 t_out: np.ndarray) -> None:
    """Signals first, then the chunk table: the table's presence marks the chunk done."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .io import atomic_write

    n = len(chunk.status)
    rows = np.arange(chunk.start, chunk.start + n, dtype=np.int64)
    if spec.signals:
        columns = {"row": np.repeat(rows, t_out.size), "time": np.tile(t_out, n)}
        for name in spec.signals:
            columns[name] = chunk.signals[name].reshape(-1)
        with atomic_write(_chunk_path(out_dir, index, True)) as tmp:
            pq.write_table(pa.table(columns), tmp)
    columns = {"row": rows}
    for j, name in enumerate(spec.features):
        columns[name] = chunk.features[:, j]
    columns["status"] = pa.array(chunk.status, type=pa.string())
    columns["error"] = pa.array(chunk.error, type=pa.string())
    columns["steps"] = np.array([chunk.steps] * n, dtype=np.int64)
    with atomic_write(_chunk_path(out_dir, index)) as tmp:
        pq.write_table(pa.table(columns), tmp)


def _read_chunk(out_dir: Path, index: int, start: int, n: int, spec: BatchSpec,
                n_t: int) -> ChunkOutput | None:
    """A finished chunk from disk, or None if missing or unreadable (then recomputed)."""
    import pyarrow.parquet as pq

    path = _chunk_path(out_dir, index)
    if not path.exists():
        return None
    try:
        frame = pq.read_table(path).to_pandas()
        if len(frame) != n or int(frame["row"].iloc[0]) != start:
            return None
        feats = frame[list(spec.features)].to_numpy(dtype=float) if spec.features else \
            np.empty((n, 0))
        sigs = {}
        if spec.signals:
            sframe = pq.read_table(_chunk_path(out_dir, index, True)).to_pandas()
            if len(sframe) != n * n_t:
                return None
            sigs = {name: sframe[name].to_numpy(dtype=float).reshape(n, n_t)
                    for name in spec.signals}
    except Exception:  # a damaged chunk is simply computed again
        return None
    return ChunkOutput(start, np.ascontiguousarray(feats), frame["status"].tolist(),
                       frame["error"].tolist(), sigs, int(frame["steps"].iloc[0]))


def _write_final(out_dir: Path, result: BatchResult) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .io import atomic_write, write_table

    frame = result.table.reset_index(drop=True)
    frame.insert(0, "row", np.arange(len(frame), dtype=np.int64))
    units = {k: v for k, v in result.units.items() if k in frame.columns and v}
    write_table(frame, out_dir / "results.parquet", units)
    write_table(frame, out_dir / "summary.csv", units)
    if result.signals:
        n, n_t = len(frame), result.time.size
        columns = {"row": np.repeat(np.arange(n, dtype=np.int64), n_t),
                   "time": np.tile(result.time, n)}
        columns.update({name: arr.reshape(-1) for name, arr in result.signals.items()})
        with atomic_write(out_dir / "signals.parquet") as tmp:
            pq.write_table(pa.table(columns), tmp)


# --------------------------------------------------------------------------- entry point


def _client_for(scheduler):
    """(client, whether we own it) for an address string or a distributed.Client."""
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - dask is installed here
        raise PneumactError("scheduler= needs dask.distributed (pip install "
                            "'dask[distributed]')") from exc
    if isinstance(scheduler, Client):
        return scheduler, False
    if isinstance(scheduler, str):
        try:
            return Client(scheduler, timeout="20s"), True
        except OSError as exc:
            raise PneumactError(f"cannot reach the Dask scheduler at {scheduler!r}: {exc}"
                                ) from exc
    raise ParameterError(f"scheduler = {scheduler!r}: must be an address string "
                         "('tcp://host:8786') or a distributed.Client")


def simulate_batch(model, experiment: Experiment, table: pd.DataFrame, *,
                   features: Sequence[str] | None = None, signals: Sequence[str] | None = None,
                   t_eval=None, solver: Solver | None = None, scheduler=None,
                   out_dir: str | os.PathLike | None = None, resume: bool = False,
                   chunk_size: int | None = None, workers: int | None = None,
                   progress: Callable[[int, int, int], None] | None = None,
                   reference=None) -> BatchResult:
    """Simulate ``model`` under ``experiment`` once per row of ``table``.

    ``table``: one column per parameter name (SI values), one row per set; each row
    replaces those entries of ``model``'s parameters. ``features``: names from
    ``ALL_FEATURES`` (default: all that apply, none if ``signals`` are asked;
    ``rms_error``/``max_error`` need ``reference=(time, position)``); ``signals``: signal
    names kept on the output grid ``t_eval`` (default the experiment's grid, on which
    features are computed too).
    ``workers`` threads locally (default all cores), or a Dask ``scheduler`` (address or
    ``distributed.Client``). ``out_dir`` makes the batch resumable (see module doc);
    ``progress(done, failed, total)`` is called after each chunk.
    """
    started = _time.perf_counter()
    solver = Rodas4() if solver is None else solver
    if resume and out_dir is None:
        raise ParameterError("resume=True needs out_dir (the directory of the batch to resume)")
    columns, values = _check_table(table)
    reference = _check_reference(reference)
    is_actuator = getattr(model, "model", "") == "actuator"
    if features is None:
        features = ("final_position", "max_velocity", "stroke")
        if is_actuator:
            features = ("final_position", "max_velocity", *HYSTERESIS_FEATURES)
        if reference is not None:
            features = (*features, *REFERENCE_FEATURES)
        if signals:
            features = ()
    features = _check_names("feature", features, ALL_FEATURES)
    if not is_actuator and set(features) & (set(HYSTERESIS_FEATURES) - {"stroke"}):
        raise ParameterError(
            f"features {sorted(set(features) & set(HYSTERESIS_FEATURES))} need a pressure "
            f"signal: use them with an Actuator, not a {type(model).__name__}")
    if reference is None and set(features) & set(REFERENCE_FEATURES):
        raise ParameterError("features rms_error/max_error need reference=(time, position)")
    t_eval = None if t_eval is None else np.asarray(t_eval, dtype=float)
    spec0 = BatchSpec(model, experiment, solver, columns, features, (), t_eval, reference)
    runner = _Runner(spec0)  # prepares the kernel (and checks the experiment) up front
    signals = _check_names("signal", signals or (), list(runner.sources))
    spec = dataclasses.replace(spec0, signals=signals)
    runner.spec = spec
    n, n_t = values.shape[0], runner.t_out.size

    client, own_client = (None, False)
    if scheduler is not None:
        client, own_client = _client_for(scheduler)
    try:
        if client is not None:
            n_workers = max(1, len(client.scheduler_info().get("workers", {})))
        else:
            n_workers = max(1, int(workers) if workers else (os.cpu_count() or 1))
        out_path = None if out_dir is None else Path(out_dir)
        manifest = None
        if out_path is not None:
            manifest = {"format": MANIFEST_FORMAT, "n_rows": n,
                        "table": _table_hash(columns, values), **spec.describe()}
            old = out_path / "manifest.json"
            if chunk_size is None and old.exists():
                try:
                    chunk_size = int(json.loads(old.read_text())["chunk_size"])
                except (ValueError, KeyError, TypeError):
                    chunk_size = None
        if chunk_size is None:
            chunk_size = max(1, min(math.ceil(n / (4 * n_workers)), MAX_DEFAULT_CHUNK))
        chunk_size = int(chunk_size)
        if chunk_size < 1:
            raise ParameterError(f"chunk_size = {chunk_size}: must be >= 1")
        starts = list(range(0, n, chunk_size))
        chunks: list[ChunkOutput | None] = [None] * len(starts)
        reuse = False
        if out_path is not None:
            manifest["chunk_size"] = chunk_size
            reuse = _open_out_dir(out_path, manifest, resume)
        if reuse:
            for c, s in enumerate(starts):
                chunks[c] = _read_chunk(out_path, c, s, min(chunk_size, n - s), spec, n_t)
        reused = sum(ch is not None for ch in chunks)
        todo = [c for c, ch in enumerate(chunks) if ch is None]
        done = sum(len(ch.status) for ch in chunks if ch is not None)
        failed = sum(sum(st != STATUS_OK for st in ch.status) for ch in chunks
                     if ch is not None)
        if progress is not None:
            progress(done, failed, n)

        def finished(c: int, chunk: ChunkOutput) -> None:
            nonlocal done, failed
            chunks[c] = chunk
            if out_path is not None:
                _write_chunk(out_path, c, chunk, spec, runner.t_out)
            done += len(chunk.status)
            failed += sum(st != STATUS_OK for st in chunk.status)
            if progress is not None:
                progress(done, failed, n)

        compute_start = _time.perf_counter()
        cpu_start = _time.process_time()
        rows_of = {c: values[starts[c]:starts[c] + chunk_size] for c in todo}
        if client is not None:
            _run_dask(client, spec, starts, rows_of, todo, finished)
        elif n_workers == 1 or len(todo) <= 1:
            for c in todo:
                finished(c, runner.run(starts[c], rows_of[c]))
        else:
            _run_threads(runner, starts, rows_of, todo, n_workers, finished)
        compute_wall = _time.perf_counter() - compute_start
        compute_cpu = _time.process_time() - cpu_start
    finally:
        if own_client:
            client.close()

    result = _assemble(table, columns, values, spec, chunks, runner.t_out)
    computed = sum(len(chunks[c].status) for c in todo)
    wall = _time.perf_counter() - started
    result.stats = {
        "n_sets": n, "failed": int((result.table["status"] != STATUS_OK).sum()),
        "computed": computed, "computed_chunks": len(todo), "reused_chunks": reused,
        "chunks": len(starts), "chunk_size": chunk_size, "workers": n_workers,
        "scheduler": None if client is None else getattr(client.scheduler, "address", None),
        "steps": int(sum(chunks[c].steps for c in todo)), "wall_time_s": wall,
        "compute_time_s": compute_wall, "compute_cpu_s": compute_cpu,
        "sims_per_s": computed / compute_wall if compute_wall > 0 and computed else 0.0,
    }
    if out_path is not None:
        _write_final(out_path, result)
    return result


def _run_threads(runner: _Runner, starts, rows_of, todo, n_workers: int, finished) -> None:
    """Chunks on a thread pool; results handed to ``finished`` in completion order."""
    pool = ThreadPoolExecutor(max_workers=n_workers, thread_name_prefix="pneumact-batch")
    try:
        pending = {pool.submit(runner.run, starts[c], rows_of[c]): c for c in todo}
        while pending:
            ready, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in ready:
                finished(pending.pop(future), future.result())
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def _run_dask(client, spec: BatchSpec, starts, rows_of, todo, finished) -> None:
    """One Dask task per chunk, running ``run_chunk`` in the worker processes."""
    from distributed import as_completed

    remote_spec = client.scatter(spec, broadcast=True)
    futures = {}
    for c in todo:
        future = client.submit(run_chunk, remote_spec, starts[c], rows_of[c], pure=False,
                               key=f"pneumact-batch-{spec.token()[:12]}-{c}-"
                                   f"{os.urandom(4).hex()}")
        futures[future] = c
    try:
        for future in as_completed(futures):
            finished(futures[future], future.result())
    finally:
        for future in futures:
            future.cancel()


def _assemble(table: pd.DataFrame, columns, values: np.ndarray, spec: BatchSpec,
              chunks: list[ChunkOutput], t_out: np.ndarray) -> BatchResult:
    frame = pd.DataFrame(values, columns=list(columns), index=table.index)
    feats = np.concatenate([ch.features for ch in chunks], axis=0) if spec.features else None
    for j, name in enumerate(spec.features):
        frame[name] = feats[:, j]
    frame["status"] = [s for ch in chunks for s in ch.status]
    frame["error"] = [e for ch in chunks for e in ch.error]
    signals = {name: np.concatenate([ch.signals[name] for ch in chunks], axis=0)
               for name in spec.signals}
    units = {c: SPECS[c].unit for c in columns}
    units.update({f: FEATURE_UNITS[f] for f in spec.features})
    return BatchResult(frame, signals, np.asarray(t_out).copy(), {}, units)
