"""Batch simulation: one model and experiment, N parameter sets, all cores or a Dask cluster.

    table = pd.DataFrame({"Fc": [2.0, 2.6, 3.0], "Fs": [3.0, 3.2, 3.5]})      # SI values
    batch = simulate_batch(actuator, experiment, table, features=["stroke", "loop_area"])
    batch.table                    # the parameters + one column per feature + status/error

Each row of ``table`` replaces those parameters of the model's set. Rows are processed in
chunks; each chunk is one call of the compiled batch loop (no ``Result`` objects, no
Python work per row), so memory grows with N × what was asked for and threads scale like
the bare kernels. A set that fails (an invalid value, a solver failure) gets ``status``
!= "ok" and an ``error`` message; the others finish. Chunks run on local threads, or as
tasks on a Dask cluster (``scheduler=``), with identical results.

With ``out_dir`` the batch is resumable (see ``pneumact.io.chunks``): every finished
chunk is written atomically, and ``resume=True`` on the same directory computes only
the missing chunks.
"""

from __future__ import annotations

import math
import os
import time as _time
from collections.abc import Sequence
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ...core.assembly import assemble
from ...core.c_engine import check_engine
from ...core.features import FEATURE_UNITS
from ...errors import ArgumentError, ArgumentTypeError, PneumactError
from ...experiments.actuator import Experiment
from ...io.chunks import ChunkOutput, ChunkStore
from ...io.report import ResultVocabulary
from ...io.tables import partial_folder, staged_folder
from ...models.actuator import CHAMBER_PRESSURE
from ...progress import ProgressCallback, check_progress, notify, stop_threads

if TYPE_CHECKING:
    from matplotlib.figure import Figure
from ...options import Checkpoint, Executor, check_scheduler_address
from ...plotting import tight_layout
from ..memory import batch_bytes, check_memory
from ..solvers import Rodas4, Solver
from .runner import STATUS_OK, ChunkRunner, run_chunk
from .spec import (
    BatchSpec,
    check_features,
    check_names,
    check_reference,
    check_table,
    default_features,
    table_hash,
)

__all__ = ["BatchResult", "check_outputs", "signal_names", "simulate_batch"]

MANIFEST_FORMAT = "pneumact-batch/2"
MAX_DEFAULT_CHUNK = 250  # rows; keeps progress and checkpoints frequent on big batches


@dataclass
class BatchResult(ResultVocabulary):
    """Results of a batch: ``table`` (parameters + features + status/error, one row per
    set, in input order), ``signals`` (name -> N × len(time) array, NaN for failed sets),
    ``time`` (the output grid), ``stats`` (wall time, sims/s, computed/reused counts).

    ``to_pandas()``: the table (``"stats"``: the run's statistics); ``plot()``: each
    feature against each parameter that varies (or the kept signals over time);
    ``write(folder)``: the tables, the figure and report.html. (``simulate_batch(...,
    out_dir=...)`` keeps its own resumable folder with every signal in Parquet.)"""

    report_title = "Batch of simulations"
    figure_name = "batch"

    table: pd.DataFrame
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    time: np.ndarray | None = None
    stats: dict[str, Any] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)

    @property
    def failed(self) -> pd.DataFrame:
        """The rows whose status is not 'ok' (with their error message)."""
        return self.table[self.table["status"] != STATUS_OK]

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"results": self.to_pandas(),
                "stats": pd.DataFrame({"value": [str(v) for v in self.stats.values()]},
                                      index=pd.Index(list(self.stats), name="statistic"))}

    def report_text(self) -> str:
        return f"{len(self.table)} parameter sets, {len(self.failed)} failed."

    def plot(self) -> Figure:
        """Each feature (rows) against each parameter that varies (columns), failed sets
        left out; a batch of signals alone: every set's first signal over time."""
        import matplotlib.pyplot as plt

        ok = self.table[self.table["status"] == STATUS_OK]
        features = [c for c in self.table.columns if c in FEATURE_UNITS]
        varied = [c for c in self.table.columns if c not in features and c not in
                  ("status", "error") and pd.api.types.is_numeric_dtype(self.table[c])
                  and self.table[c].nunique() > 1]
        if not features and self.signals and self.time is not None:
            name, values = next(iter(self.signals.items()))
            fig, ax = plt.subplots(figsize=(7.0, 3.8))
            ax.plot(self.time, values.T, lw=0.8)
            ax.set_xlabel("time [s]")
            ax.set_ylabel(f"{name} [{self.units.get(name, '')}]")
            return fig
        from ...plotting import MAX_PANEL_COLUMNS, panel_grid

        columns = varied or ["set"]
        # a row per feature, a column per varied input; more inputs than fit side by side
        # wrap into rows (a figure of many inputs stays readable)
        pairs = [(feature, column) for feature in features for column in columns]
        fig, panels = panel_grid(len(pairs), width=3.4, height=2.4,
                                 columns=min(len(columns), MAX_PANEL_COLUMNS))
        for (ax,), (feature, column) in zip(panels, pairs, strict=False):
            x = ok.index if column == "set" else ok[column]
            ax.plot(x, ok[feature], ".", ms=4)
            ax.set_xlabel(f"{column} [{self.units.get(column, '')}]"
                          if column != "set" else "set")
            ax.set_ylabel(f"{feature} [{FEATURE_UNITS[feature]}]", fontsize=8)
            ax.grid(True, alpha=0.3)
        tight_layout(fig)
        return fig

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """A copy of ``table`` (units in ``attrs['units']``); ``name="stats"``: the run's
        statistics."""
        if name is not None:
            return super().to_pandas(name)
        frame = self.table.copy()
        frame.attrs["units"] = dict(self.units)
        return frame

    def __repr__(self) -> str:
        return (f"BatchResult({len(self.table)} sets, {len(self.failed)} failed, "
                f"features={[c for c in self.table.columns if c in FEATURE_UNITS]}, "
                f"signals={list(self.signals)})")


# --------------------------------------------------------------------------- planning
def signal_names(model, experiment) -> list[str]:
    """The signals a batch of ``model`` under ``experiment`` can keep: its states, then
    its derived outputs (the drive named after the experiment's quantity)."""
    assembly = assemble(model)
    return [*assembly.state_names,
            *(f"drive_{experiment.quantity}" if n == "drive" else n
              for n in assembly.output_names if n not in assembly.state_names)]


def check_outputs(model, experiment, features=(), signals=(), *, reference: bool = False,
                  cli: bool = False) -> None:
    """Refuse unknown feature or signal names (and pressure features of a model without a
    pressure) before anything runs; ``cli`` names them as the command line's options."""
    assembly = assemble(model)
    has_pressure = assembly.signal_source(CHAMBER_PRESSURE) is not None
    try:
        check_features(features, has_pressure, reference, type(model).__name__)
        check_names("signal", signals, signal_names(model, experiment))
    except PneumactError as exc:
        if cli:
            raise ArgumentError(f"{'--features' if 'feature' in exc.message else '--signals'}"
                                f": {exc.message}") from None
        raise


def _plan(model, experiment, table, features, signals, t_eval, solver, reference, y0,
          engine: str = "auto"):
    """(spec, values, runner): the checked batch and its prepared kernel."""
    assembly = assemble(model)
    columns, values = check_table(table, assembly)
    reference = check_reference(reference)
    has_pressure = assembly.signal_source(CHAMBER_PRESSURE) is not None
    if features is None:
        features = default_features(model.summary_kind, has_pressure, reference is not None,
                                    signals)
    features = check_features(features, has_pressure, reference is not None,
                              type(model).__name__)
    t_eval = None if t_eval is None else np.asarray(t_eval, dtype=float)
    y0 = None if y0 is None else np.asarray(y0, dtype=float)
    spec = BatchSpec(model, experiment, solver, columns, features, (), t_eval, reference, y0,
                     engine)
    runner = ChunkRunner(spec)  # prepares the kernel (and checks the experiment) up front
    spec = replace(spec, signals=check_names("signal", signals or (),
                                             signal_names(model, experiment)))
    runner.spec = spec
    runner.signal_sources = np.array([runner.source_of(n) for n in spec.signals],
                                     dtype=np.int64).reshape(len(spec.signals), 2)
    return spec, values, runner


def dask_client(scheduler):
    """(client, whether we own it) for an address string or a distributed.Client."""
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - dask is a declared extra
        raise PneumactError("scheduler= needs dask.distributed (pip install "
                            "'pneumact[dask]')") from exc
    if isinstance(scheduler, Client):
        return scheduler, False
    if isinstance(scheduler, str):
        address = check_scheduler_address(scheduler)
        try:
            return Client(address, timeout="20s"), True
        except Exception as exc:  # distributed raises OSError, TimeoutError, ValueError...
            raise PneumactError(f"cannot reach the Dask scheduler at {scheduler!r}: "
                                f"{type(exc).__name__}: {exc}") from exc
    raise ArgumentTypeError(f"scheduler = {scheduler!r}: must be an address string "
                            "('tcp://host:8786') or a distributed.Client")


# --------------------------------------------------------------------------- execution
def _run_threads(runner: ChunkRunner, starts, rows_of, todo, n_workers: int, finished) -> None:
    """Chunks on a thread pool; results handed to ``finished`` in completion order."""
    with stop_threads(ThreadPoolExecutor(max_workers=n_workers,
                                         thread_name_prefix="pneumact-batch")) as pool:
        pending = {pool.submit(runner.run, starts[c], rows_of[c]): c for c in todo}
        while pending:
            ready, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in ready:
                finished(pending.pop(future), future.result())


def _run_dask(client, spec: BatchSpec, starts, rows_of, todo, finished) -> None:
    """One Dask task per chunk, running ``run_chunk`` in the worker processes."""
    from distributed import as_completed

    remote_spec = client.scatter(spec, broadcast=True)
    token = spec.token()[:12]
    futures = {client.submit(run_chunk, remote_spec, starts[c], rows_of[c], pure=False,
                             key=f"pneumact-batch-{token}-{c}-{os.urandom(4).hex()}"): c
               for c in todo}
    try:
        for future in as_completed(futures):
            finished(futures[future], future.result())
    finally:
        for future in futures:
            future.cancel()


def _assemble(table: pd.DataFrame, spec: BatchSpec, values: np.ndarray,
              chunks: list[ChunkOutput], t_out: np.ndarray) -> BatchResult:
    frame = pd.DataFrame(values, columns=list(spec.columns), index=table.index)
    feats = np.concatenate([ch.features for ch in chunks], axis=0)
    for j, name in enumerate(spec.features):
        frame[name] = feats[:, j]
    frame["status"] = [s for ch in chunks for s in ch.status]
    frame["error"] = [e for ch in chunks for e in ch.error]
    signals = {name: np.concatenate([ch.signals[name] for ch in chunks], axis=0)
               for name in spec.signals}
    return BatchResult(frame, signals, np.asarray(t_out).copy(), {}, spec.units)


# --------------------------------------------------------------------------- entry point
def simulate_batch(model, experiment: Experiment, table: pd.DataFrame, *,
                   features: Sequence[str] | None = None, signals: Sequence[str] | None = None,
                   t_eval=None, solver: Solver | None = None,
                   executor: Executor | int | str | None = None,
                   checkpoint: Checkpoint | str | os.PathLike | None = None,
                   progress: ProgressCallback | None = None,
                   reference=None, y0=None, engine: str | None = None) -> BatchResult:
    """Simulate ``model`` under ``experiment`` once per row of ``table``.

    ``table``: one column per parameter name (SI values), one row per set. ``features``:
    names from ``pneumact.analysis.FEATURES`` (default: those of the model's
    ``summary_kind``, an actuator's hysteresis or a cylinder's motion; none if
    ``signals`` are asked; ``rms_error``/``max_error`` need ``reference=(time,
    position)``); ``signals``: signal names kept on the output grid ``t_eval`` (default
    the experiment's grid, on which features are computed too). ``executor``: an
    ``Executor`` (threads, default all cores, or a Dask scheduler; chunk size), or
    just a number of threads or a scheduler address. ``checkpoint``: a ``Checkpoint``
    (or a folder) makes the batch resumable: ``Checkpoint(folder, resume=True)``
    continues it, ``overwrite=True`` starts it again. ``progress`` is
    called with a ``pneumact.progress.Progress`` (stage "batch", sets done of all, failed
    sets) after each chunk. ``y0`` fixes the initial state of every run. ``engine``: as
    ``simulate``'s ('c', 'numba', 'auto'; None: ``PNEUMACT_ENGINE``).
    """
    started = _time.perf_counter()
    solver = _checked_solver(solver)
    executor = Executor.of(executor, "simulate_batch")
    checkpoint = Checkpoint.of(checkpoint, "simulate_batch")
    check_progress(progress, "simulate_batch")
    out = None if checkpoint is None else checkpoint.path
    resume = checkpoint is not None and checkpoint.resume
    overwrite = checkpoint is not None and checkpoint.overwrite
    chunk_size = executor.chunk_size
    scheduler = executor.scheduler
    engine = check_engine(engine, "simulate_batch: engine")
    spec, values, runner = _plan(model, experiment, table, features, signals, t_eval, solver,
                                 reference, y0, engine)
    n, n_t = values.shape[0], runner.t_out.size
    check_memory(batch_bytes(n, len(spec.signals), n_t, len(spec.features)),
                 f"simulate_batch: {n} sets x {len(spec.signals)} signals x {n_t} times")
    client, own_client = (None, False) if scheduler is None else dask_client(scheduler)
    try:
        n_workers = (max(1, len(client.scheduler_info().get("workers", {}))) if client
                     else executor.threads)
        if chunk_size is None and out is not None and resume:
            chunk_size = (ChunkStore(partial_folder(out)).saved_chunk_size()
                          or ChunkStore(out).saved_chunk_size())
        if chunk_size is None:
            chunk_size = max(1, min(math.ceil(n / (4 * n_workers)), MAX_DEFAULT_CHUNK))
        run = _Run(spec, values, runner, int(chunk_size), client, n_workers, progress)
        if out is None:
            run.execute(None)
            result = run.result(table)
        else:
            manifest = {"format": MANIFEST_FORMAT, "n_rows": n, "chunk_size": run.chunk_size,
                        "table": table_hash(spec.columns, values), **spec.describe()}
            ChunkStore(out).check_previous(manifest, resume, overwrite)
            with staged_folder(out, resumable=True, resume=resume,
                               overwrite=overwrite) as stage:
                store = ChunkStore(stage)
                run.execute(store, reuse=store.open(manifest))
                result = run.result(table)
                assert result.time is not None  # a batch's result has its output grid
                store.write_final(result.table, result.units, result.signals, result.time)
    finally:
        if own_client and client is not None:
            client.close()
    result.stats = run.stats(started, client)
    return result


def _checked_solver(solver) -> Solver:
    from ...checks import as_instance

    if solver is None:
        return Rodas4()
    return as_instance("solver", solver, Solver, examples="Rodas4() or DormandPrince()",
                       where="simulate_batch")


class _Run:
    """The chunks of one batch: which are reused, which are computed, and where."""

    def __init__(self, spec, values, runner, chunk_size, client, n_workers, progress):
        self.spec, self.values, self.runner = spec, values, runner
        self.chunk_size, self.client, self.n_workers = chunk_size, client, n_workers
        self.progress = progress
        n = values.shape[0]
        self.starts = list(range(0, n, chunk_size))
        self.chunks: list[ChunkOutput | None] = [None] * len(self.starts)
        self.todo: list[int] = []
        self.reused = 0
        self.compute_wall = self.compute_cpu = 0.0

    def execute(self, store: ChunkStore | None, reuse: bool = False) -> None:
        spec, values, runner, n = self.spec, self.values, self.runner, self.values.shape[0]
        n_t = runner.t_out.size
        chunks, starts, chunk_size = self.chunks, self.starts, self.chunk_size
        if store is not None and reuse:
            for c, s in enumerate(starts):
                chunks[c] = store.read_chunk(c, s, min(chunk_size, n - s), spec.features,
                                             spec.signals, n_t)
        self.reused = sum(ch is not None for ch in chunks)
        self.todo = todo = [c for c, ch in enumerate(chunks) if ch is None]
        done = sum(len(ch) for ch in chunks if ch is not None)
        failed = sum(sum(st != STATUS_OK for st in ch.status) for ch in chunks if ch is not None)
        progress = self.progress
        notify(progress, "batch", done, n, failed)

        def finished(c: int, chunk: ChunkOutput) -> None:
            nonlocal done, failed
            chunks[c] = chunk
            if store is not None:
                store.write_chunk(c, chunk, spec.features, spec.signals, runner.t_out)
            done += len(chunk)
            failed += sum(st != STATUS_OK for st in chunk.status)
            notify(progress, "batch", done, n, failed)

        compute_start, cpu_start = _time.perf_counter(), _time.process_time()
        rows_of = {c: values[starts[c]:starts[c] + chunk_size] for c in todo}
        if self.client is not None:
            _run_dask(self.client, spec, starts, rows_of, todo, finished)
        elif self.n_workers == 1 or len(todo) <= 1:
            for c in todo:
                finished(c, runner.run(starts[c], rows_of[c]))
        else:
            _run_threads(runner, starts, rows_of, todo, self.n_workers, finished)
        self.compute_wall = _time.perf_counter() - compute_start
        self.compute_cpu = _time.process_time() - cpu_start

    def _all_chunks(self) -> list[ChunkOutput]:
        """Every chunk, once ``execute`` has run (each was read back or computed)."""
        chunks = [ch for ch in self.chunks if ch is not None]
        if len(chunks) != len(self.chunks):
            raise RuntimeError("batch: a chunk was neither read back nor computed")
        return chunks

    def result(self, table: pd.DataFrame) -> BatchResult:
        return _assemble(table, self.spec, self.values, self._all_chunks(), self.runner.t_out)

    def stats(self, started: float, client) -> dict[str, Any]:
        chunks, todo = self._all_chunks(), self.todo
        computed = sum(len(chunks[c]) for c in todo)
        statuses = [s for ch in chunks for s in ch.status]
        wall = self.compute_wall
        return {
            "n_sets": self.values.shape[0],
            "failed": int(sum(s != STATUS_OK for s in statuses)),
            "computed": computed, "computed_chunks": len(todo),
            "reused_chunks": self.reused, "chunks": len(self.starts),
            "chunk_size": self.chunk_size, "workers": self.n_workers,
            "scheduler": None if client is None else getattr(client.scheduler, "address",
                                                                 None),
            "steps": int(sum(int(np.sum(chunks[c].steps)) for c in todo)),
            "wall_time_s": _time.perf_counter() - started, "compute_time_s": wall,
            "compute_cpu_s": self.compute_cpu,
            "sims_per_s": computed / wall if wall > 0 and computed else 0.0,
        }
