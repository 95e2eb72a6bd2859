"""The one entry point: ``simulate(model, experiment, solver)``."""

from __future__ import annotations

import time as _time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from ..checks import (
    as_instance,
    check_finite,
    check_type,
    shown,
)
from ..core.assembly import Assembly, assemble
from ..core.c_engine import Kernel, check_engine, engine_scope
from ..core.channels import CH_LOAD_T
from ..core.signals import pack_channels
from ..errors import ArgumentTypeError, ExperimentError, ParameterError, SolverError
from ..experiments.actuator import Experiment
from ..progress import ProgressCallback, check_progress, notify, raise_if_stopped
from .memory import check_memory, simulate_bytes
from .result import Result, SolverStats
from .solvers import Rodas4, Solver

if TYPE_CHECKING:
    from ..core.channels import InputChannel
    from ..core.component import Part
    from ..core.signals import Signal
    from ..parameters.parameter_set import ParameterSet

__all__ = ["Model", "Prepared", "check_drive", "check_drive_while_building", "check_experiment",
           "check_model", "checked_solver", "model_stroke", "prepare", "run_kernel", "simulate"]


@runtime_checkable
class Model(Protocol):
    """What the simulation asks of a model: an ``Actuator``, a ``FrictionRig``, a
    ``Cylinder`` or a ``control.ClosedLoop`` has it (``check_model`` checks it at run time).

    ``inputs()`` declares what drives it (``core.channels.InputChannel``: name, unit,
    range, record signals, channel; its drive first, declared by the component that owns
    it; an experiment drives the others by name, ``Experiment.drives``, which
    ``channels(drive, drives)`` puts on their channels), and the rest is read from there:
    ``drive_quantity`` is what the experiment's signal is
    (pressure, command, force, position...); ``input_signal`` the record signal that
    drives the model (a regulator's logged ``setpoint``, a ``pressure``, a ``command``, a
    loop's ``position_setpoint``); ``input_range`` the values it acts over;
    ``input_signals`` every record signal it can be driven by, and ``driven_by(signal)``
    the same model driven by one of them (an actuator behind another valve);
    ``plant_kind`` what its input acts on (pressure, command, force...); ``stroke`` the
    end of its travel (None: unbounded); ``summary_kind`` the features its
    ``Result.summary()`` computes (``simulation.result.SUMMARIES``: an actuator's
    hysteresis, a cylinder's or a rig's motion)."""

    @property
    def sensitivity_refusal(self) -> str | None:
        """Why the model does not carry forward sensitivities (None: it does)."""
        ...

    @property
    def params(self) -> ParameterSet: ...

    def inputs(self) -> tuple[InputChannel, ...]:
        """The inputs it declares, its drive first."""
        ...

    @property
    def drive_input(self) -> InputChannel:
        """The input an experiment drives (the first declared)."""
        ...

    def declared_input(self, name: str, who: str, /) -> InputChannel:
        """Its input named ``name``; refused naming ``who``, the model and its inputs."""
        ...

    @property
    def drive_quantity(self) -> str: ...

    @property
    def input_signal(self) -> str: ...

    @property
    def input_signals(self) -> tuple[str, ...]: ...

    def driven_by(self, signal: str, /) -> Model: ...

    @property
    def plant_kind(self) -> str: ...

    @property
    def drive_label(self) -> str: ...

    @property
    def input_range(self) -> tuple[float, float]: ...

    def check_drive_values(self, low: float, high: float, where: str, /) -> None:
        """Refuse a drive signal spanning ``low`` to ``high`` outside its declared drive
        (its components own the limits and the message; ``where`` names the experiment)."""

    @property
    def stroke(self) -> float | None: ...

    @property
    def summary_kind(self) -> str: ...

    def parts(self) -> tuple[Part, ...]: ...

    def channels(self, drive: Signal, drives: Mapping[str, Signal] | None = None, /
                 ) -> list[Signal | None]:
        """The kernel's signals: ``drive`` on its drive's channel, each of ``drives``
        (its other inputs by name) on its own."""
        ...

    def breakpoints(self, bp: np.ndarray, channels: list[Signal | None], t_start: float,
                    t_end: float, /) -> np.ndarray: ...

    def describe(self) -> str: ...


#: classes whose instances passed ``check_model``: the protocol's isinstance reads every
#: attribute it names (properties computed), 0.1 ms a run, and a class answers for its
#: instances
_MODEL_CLASSES: set[type] = set()


def check_model(model, where: str = "simulate") -> None:
    """``model`` must be a model (an Actuator, a FrictionRig, a Cylinder, a ClosedLoop)."""
    if type(model) in _MODEL_CLASSES:
        return
    if isinstance(model, Model):
        _MODEL_CLASSES.add(type(model))
    else:
        raise ArgumentTypeError(
            f"{where}: model = {shown(model)}: must be a model, e.g. pa.Actuator(params), "
            f"pa.FrictionRig(params), pa.Cylinder(params) or pneumact.control.ClosedLoop(...), "
            f"not {type(model).__name__}")


def check_experiment(experiment, where: str = "simulate") -> None:
    check_type("experiment", experiment, Experiment, where=where,
               what="an Experiment, e.g. pa.PressureCycle(), pa.CommandCycle() or "
                    "pa.experiments.from_csv(path)")


def check_drive(model, experiment: Experiment, where: str = "simulate") -> None:
    """The experiment must drive the model's drive by its quantity and only inputs the
    model declares by name (``Experiment.drives``), each with values in its declared range
    (an absolute pressure, a command in [0, 1], a set-point within the stroke, a load
    force); one ExperimentError otherwise, naming the input, the model and its inputs."""
    check_model(model, where)
    _check_drive_of(model, experiment, where)


def check_drive_while_building(model, experiment: Experiment, where: str = "simulate"
                               ) -> None:
    """``check_drive``, with ``model``'s C kernel built meanwhile where the engine in force
    may run C and it is not built yet (``core.c_engine.build_ahead``): on a cold start its
    compiler runs beside the one building the signal library that ``check_drive`` reads
    the drive with."""
    check_model(model, where)
    with assemble(model).building_kernel():
        _check_drive_of(model, experiment, where)


def _check_drive_of(model: Model, experiment: Experiment, where: str) -> None:
    """``check_drive`` of a model already checked."""
    check_experiment(experiment, where)
    who = f"experiment '{experiment.name}'"
    for name, (low, high) in experiment.input_extremes().items():
        declared = model.declared_input(name, who)
        if name == experiment.quantity and declared.name != model.drive_quantity:
            raise ExperimentError(
                f"{who} drives {name!r} as its quantity, but the drive of this "
                f"{type(model).__name__} is {model.drive_quantity!r}: drive "
                f"{model.drive_quantity!r} and give {name!r} in drives={{{name!r}: ...}}")
        declared.check(low, high, who)


def model_stroke(model: Model) -> float | None:
    """x_max of a model whose plant is an actuator (set-points beyond it are impossible)."""
    return model.stroke


@dataclass(eq=False)
class Prepared:
    """Everything a kernel call needs, as arrays, with the assembly that made them."""

    assembly: Assembly
    kernel: Kernel
    vector: np.ndarray
    sig: np.ndarray
    ptr: np.ndarray
    breakpoints: np.ndarray
    t_out: np.ndarray
    y0: np.ndarray
    atol: np.ndarray
    max_steps: int = 0

    @property
    def segment_time(self) -> float:
        """Mid-point of the first interval between breakpoints (selects input segments)."""
        return 0.5 * (self.breakpoints[0] + self.breakpoints[1])


def _breakpoints(model, experiment: Experiment, channels) -> np.ndarray:
    bp = experiment.breakpoints()
    load = channels[CH_LOAD_T]  # a load against time has corners of its own
    if load is not None:
        bp = np.unique(np.concatenate([bp, load.breakpoints()]))
        bp = bp[(bp >= experiment.t_start) & (bp <= experiment.t_end)]
    # a closed loop adds its own inputs' corners and its samples
    return model.breakpoints(bp, channels, experiment.t_start, experiment.t_end)


def _output_times(experiment: Experiment, t_eval) -> np.ndarray:
    """The output times, always a writeable C-contiguous copy: numba types a read-only
    array (a Record's time) apart from a writeable one, so passing both would compile
    every integrator of a kernel twice."""
    if t_eval is None:
        return _writeable(experiment.output_times())
    try:
        t_out = np.asarray(t_eval, dtype=float)
    except (TypeError, ValueError):
        raise ArgumentTypeError(f"t_eval = {shown(t_eval)}: must be an array of times [s]"
                                ) from None
    allowed = (f"must be a non-empty increasing array of finite times within "
               f"[{experiment.t_start:g}, {experiment.t_end:g}] s")
    if t_out.ndim != 1 or t_out.size == 0:
        raise ExperimentError(f"t_eval has shape {t_out.shape}: {allowed}")
    bad = np.flatnonzero(~np.isfinite(t_out))
    if bad.size:
        raise ExperimentError(f"t_eval[{bad[0]}] = {t_out[bad[0]]}: {allowed}")
    if np.any(np.diff(t_out) < 0) or t_out[0] < experiment.t_start or \
            t_out[-1] > experiment.t_end:
        raise ExperimentError(f"t_eval spans {t_out[0]:g}..{t_out[-1]:g} s: {allowed}")
    return _writeable(t_out)


def _writeable(times) -> np.ndarray:
    return np.array(times, dtype=float, order="C", copy=True)


def _output_count(experiment: Experiment, t_eval) -> int:
    if t_eval is None:
        return int(experiment.n_points)
    return int(np.size(t_eval))


def prepare(model, experiment: Experiment, solver: Solver, t_eval=None, y0=None,
            vector: np.ndarray | None = None, values: Mapping[str, float] | None = None
            ) -> Prepared:
    """The arrays of one run of ``model`` under ``experiment`` (shared with the batch
    engine, sensitivities and identification): the packed parameter vector (or
    ``vector``), the input channels, breakpoints, output times, initial state (the
    model's equilibrium unless ``y0``) and absolute tolerances. ``values`` overrides
    parameter values by name (SI) for this run only."""
    check_drive_while_building(model, experiment)
    assembly = assemble(model)
    n_out = len(assembly.output_names)
    check_memory(simulate_bytes(_output_count(experiment, t_eval), len(assembly.states),
                                n_out),
                 f"a run of {_output_count(experiment, t_eval)} output points")
    kernel = assembly.kernel
    vec = assembly.pack() if vector is None else np.array(vector, dtype=float)
    if values:
        if not isinstance(values, Mapping):
            raise ArgumentTypeError(f"values = {shown(values)}: must be a mapping of "
                                    "parameter name -> SI value")
        assembly.check_parameters(list(values), "values")
        values = {n: check_finite(f"values[{n!r}]", v, error=ParameterError)
                  for n, v in values.items()}
        assembly.update(vec, values)
    elif vector is not None:  # ``pack`` derived its own vector
        kernel.derive(vec)
    channels = model.channels(experiment.drive, experiment.drives)
    sig, ptr = pack_channels(channels)
    bp = _breakpoints(model, experiment, channels)
    t_out = _output_times(experiment, t_eval)
    n = len(assembly.states)
    if y0 is None or isinstance(y0, Mapping):
        start = np.empty(n)
        kernel.initial_state(bp[0], 0.5 * (bp[0] + bp[1]), vec, sig, ptr, start)
        if y0 is not None:
            _set_named_states(assembly, start, y0)
    else:
        try:
            start = np.asarray(y0, dtype=float).copy()
        except (TypeError, ValueError):
            raise ArgumentTypeError(f"y0 = {shown(y0)}: must be an array of {n} initial "
                                    "states") from None
        if start.shape == (n,) and not np.all(np.isfinite(start)):
            raise ExperimentError(f"y0 = {start.tolist()}: every initial state must be finite")
        if start.shape != (n,):
            raise ExperimentError(f"y0 has shape {start.shape}; this model has {n} states: "
                                  f"{', '.join(assembly.state_names)}")
    scales = np.empty(n)
    kernel.state_scales(vec, scales)
    atol = solver.atol_vector(assembly.state_names, scales)
    return Prepared(assembly, kernel, vec, sig, ptr, bp, t_out, start, atol,
                    solver.step_limit(bp.size - 1))


def _set_named_states(assembly, start: np.ndarray, y0: Mapping[str, float]) -> None:
    """Overwrite the states ``y0`` names (SI) in the model's equilibrium ``start``."""
    names = assembly.state_names
    for name, value in y0.items():
        if name not in names:
            raise ExperimentError(f"y0: unknown state {name!r}; the states of "
                                  f"{assembly.describe()} are {', '.join(names)}")
        start[names.index(name)] = check_finite(f"y0[{name!r}]", value,
                                                error=ExperimentError)


def checked_solver(solver, where: str = "simulate") -> Solver:
    """The solver to use: Rodas4() when None, an instance for its class."""
    if solver is None:
        return Rodas4()
    return as_instance("solver", solver, Solver, examples="pa.Rodas4(rtol=1e-6) or "
                       "pa.DormandPrince()", where=where)


def compiled(fn, *args):
    """``fn`` compiled (or loaded from the disk cache) for the types of ``args``, so that
    a timed call measures the run, not the compilation (a C engine's function is built)."""
    if not getattr(fn, "signatures", True):
        from numba import typeof

        fn.compile(tuple(typeof(a) for a in args))
    return fn


def run_kernel(prep: Prepared, solver: Solver,
               progress: ProgressCallback | None = None, chunks: int = 1):
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
               prep.atol, solver.h_init, solver.h_max, prep.max_steps, y_out, out, info)
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
               solver.h_max, prep.max_steps, y_out[k0:j1], out[k0:j1], info)
        for index in counters:
            total[index] += info[index]
        for index in (kernel.INFO_STATUS, kernel.INFO_T, kernel.INFO_H):
            total[index] = info[index]
        h = info[kernel.INFO_H]
        j0 = j1
        notify(progress, "simulate", c + 1, chunks)
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
             y0=None, progress: ProgressCallback | None = None,
             values: Mapping[str, float] | None = None, engine: str | None = None) -> Result:
    """Simulate ``model`` (an ``Actuator``, a ``FrictionRig`` or a ``Cylinder``) under
    ``experiment``.

    Returns a ``Result`` with named, unit-tagged signals at ``t_eval`` (default: the
    experiment's uniform output grid). ``progress`` is called with a
    ``pneumact.progress.Progress`` (stage "simulate", chunks done of 50: the run is then
    split into chunks). Raises ``SolverError`` saying when and in which
    state the integrator failed. ``values`` changes parameter values (SI, by name) for
    this run without building a new parameter set (fitting loops use it; ranges and
    relations are not re-checked). ``y0`` starts the run elsewhere than at the model's
    equilibrium: an array of every state, or state name -> SI value (the others at the
    equilibrium). ``engine`` runs the model's kernel in C ('c': built once per machine
    and model with the C compiler), in numba ('numba') or 'auto' (C where a compiler is
    found and the model translates, else numba with an ``EngineWarning``); None: the
    ``PNEUMACT_ENGINE`` setting, 'auto' when unset. Both give the same trajectories.
    """
    solver = checked_solver(solver)
    check_progress(progress, "simulate")
    raise_if_stopped()
    with engine_scope(check_engine(engine, "simulate: engine")):
        return _simulate(model, experiment, solver, t_eval, y0, progress, values)


def _simulate(model, experiment: Experiment, solver: Solver, t_eval, y0,
              progress: ProgressCallback | None, values: Mapping[str, float] | None
              ) -> Result:
    prep = prepare(model, experiment, solver, t_eval, y0, values=values)
    n_t = prep.t_out.size
    compiled(getattr(prep.kernel, solver.kernel_function), prep.y0, prep.vector, prep.sig,
             prep.ptr, prep.breakpoints, prep.t_out, solver.rtol, prep.atol, solver.h_init,
             solver.h_max, prep.max_steps, np.empty((n_t, prep.kernel.NSTATE)),
             np.empty((n_t, prep.kernel.NOUT)), np.zeros(prep.kernel.INFO_LENGTH))
    start = _time.perf_counter()
    y_end, y_out, out, info = run_kernel(prep, solver, progress,
                                         chunks=50 if progress else 1)
    wall = _time.perf_counter() - start
    stats = SolverStats.from_info(prep.kernel, info)
    if not stats.ok:
        raise failure(prep, solver, stats, y_end)
    return Result.from_run(prep, experiment, solver, y_out, out, stats, wall)
