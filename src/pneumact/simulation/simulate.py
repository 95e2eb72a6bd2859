"""The one entry point: ``simulate(model, experiment, solver)``."""

from __future__ import annotations

import time as _time
from collections.abc import Callable

import numpy as np

from ..errors import ExperimentError, SolverError
from ..experiments.actuator import Experiment
from ..experiments.signals import pack_channels
from ..models.pneumatics import derive_flow_constants
from .codegen import load_kernel
from .result import Result
from .solvers import Rodas4, Solver

STATUS_TEXT = {
    1: "step size underflow (the solution changes faster than the tolerances allow)",
    2: "the state became non-finite (NaN or inf)",
    3: "maximum number of steps reached",
}


def kernel_for(model):
    """The compiled kernel module of ``model``'s component combination."""
    return load_kernel(model.model, model.components(), model.kernel_key())


def check_drive(model, experiment: Experiment) -> None:
    """The experiment's signal must be what the model's valve or drive expects."""
    expected = getattr(model, "drive_quantity", None) or model.drive
    if experiment.quantity != expected:
        who = getattr(getattr(model, "valve", None), "name", None) or f"{model.drive} drive"
        raise ExperimentError(
            f"experiment '{experiment.name}' drives {experiment.quantity!r}, but the "
            f"{who} of this {type(model).__name__} needs a {expected!r} signal"
        )


def prepare(model, experiment: Experiment, solver: Solver, t_eval=None, y0=None):
    """Everything the kernel call needs, as arrays (shared with the batch engine)."""
    check_drive(model, experiment)
    kernel = kernel_for(model)
    prm = model.vector()
    derive_flow_constants(prm)  # complete vector, also for callers of kernel.rhs/jac
    channels = model.channels(experiment.drive)
    sig, ptr = pack_channels(channels)
    bp = experiment.breakpoints()
    load = channels[1]  # a load against time has corners of its own
    if load is not None:
        bp = np.unique(np.concatenate([bp, load.breakpoints()]))
        bp = bp[(bp >= experiment.t_start) & (bp <= experiment.t_end)]
    t_out = experiment.output_times() if t_eval is None else np.asarray(t_eval, dtype=float)
    if t_out.ndim != 1 or t_out.size == 0 or np.any(np.diff(t_out) < 0) or \
            t_out[0] < experiment.t_start or t_out[-1] > experiment.t_end:
        raise ExperimentError(
            f"t_eval must be a non-empty increasing array within [{experiment.t_start}, "
            f"{experiment.t_end}] s"
        )
    if y0 is None:
        y0 = model.initial_state(experiment.drive, experiment.t_start)
    scales = model.state_scales(prm) if hasattr(model, "state_scales") else np.ones(len(y0))
    atol = solver.atol_vector(kernel.STATE_NAMES, scales)
    return kernel, prm, sig, ptr, bp, t_out, np.asarray(y0, dtype=float), atol


def run_kernel(kernel, solver: Solver, y0, prm, sig, ptr, bp, t_out, atol,
               progress: Callable[[float], None] | None = None, chunks: int = 1):
    """Call the compiled integrator, optionally in chunks to report progress."""
    fn = getattr(kernel, solver.kernel_function)
    y_out = np.empty((t_out.size, kernel.NSTATE))
    out = np.empty((t_out.size, kernel.NOUT))
    info = np.zeros(8)
    if chunks <= 1:
        y = fn(y0, prm, sig, ptr, bp, t_out, solver.rtol, atol, solver.h_init, solver.h_max,
               solver.max_steps, y_out, out, info)
        return y, y_out, out, info
    edges = np.linspace(bp[0], bp[-1], chunks + 1)
    y = np.asarray(y0, dtype=float)
    h = solver.h_init
    total = np.zeros(8)
    j0 = 0
    for c in range(chunks):
        lo, hi = edges[c], edges[c + 1]
        seg_bp = np.unique(np.concatenate([[lo, hi], bp[(bp > lo) & (bp < hi)]]))
        j1 = int(np.searchsorted(t_out, hi, side="right")) if c < chunks - 1 else t_out.size
        sel = t_out[j0:j1] if c == 0 else t_out[j0:j1][t_out[j0:j1] > lo]
        k0 = j1 - sel.size
        y = fn(y, prm, sig, ptr, seg_bp, sel, solver.rtol, atol, h, solver.h_max,
               solver.max_steps, y_out[k0:j1], out[k0:j1], info)
        total[2:6] += info[2:6]
        total[0:2] = info[0:2]
        total[6] = info[6]
        h = info[6]
        j0 = j1
        if progress is not None:
            progress((c + 1) / chunks)
        if info[0] != 0:
            break
    return y, y_out, out, total


def simulate(model, experiment: Experiment, solver: Solver | None = None, *, t_eval=None,
             y0=None, progress: Callable[[float], None] | None = None) -> Result:
    """Simulate ``model`` (an ``Actuator`` or a ``FrictionRig``) under ``experiment``.

    Returns a ``Result`` with named, unit-tagged signals at ``t_eval`` (default: the
    experiment's uniform output grid). ``progress`` is called with the completed fraction
    (the run is then split into chunks). Raises ``SolverError`` saying when and in which
    state the integrator failed.
    """
    solver = Rodas4() if solver is None else solver
    kernel, prm, sig, ptr, bp, t_out, y0, atol = prepare(model, experiment, solver, t_eval,
                                                         y0)
    start = _time.perf_counter()
    y_end, y_out, out, info = run_kernel(kernel, solver, y0, prm, sig, ptr, bp, t_out, atol,
                                         progress, chunks=50 if progress else 1)
    wall = _time.perf_counter() - start
    status = int(info[0])
    if status != 0:
        state = ", ".join(f"{n}={v:.6g} {u}" for n, v, u in
                          zip(kernel.STATE_NAMES, y_end, kernel.STATE_UNITS, strict=True))
        raise SolverError(
            f"{type(solver).__name__} failed at t = {info[1]:.9g} s after {int(info[2])} "
            f"steps: {STATUS_TEXT.get(status, 'unknown failure')}; state: {state}"
        )
    return Result.from_kernel(kernel, model, experiment, solver, t_out, y_out, out, info,
                              wall)
