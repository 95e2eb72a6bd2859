"""One chunk of a batch: its rows checked with numpy, then simulated one by one.

For each row the runner sets the row's values into a copy of the base vector, re-derives,
finds the initial state, sets the tolerances from the row's state scales, and calls the
model kernel's compiled integrator, the same function a single run calls (the integrator
releases the GIL: threads running chunks run in parallel; where the features and the
kept signals read states only, its states-only form, which skips the derived outputs);
then the features
(``core.features``, compiled once per machine) and the requested signals. The loop over
the rows is Python: a compiled loop was measured no faster (1 000 rows of the
valve-driven cycle: 2.95 ms per row on one thread and 665 rows/s on two either way,
bit-identical features; the Python loop adds about 6 µs per row), and compiling it
cost every model 3-5 s more. A runner is
prepared once per batch (and per Dask worker process) and reused for every chunk.
"""

from __future__ import annotations

import threading
from typing import NamedTuple

import numpy as np

from ...core.c_common import on_engine
from ...core.c_engine import engine_scope
from ...core.features import FEATURES, N_FEATURES, all_features
from ...errors import ArgumentError
from ...io.chunks import ChunkOutput
from ...models.actuator import CHAMBER_PRESSURE
from ...parameters.validation import row_problems
from ...progress import raise_if_stopped
from ..result import SolverStats
from ..simulate import prepare
from .spec import BatchSpec

__all__ = ["STATUS_ERROR", "STATUS_INVALID", "STATUS_OK", "STATUS_SOLVER", "ChunkRunner",
           "run_chunk"]

STATUS_OK = "ok"
STATUS_INVALID = "invalid"  # a parameter value out of its range, or a broken relation
STATUS_SOLVER = "solver"  # the integrator failed (step underflow, NaN, max_steps)
STATUS_ERROR = "error"  # the row's run raised

#: the signals the features are computed from, in this order (``sources`` rows)
FEATURE_SIGNALS = ("position", "velocity", CHAMBER_PRESSURE)
#: where a signal is read: a state column or a derived-output column
FROM_STATE = 0
FROM_OUTPUT = 1


def _feature_source(assembly, name: str) -> tuple[int, int]:
    """Where the features read ``name``; a model without pressure (a friction rig) gives
    (−1, −1) there, and the pressure features are NaN."""
    source = assembly.signal_source(name)
    if source is None and name != CHAMBER_PRESSURE:
        raise ArgumentError(f"batch: the model has no {name!r} signal, which every feature "
                            f"needs; its signals: {', '.join(assembly.state_names)}")
    return source if source is not None else (-1, -1)


class _RowWork(NamedTuple):
    """A chunk's work arrays, reused by each of its rows."""

    y_out: np.ndarray
    out: np.ndarray
    info: np.ndarray
    y0: np.ndarray
    scales: np.ndarray


class ChunkRunner:
    """The prepared kernel of one batch, and its loop over a chunk's rows."""

    def __init__(self, spec: BatchSpec):
        self.spec = spec
        with engine_scope(spec.engine):
            prep = prepare(spec.model, spec.experiment, spec.solver, spec.t_eval, spec.y0)
            #: the features of a row, on the batch's engine (numba or the common C library)
            self.all_features = on_engine(all_features) if spec.features else all_features
        self.prep = prep
        assembly = prep.assembly
        slot_ptr, slot_idx = assembly.column_slots(spec.columns)
        #: the vector slots each column of the rows writes
        self.column_slots = [slot_idx[slot_ptr[c]:slot_ptr[c + 1]]
                             for c in range(len(spec.columns))]
        self.base = dict(spec.model.params.values)
        self.sources = np.array([_feature_source(assembly, name) for name in FEATURE_SIGNALS],
                                dtype=np.int64)
        self.signal_sources = np.array([self.source_of(name) for name in spec.signals],
                                       dtype=np.int64).reshape(len(spec.signals), 2)
        self.feature_index = np.array([FEATURES.index(f) for f in spec.features],
                                      dtype=np.int64)
        self.atol_given = spec.solver.atol_overrides(assembly.state_names)
        self.y0_given = (np.asarray(spec.y0, dtype=float) if spec.y0 is not None
                         else np.empty(0))
        empty = np.empty(0)
        reference: tuple[np.ndarray, np.ndarray] = (
            spec.reference if spec.reference is not None else (empty, empty))
        self.ref_t, self.ref_x = reference

    @property
    def t_out(self) -> np.ndarray:
        return self.prep.t_out

    def source_of(self, name: str) -> tuple[int, int]:
        """Where a signal of the batch comes from (the experiment's drive renamed)."""
        quantity = self.spec.experiment.quantity
        if name == f"drive_{quantity}":
            name = "drive"
        source = self.prep.assembly.signal_source(name)
        if source is None:  # the names were checked against signal_names() before
            raise ArgumentError(f"batch: the model has no signal {name!r}")
        return source

    def run(self, start: int, values: np.ndarray) -> ChunkOutput:
        """Simulate the rows ``values`` (n × columns); row k is set ``start + k``."""
        spec, prep, kernel = self.spec, self.prep, self.prep.kernel
        values = np.ascontiguousarray(values, dtype=float).reshape(-1, len(spec.columns))
        n, n_t = values.shape[0], prep.t_out.size
        problems = self._problems(values)
        valid = np.array([p is None for p in problems])
        features = np.full((n, N_FEATURES), np.nan)
        signals = np.full((n, len(spec.signals), n_t), np.nan)
        info = np.zeros((n, kernel.INFO_LENGTH))
        crashed = self._rows(values, valid, features, signals, info)
        solver = spec.solver
        status: list[str] = []
        error: list[str] = []
        for i, problem in enumerate(problems):
            stats = SolverStats.from_info(kernel, info[i])
            if problem is not None:
                status.append(STATUS_INVALID)
                error.append(problem)
            elif i in crashed:
                status.append(STATUS_ERROR)
                error.append(crashed[i])
            elif not stats.ok:
                status.append(STATUS_SOLVER)
                error.append(f"{type(solver).__name__} failed at t = {stats.t:.9g} s after "
                             f"{stats.steps} steps: {stats.reason}")
            else:
                status.append(STATUS_OK)
                error.append("")
        return ChunkOutput(start, np.ascontiguousarray(features[:, self.feature_index]),
                           status, error, {name: signals[:, k, :] for k, name in
                                           enumerate(spec.signals)},
                           info[:, kernel.INFO_STEPS].astype(np.int64))

    def _problems(self, values: np.ndarray) -> list[str | None]:
        """Why each row is invalid (None: valid), column by column; should the check
        itself fail on some row, each row is checked alone and that one is invalid."""
        try:
            return row_problems(self.base, self.spec.columns, values)
        except Exception:
            found: list[str | None] = []
            for row in values:
                try:
                    found.append(row_problems(self.base, self.spec.columns, row[None, :])[0])
                except Exception as exc:
                    found.append(f"invalid parameters: {type(exc).__name__}: {exc}")
            return found

    def _rows(self, values, valid, features, signals, info) -> dict[int, str]:
        """Simulate the ``valid`` rows of ``values`` (n × columns, SI), writing each one's
        features and signals (rows that succeed) and solver info into the arrays; returns
        the rows whose run raised, with the error (their results stay NaN)."""
        kernel, n_t = self.prep.kernel, self.prep.t_out.size
        states_only = self.reads_states_only()
        work = _RowWork(np.empty((n_t, kernel.NSTATE)),
                        np.empty((0 if states_only else n_t, kernel.NOUT)),
                        np.zeros(kernel.INFO_LENGTH), np.empty(kernel.NSTATE),
                        np.empty(kernel.NSTATE))
        crashed: dict[int, str] = {}
        for r in np.flatnonzero(valid):
            raise_if_stopped()  # Ctrl-C: the chunk ends at its next row
            try:
                self._row(values[r], work, states_only)
            except Exception as exc:
                crashed[int(r)] = f"{type(exc).__name__} in this row's run: {exc}"
                continue
            info[r] = work.info
            if work.info[kernel.INFO_STATUS] != 0:
                continue
            if self.spec.features:
                features[r] = self._features(work.y_out, work.out)
            for k, (kind, index) in enumerate(self.signal_sources):
                signals[r, k] = (work.y_out if kind == FROM_STATE else work.out)[:, index]
        return crashed

    def reads_states_only(self) -> bool:
        """Whether the features and the kept signals read states alone: then the rows
        run the integrator that writes no derived output (the same states, bit for bit,
        without three ``outputs`` calls per step that writes output points)."""
        read = [*(self.sources if self.spec.features else ()), *self.signal_sources]
        return all(kind != FROM_OUTPUT for kind, _ in read)

    def _row(self, row: np.ndarray, work: _RowWork, states_only: bool = False) -> None:
        """One row: its vector, its initial state and tolerances, then the integrator
        (states, outputs unless ``states_only``, and solver info into ``work``)."""
        prep, solver, kernel = self.prep, self.spec.solver, self.prep.kernel
        # a closed loop writes its controller output into its own copy of the inputs
        sig = prep.sig.copy() if kernel.PRIVATE_INPUTS else prep.sig
        prm = prep.vector.copy()
        for value, slots in zip(row, self.column_slots, strict=True):
            prm[slots] = value
        kernel.derive(prm)
        tb = prep.breakpoints
        if self.y0_given.shape[0] == kernel.NSTATE:
            work.y0[:] = self.y0_given
        else:
            kernel.initial_state(tb[0], 0.5 * (tb[0] + tb[1]), prm, sig, prep.ptr, work.y0)
        kernel.state_scales(prm, work.scales)
        atol = np.where(self.atol_given > 0.0, self.atol_given, solver.rtol * work.scales)
        arguments = (work.y0, prm, sig, prep.ptr, tb, prep.t_out, solver.rtol, atol,
                     solver.h_init, solver.h_max, prep.max_steps, work.y_out)
        if states_only:
            getattr(kernel, solver.states_function)(*arguments, work.info)
        else:
            getattr(kernel, solver.kernel_function)(*arguments, work.out, work.info)

    def _features(self, y_out: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Every feature of one run, from the columns ``sources`` points at."""
        def column(kind: int, index: int) -> np.ndarray:
            return np.ascontiguousarray((y_out if kind == FROM_STATE else out)[:, index])

        position, velocity, pressure = self.sources
        x, v = column(*position), column(*velocity)
        has_pressure = bool(pressure[0] >= 0)
        p = column(*pressure) if has_pressure else x
        values = np.empty(N_FEATURES)
        self.all_features(self.prep.t_out, x, v, p, has_pressure, self.ref_t, self.ref_x,
                          self.ref_t.shape[0] >= 2, values)
        return values


_RUNNERS: dict[str, ChunkRunner] = {}
_RUNNERS_LOCK = threading.Lock()


def run_chunk(spec: BatchSpec, start: int, values: np.ndarray) -> ChunkOutput:
    """Simulate one chunk of rows (the Dask task; the runner is cached per process)."""
    token = spec.token()
    with _RUNNERS_LOCK:
        runner = _RUNNERS.get(token)
        if runner is None:
            runner = _RUNNERS[token] = ChunkRunner(spec)
    return runner.run(start, values)
