"""Forward parameter sensitivities d(signal)/d(parameter) along a simulation.

The sensitivities s = ∂y/∂θ obey ds/dt = J·s + ∂f/∂θ. They are integrated with the
state inside the compiled RODAS4 loop, with the same stages and LU factors (the
staggered direct method), from the components' analytic Jacobians and analytic
parameter derivatives; a parameter that enters derived quantities (γ through the
polytropic index and the orifice constants) moves them along (``Assembly.directions``).
The start ∂y0/∂θ comes from central differences of the compiled equilibrium. Derived
outputs (friction, flows) get their sensitivities by the chain rule at the output times.

For identification they are the columns of the least-squares Jacobian; for local
sensitivity analysis ``relative()`` gives θ·∂y/∂θ, comparable across parameters.
"""

from __future__ import annotations

import functools
import time as _time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..core.c_engine import check_engine, engine_scope
from ..errors import ParameterError
from ..io.report import ResultVocabulary
from ..progress import raise_if_stopped

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure
from ..plotting import tight_layout
from .memory import check_memory, simulate_bytes
from .result import Result, SolverStats
from .simulate import Prepared, failure, prepare
from .solvers import Rodas4

__all__ = ["SensitivityResult", "simulate_sensitivities"]


@dataclass(eq=False)
class SensitivityResult(ResultVocabulary):
    """The simulation and, per signal, an array (n_time × n_parameters) of ∂signal/∂θ.

    ``to_pandas()``: the long table (``"simulation"``: the run's signals); ``plot()``:
    the relative sensitivities θ·∂y/∂θ of position (or the first signal) over time;
    ``write(folder)``: both tables, the figure and report.html.

    State sensitivities come from the integration; those of derived outputs (friction,
    pressure of a source, flows) are computed by the chain rule on first access only.
    """

    result: Result
    parameters: list[str]
    values: np.ndarray
    sensitivities: dict[str, np.ndarray]
    _derived: dict[str, Callable[[], np.ndarray]] = field(default_factory=dict, repr=False)
    units: dict[str, str] = field(default_factory=dict)

    @property
    def signals(self) -> list[str]:
        return list(self.sensitivities) + [n for n in self._derived
                                           if n not in self.sensitivities]

    def __getitem__(self, signal: str) -> np.ndarray:
        if signal not in self.sensitivities:
            if signal not in self._derived:
                raise KeyError(f"no sensitivity of {signal!r}; signals: "
                               f"{', '.join(self.signals)}")
            self.sensitivities[signal] = self._derived[signal]()
        return self.sensitivities[signal]

    def relative(self, signal: str) -> np.ndarray:
        """θ·∂signal/∂θ: the change of the signal per relative change of each parameter."""
        return self[signal] * self.values[None, :]

    report_title = "Forward sensitivities"
    figure_name = "relative_sensitivities"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"sensitivities": self.to_pandas(), "simulation": self.result.to_pandas()}

    @staticmethod
    def tables_names() -> tuple[str, ...]:
        """The names of ``tables()`` (a signal of the same name yields to them)."""
        return ("sensitivities", "simulation")

    def notebook_table(self) -> pd.DataFrame:
        """Per signal and parameter, the largest |θ·∂y/∂θ| over the run (``max``)."""
        import pandas as pd

        rows = [{"signal": sig, "parameter": par, "unit": self.result.units.get(sig, ""),
                 "max": float(np.max(np.abs(self.relative(sig)[:, k])))}
                for sig in self.signals for k, par in enumerate(self.parameters)]
        return pd.DataFrame(rows, columns=["signal", "parameter", "unit", "max"])

    def report_text(self) -> str:
        return (f"∂signal/∂θ along {self.result.meta.get('experiment', 'the run')} for "
                f"{', '.join(self.parameters)}; the figure shows θ·∂y/∂θ (the change per "
                "relative change of each parameter).")

    def plot(self, signal: str | None = None) -> Figure:
        """θ·∂signal/∂θ over time, one line per parameter (default signal: position)."""
        import matplotlib.pyplot as plt

        signal = signal or ("position" if "position" in self.signals else self.signals[0])
        fig, ax = plt.subplots(figsize=(7.0, 3.8))
        relative = self.relative(signal)
        for k, name in enumerate(self.parameters):
            ax.plot(self.result.time, relative[:, k], label=name)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"θ·∂{signal}/∂θ [{self.result.units.get(signal, '')}]")
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
        tight_layout(fig)
        return fig

    def to_pandas(self, name: str | None = None):
        """Long table: time, signal, parameter, sensitivity (SI units of signal/parameter);
        ``name="simulation"``: the run's signals; ``name`` a signal ("position"): its
        ∂signal/∂θ labelled, a column per parameter over a ``time`` index, the units in
        ``attrs["units"]`` (``self["position"]`` is the same as a bare array)."""
        import pandas as pd

        if name is not None and name in self.signals and name not in self.tables_names():
            frame = pd.DataFrame(self[name], columns=list(self.parameters),
                                 index=pd.Index(np.array(self.result.time), name="time"))
            frame.attrs["units"] = {par: f"{self.result.units.get(name, '')}/"
                                         f"({self.units.get(par) or '1'})"
                                    for par in self.parameters}
            return frame
        if name is not None:
            return super().to_pandas(name)
        frames = []
        for name in self.signals:
            arr = self[name]
            for k, par in enumerate(self.parameters):
                frames.append(pd.DataFrame({
                    "time": self.result.time, "signal": name, "parameter": par,
                    "sensitivity": arr[:, k],
                    "unit": f"{self.result.units[name]}/({self.units.get(par) or '1'})",
                }))
        return pd.concat(frames, ignore_index=True)


def initial_sensitivity(prep: Prepared, names: Sequence[str]) -> np.ndarray:
    """∂y0/∂θ of the equilibrium start, by central differences of the compiled
    ``initial_state`` (n × len(names))."""
    assembly, kernel = prep.assembly, prep.kernel
    n = len(assembly.states)
    cols = []
    t0, ts0 = prep.breakpoints[0], prep.segment_time
    for name in names:
        value = prep.vector[assembly.slots[name][0]]
        step = 1e-6 * (abs(value) if value != 0 else 1.0)
        ys = []
        for sign in (1.0, -1.0):
            vec = assembly.update(prep.vector.copy(), {name: value + sign * step})
            y = np.empty(n)
            kernel.initial_state(t0, ts0, vec, prep.sig, prep.ptr, y)
            ys.append(y)
        cols.append((ys[0] - ys[1]) / (2 * step))
    return np.column_stack(cols)


def simulate_sensitivities(model, experiment, parameters: Sequence[str], solver=None, *,
                           t_eval=None, y0=None, values=None,
                           engine: str | None = None) -> SensitivityResult:
    """Simulate and integrate ∂y/∂θ for ``parameters`` (any parameters of the model).

    Only the RODAS4 solver carries sensitivities. With ``y0`` given, the start does not
    depend on the parameters (∂y0/∂θ = 0). ``values`` overrides parameter values for
    this run and ``engine`` chooses where it runs, as in ``simulate``.
    """
    raise_if_stopped()
    with engine_scope(check_engine(engine, "simulate_sensitivities: engine")):
        return _sensitivities(model, experiment, parameters, solver, t_eval, y0, values)


def _sensitivities(model, experiment, parameters: Sequence[str], solver, t_eval, y0,
                   values) -> SensitivityResult:
    from ..parameters import catalogue

    solver = Rodas4() if solver is None else solver
    if solver.kernel_function != "integrate_rodas4":
        raise ParameterError(f"sensitivities need the Rodas4 solver, got "
                             f"{type(solver).__name__}")
    names = list(parameters)
    if not names:
        raise ParameterError("sensitivities: give at least one parameter name")
    if model.sensitivity_refusal is not None:
        raise ParameterError(
            f"sensitivities: {model.describe()} does not carry forward sensitivities "
            f"({model.sensitivity_refusal}); use finite differences or the batch engine")
    prep = prepare(model, experiment, solver, t_eval, y0, values=values)
    assembly, kernel = prep.assembly, prep.kernel
    names = assembly.check_parameters(names, "sensitivities")
    check_memory(simulate_bytes(prep.t_out.size, len(assembly.states), kernel.NOUT,
                                len(names)),
                 f"sensitivities to {len(names)} parameters on {prep.t_out.size} output points")
    w_ptr, w_idx, w_val = assembly.directions(prep.vector, names)
    needed = np.zeros(assembly.size, dtype=np.bool_)
    needed[w_idx] = True
    n, n_t = len(assembly.states), prep.t_out.size
    s0 = np.zeros((n, len(names))) if y0 is not None else initial_sensitivity(prep, names)
    y_out = np.empty((n_t, n))
    out = np.empty((n_t, kernel.NOUT))
    s_out = np.empty((n, n_t, len(names)))  # one contiguous n_t × P block per state
    info = np.zeros(kernel.INFO_LENGTH)
    start = _time.perf_counter()
    y_end = kernel.integrate_rodas4_sens(
        prep.y0, prep.vector, prep.sig, prep.ptr, prep.breakpoints, prep.t_out, solver.rtol,
        prep.atol, solver.h_init, solver.h_max, prep.max_steps, y_out, out, info, w_ptr,
        w_idx, w_val, needed, s0, s_out)
    wall = _time.perf_counter() - start
    stats = SolverStats.from_info(kernel, info)
    if not stats.ok:
        raise failure(prep, solver, stats, y_end)
    result = Result.from_run(prep, experiment, solver, y_out, out, stats, wall)
    handed_out = s_out.view()  # read-only views; the kernel keeps the writeable array
    handed_out.flags.writeable = False
    sens = {name: handed_out[i] for i, name in enumerate(assembly.state_names)}
    derived = _output_sensitivities(prep, experiment, result, sens, y_out, s_out,
                                    (w_ptr, w_idx, w_val), len(names))
    specs = catalogue()
    values = np.array([prep.vector[assembly.slots[n][0]] for n in names])
    own = assembly.parameter_units  # a controller's gains: in the loop's units
    return SensitivityResult(result, names, values, sens, derived,
                             {n: own.get(n) or specs[n].unit for n in names})


def _output_sensitivities(prep, experiment, result, sens, y_out, s_out, directions,
                          n_par) -> dict[str, Callable[[], np.ndarray]]:
    """Lazy chain-rule sensitivities of the derived outputs (one pass computes all)."""
    assembly, kernel = prep.assembly, prep.kernel
    computed: list[np.ndarray] = []

    def column(i: int) -> np.ndarray:
        if not computed:
            bp, t_out = prep.breakpoints, prep.t_out
            k = np.clip(np.searchsorted(bp, t_out, side="right") - 1, 0, bp.size - 2)
            ts_out = 0.5 * (bp[k] + bp[k + 1])
            d_out = np.empty((kernel.NOUT, t_out.size, n_par))
            kernel.output_sensitivities(t_out, ts_out, y_out, s_out, prep.vector.copy(),
                                        prep.sig, prep.ptr, *directions, d_out)
            d_out.flags.writeable = False
            computed.append(d_out)  # not passed to a kernel again
        return computed[0][i]

    derived: dict[str, Callable[[], np.ndarray]] = {}
    for i, name in enumerate(assembly.output_names):
        if name == "drive":
            name = f"drive_{experiment.quantity}"
        if name not in sens and name in result.signals:
            derived[name] = functools.partial(column, i)
    return derived
