"""One chunk of a batch: its rows checked with numpy, then simulated in one compiled call.

The compiled loop (``pneumact.core.batch_loop``) sets each row's values, finds the initial
state, integrates and computes the features inside the kernel, so a thread running a
chunk holds no Python lock while it works. A runner is prepared once per batch (and per
Dask worker process) and reused for every chunk.
"""

from __future__ import annotations

import threading

import numpy as np

from ...core.batch_loop import FEATURE_SIGNALS
from ...core.features import FEATURES, N_FEATURES
from ...errors import ArgumentError
from ...io.chunks import ChunkOutput
from ...parameters.validation import row_problems
from ..result import SolverStats
from ..simulate import prepare
from .spec import BatchSpec

__all__ = ["STATUS_ERROR", "STATUS_INVALID", "STATUS_OK", "STATUS_SOLVER", "ChunkRunner",
           "run_chunk"]

STATUS_OK = "ok"
STATUS_INVALID = "invalid"  # a parameter value out of its range, or a broken relation
STATUS_SOLVER = "solver"  # the integrator failed (step underflow, NaN, max_steps)
STATUS_ERROR = "error"  # the row's run raised (an exception inside the compiled loop)


def _feature_source(assembly, name: str) -> tuple[int, int]:
    """Where the features read ``name``; a model without pressure (a friction rig) gives
    (−1, −1) there, and the pressure features are NaN."""
    source = assembly.signal_source(name)
    if source is None and name != "pressure":
        raise ArgumentError(f"batch: the model has no {name!r} signal, which every feature "
                            f"needs; its signals: {', '.join(assembly.state_names)}")
    return source if source is not None else (-1, -1)


class ChunkRunner:
    """The prepared kernel of one batch and the compiled per-chunk loop."""

    def __init__(self, spec: BatchSpec):
        self.spec = spec
        prep = prepare(spec.model, spec.experiment, spec.solver, spec.t_eval, spec.y0)
        self.prep = prep
        assembly = prep.assembly
        self.slot_ptr, self.slot_idx = assembly.column_slots(spec.columns)
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
        crashed: dict[int, str] = {}
        try:
            self._rows(values, valid, features, signals, info)
        except Exception:  # one row raised inside the compiled loop: run them one by one
            crashed = self._one_by_one(values, valid, features, signals, info)
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

    def _rows(self, values, valid, features, signals, info) -> None:
        """The compiled loop over ``values`` (results written into the arrays)."""
        spec, prep, solver = self.spec, self.prep, self.spec.solver
        prep.kernel.run_rows(prep.vector, self.slot_ptr, self.slot_idx, values, valid,
                             self.y0_given, prep.sig, prep.ptr, prep.breakpoints, prep.t_out,
                             True if solver.explicit else None, solver.rtol, self.atol_given,
                             solver.h_init, solver.h_max, prep.max_steps, self.sources,
                             self.ref_t, self.ref_x, len(spec.features) > 0, features,
                             self.signal_sources, signals, info)

    def _one_by_one(self, values, valid, features, signals, info) -> dict[int, str]:
        """Each valid row in a call of its own: a row that raises is that row's error
        (its results stay NaN), the others finish."""
        crashed: dict[int, str] = {}
        for i in np.flatnonzero(valid):
            row_f, row_s = features[i:i + 1].copy(), signals[i:i + 1].copy()
            row_info = np.zeros((1, info.shape[1]))
            try:
                self._rows(values[i:i + 1].copy(), valid[i:i + 1].copy(), row_f, row_s,
                           row_info)
            except Exception as exc:
                crashed[int(i)] = f"{type(exc).__name__} in this row's run: {exc}"
                continue
            features[i], signals[i], info[i] = row_f[0], row_s[0], row_info[0]
        return crashed


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
