"""The one entry point: ``simulate(model, experiment, solver)``."""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from ..errors import ExperimentError, ParameterError, SolverError
from ..experiments.actuator import Experiment
from ..experiments.signals import pack_channels
from .assembly import Assembly, assemble
from .result import Result, SolverStats
from .solvers import Rodas4, Solver

__all__ = ["Prepared", "check_drive", "prepare", "run_kernel", "simulate"]


def check_drive(model, experiment: Experiment) -> None:
    """The experiment's signal must be what the model's valve or drive expects."""
    expected = model.drive_quantity
    if experiment.quantity != expected:
        valve = getattr(model, "valve", None)
        who = valve.name if valve is not None else f"{expected} drive"
        raise ExperimentError(
            f"experiment '{experiment.name}' drives {experiment.quantity!r}, but the "
            f"{who} of this {type(model).__name__} needs a {expected!r} signal")


@dataclass(eq=False)
class Prepared:
    """Everything a kernel call needs, as arrays, with the assembly that made them."""

    assembly: Assembly
    kernel: ModuleType
    vector: np.ndarray
    sig: np.ndarray
    ptr: np.ndarray
    breakpoints: np.ndarray
    t_out: np.ndarray
    y0: np.ndarray
    atol: np.ndarray

    @property
    def segment_time(self) -> float:
        """Mid-point of the first interval between breakpoints (selects input segments)."""
        return 0.5 * (self.breakpoints[0] + self.breakpoints[1])


def _breakpoints(model, experiment: Experiment, channels) -> np.ndarray:
    bp = experiment.breakpoints()
    load = channels[1]  # a load against time has corners of its own
    if load is not None:
        bp = np.unique(np.concatenate([bp, load.breakpoints()]))
        bp = bp[(bp >= experiment.t_start) & (bp <= experiment.t_end)]
    if hasattr(model, "breakpoints"):  # a closed loop: its own inputs and samples
        bp = model.breakpoints(bp, channels, experiment.t_start, experiment.t_end)
    return bp


def _output_times(experiment: Experiment, t_eval) -> np.ndarray:
    t_out = experiment.output_times() if t_eval is None else np.asarray(t_eval, dtype=float)
    if t_out.ndim != 1 or t_out.size == 0 or np.any(np.diff(t_out) < 0) or \
            t_out[0] < experiment.t_start or t_out[-1] > experiment.t_end:
        raise ExperimentError(f"t_eval must be a non-empty increasing array within "
                              f"[{experiment.t_start}, {experiment.t_end}] s")
    return np.ascontiguousarray(t_out)


def prepare(model, experiment: Experiment, solver: Solver, t_eval=None, y0=None,
            vector: np.ndarray | None = None, values: Mapping[str, float] | None = None
            ) -> Prepared:
    """The arrays of one run of ``model`` under ``experiment`` (shared with the batch
    engine, sensitivities and identification): the packed parameter vector (or
    ``vector``), the input channels, breakpoints, output times, initial state (the
    model's equilibrium unless ``y0``) and absolute tolerances. ``values`` overrides
    parameter values by name (SI) for this run only."""
    check_drive(model, experiment)
    assembly = assemble(model)
    kernel = assembly.kernel
    vec = assembly.pack() if vector is None else np.array(vector, dtype=float)
    if values:
        assembly.check_parameters(list(values), "values")
        bad = {n: v for n, v in values.items() if not np.isfinite(v)}
        if bad:
            raise ParameterError(f"values: {bad} must be finite numbers")
        assembly.update(vec, values)
    else:
        kernel.derive(vec)
    channels = model.channels(experiment.drive)
    sig, ptr = pack_channels(channels)
    bp = _breakpoints(model, experiment, channels)
    t_out = _output_times(experiment, t_eval)
    n = len(assembly.states)
    if y0 is None:
        start = np.empty(n)
        kernel.initial_state(bp[0], 0.5 * (bp[0] + bp[1]), vec, sig, ptr, start)
    else:
        start = np.asarray(y0, dtype=float).copy()
        if start.shape != (n,):
            raise ExperimentError(f"y0 has shape {start.shape}; this model has {n} states: "
                                  f"{', '.join(assembly.state_names)}")
    scales = np.empty(n)
    kernel.state_scales(vec, scales)
    atol = solver.atol_vector(assembly.state_names, scales)
    return Prepared(assembly, kernel, vec, sig, ptr, bp, t_out, start, atol)


def compiled(fn, *args):
    """``fn`` compiled (or loaded from the disk cache) for the types of ``args``, so that
    a timed call measures the run, not the compilation."""
    if not fn.signatures:
        from numba import typeof

        fn.compile(tuple(typeof(a) for a in args))
    return fn


def run_kernel(prep: Prepared, solver: Solver,
               progress: Callable[[float], None] | None = None, chunks: int = 1):
    """Call the compiled integrator, optionally in chunks to report progress; returns
    (final state, states at t_out, outputs at t_out, solver info)."""
    kernel = prep.kernel
    fn = getattr(kernel, solver.kernel_function)
    n_t = prep.t_out.size
    y_out = np.empty((n_t, kernel.NSTATE))
    out = np.empty((n_t, kernel.NOUT))
    info = np.zeros(kernel.INFO_LENGTH)
    bp = prep.breakpoints
    if chunks <= 1:
        y = fn(prep.y0, prep.vector, prep.sig, prep.ptr, bp, prep.t_out, solver.rtol,
               prep.atol, solver.h_init, solver.h_max, solver.max_steps, y_out, out, info)
        return y, y_out, out, info
    edges = np.linspace(bp[0], bp[-1], chunks + 1)
    y = prep.y0
    h = solver.h_init
    total = np.zeros(kernel.INFO_LENGTH)
    counters = (kernel.INFO_STEPS, kernel.INFO_REJECTED, kernel.INFO_RHS, kernel.INFO_JAC)
    j0 = 0
    for c in range(chunks):
        lo, hi = edges[c], edges[c + 1]
        seg_bp = np.unique(np.concatenate([[lo, hi], bp[(bp > lo) & (bp < hi)]]))
        j1 = int(np.searchsorted(prep.t_out, hi, side="right")) if c < chunks - 1 else n_t
        sel = prep.t_out[j0:j1] if c == 0 else prep.t_out[j0:j1][prep.t_out[j0:j1] > lo]
        k0 = j1 - sel.size
        y = fn(y, prep.vector, prep.sig, prep.ptr, seg_bp, sel, solver.rtol, prep.atol, h,
               solver.h_max, solver.max_steps, y_out[k0:j1], out[k0:j1], info)
        for index in counters:
            total[index] += info[index]
        for index in (kernel.INFO_STATUS, kernel.INFO_T, kernel.INFO_H):
            total[index] = info[index]
        h = info[kernel.INFO_H]
        j0 = j1
        if progress is not None:
            progress((c + 1) / chunks)
        if info[kernel.INFO_STATUS] != 0:
            break
    return y, y_out, out, total


def failure(prep: Prepared, solver: Solver, stats: SolverStats, y_end) -> SolverError:
    """The SolverError of a failed run: when, after how many steps, why, in which state."""
    assembly = prep.assembly
    state = ", ".join(f"{n}={v:.6g} {u}" for n, v, u in
                      zip(assembly.state_names, y_end, assembly.state_units, strict=True))
    return SolverError(f"{type(solver).__name__} failed at t = {stats.t:.9g} s after "
                       f"{stats.steps} steps: {stats.reason}; state: {state}")


def simulate(model, experiment: Experiment, solver: Solver | None = None, *, t_eval=None,
             y0=None, progress: Callable[[float], None] | None = None,
             values: Mapping[str, float] | None = None) -> Result:
    """Simulate ``model`` (an ``Actuator`` or a ``FrictionRig``) under ``experiment``.

    Returns a ``Result`` with named, unit-tagged signals at ``t_eval`` (default: the
    experiment's uniform output grid). ``progress`` is called with the completed fraction
    (the run is then split into chunks). Raises ``SolverError`` saying when and in which
    state the integrator failed. ``values`` changes parameter values (SI, by name) for
    this run without building a new parameter set (fitting loops use it; ranges and
    relations are not re-checked).
    """
    solver = Rodas4() if solver is None else solver
    prep = prepare(model, experiment, solver, t_eval, y0, values=values)
    n_t = prep.t_out.size
    compiled(getattr(prep.kernel, solver.kernel_function), prep.y0, prep.vector, prep.sig,
             prep.ptr, prep.breakpoints, prep.t_out, solver.rtol, prep.atol, solver.h_init,
             solver.h_max, solver.max_steps, np.empty((n_t, prep.kernel.NSTATE)),
             np.empty((n_t, prep.kernel.NOUT)), np.zeros(prep.kernel.INFO_LENGTH))
    start = _time.perf_counter()
    y_end, y_out, out, info = run_kernel(prep, solver, progress,
                                         chunks=50 if progress else 1)
    wall = _time.perf_counter() - start
    stats = SolverStats.from_info(prep.kernel, info)
    if not stats.ok:
        raise failure(prep, solver, stats, y_end)
    return Result.from_run(prep, experiment, solver, y_out, out, stats, wall)
