"""The linearised plant, the nonlinear model's sine-sweep frequency response and a Bode plot.

``linearise(plant, input_value)`` gives the plant's state-space model
dy/dt = A·Δy + B·Δu, Δx = C·Δy (+ D·Δu, D = 0) about an operating point:

- ``regime="presliding"``: the static equilibrium under the constant input (the kernel's
  ``initial_state``: v = 0, the friction unloaded; a rig under a force F has its bristle
  take the load, σ0·z = F). At v = 0 the LuGre friction acts as the bristle spring σ0 with
  the damping σ1 + σ2 (a static map as its slope at v = 0). The law is smooth there while
  the bristle is unloaded (the actuator's rest); under a load (z ≠ 0) the term σ0·|v|·z/g
  has a kink and A holds the mean of the two one-sided slopes.
- ``regime="sliding"``: the state moved to steady sliding at ``velocity`` (bristle at its
  steady deflection, with the sign of v, the other states as at rest). This is a motion,
  not an equilibrium (the position moves at v, ``LinearPlant.rates`` is not zero): the
  model describes small deviations from that motion, and the friction enters through its
  local slopes ∂F/∂v, ∂F/∂z there.

The plant's other declared inputs (a cylinder's external ``load``) are held at the
constant values ``inputs`` gives (zero where it gives none): a cylinder holding a
position under a load is linearised at the spool command ``ClosedLoop.holding_input``
finds under the same ``inputs``.

A is the kernel's analytic Jacobian ∂f/∂y at the point; B = ∂f/∂u by central differences
of the kernel's ``rhs`` with the input channel at u ± δ, δ = 1e-6·max(|u|, input scale)
(one-sided at an end of the input's range; f is linear in u for every valve and the force
drive, so δ only sets the round-off); C picks the named outputs among the states.

``frequency_response(plant, input_value, amplitude, frequencies)`` drives the nonlinear
model with u = input_value + amplitude·sin(2πft), one run per frequency, and fits the
fundamental of the position. ``plot_bode`` shows both. python-control is optional
(``pip install 'pneumact[control]'``): only ``LinearPlant.to_control`` needs it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.signals import Constant, Signal, Sine, pack_channels
from ..errors import ExperimentError, ParameterError
from ..experiments.actuator import Experiment
from ..io.report import ResultVocabulary
from ..models.valves import PRESSURE_INPUT
from ..plotting import tight_layout
from .plants import held_inputs, input_kind, input_range

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

__all__ = ["REGIMES", "LinearPlant", "frequency_response", "linearise", "plot_bode"]

REGIMES = ("presliding", "sliding")
#: central-difference step of B, relative to max(|u|, the input's scale)
FD_REL_STEP = 1e-6
#: singular values of the scaled A below this fraction of the largest are zero (dc_gain)
NULL_RTOL = 1e-9
#: time of the operating point (a time-varying load is taken at its value at t = 0)
T_POINT = 0.0
#: time constants of the slowest stable pole the sweep discards by default
SETTLE_TIME_CONSTANTS = 5.0
#: default integrator tolerance of the sweep: atol = rtol × state scale, 2e-11 m on the
#: position, far below the sub-micrometre responses of a presliding sweep
SWEEP_RTOL = 1e-9


def _require_control():
    try:
        import control
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("LinearPlant.to_control needs python-control: "
                          "pip install 'pneumact[control]'") from exc
    return control


# --------------------------------------------------------------------------- the plant
def _input_scale(plant, kind: str) -> float:
    if kind == PRESSURE_INPUT.name:
        return float(plant.params["p_atm"])
    return 1.0


def _check_input(plant, kind: str, value, what: str = "input_value") -> float:
    lo, hi = input_range(plant)
    unit = plant.drive_unit
    if not (isinstance(value, int | float | np.floating) and math.isfinite(value)):
        raise ExperimentError(f"linearise: {what} = {value!r}; must be a finite "
                              f"{plant.drive_quantity} [{unit}]")
    if not lo <= value <= hi:
        raise ExperimentError(f"linearise: {what} = {value!r} {unit}; allowed for the "
                              f"{plant.drive_quantity} of this plant: [{lo:g}, {hi:g}] {unit}")
    return float(value)


def _quantity(name: str, value: float, unit: str) -> str:
    """"command = 0.6", "force = 1 N": a value with its unit (none for a ratio)."""
    return f"{name} = {value:g}" + ("" if unit == "1" else f" {unit}")


def _signals(plant, value: float, held: Mapping[str, Signal] | None = None):
    """The packed channels: the drive at ``value``, the ``held`` inputs on theirs."""
    return pack_channels(plant.channels(Constant(value), held))


def _unit_of(plant, name: str) -> str:
    """The unit of the plant's declared input ``name``."""
    return next(channel.unit for channel in plant.inputs() if channel.name == name)


def _rates(kernel, y, vec, sig, ptr) -> np.ndarray:
    f = np.empty_like(y)
    kernel.rhs(T_POINT, T_POINT, y, vec, sig, ptr, f)
    return f


def _friction_takes_load(plant, kind, assembly, kernel, y, vec, sig, ptr, u) -> None:
    """A rig under a constant force rests on its friction law's state: σ0·z = F for LuGre
    (Newton on the state, exact for the laws linear in z at v = 0); a static map, a force
    beyond the law's bound, or a law of several states (whose rest under a load depends on
    its history) leaves no state of rest here."""
    if kind != "force" or u == 0.0:
        return
    iv = assembly.state_index("velocity")
    friction_states = assembly.role_states("friction")
    if len(friction_states) == 1:
        iz, = friction_states
        jac = np.zeros((y.size, y.size))
        for _ in range(3):
            f = _rates(kernel, y, vec, sig, ptr)
            jac[:] = 0.0
            kernel.jac(T_POINT, T_POINT, y, vec, sig, ptr, jac)
            if jac[iv, iz] == 0.0:
                break
            y[iz] -= f[iv] / jac[iv, iz]
        bounded = y.copy()
        kernel.project(vec, bounded)
        residual = _rates(kernel, y, vec, sig, ptr)[iv] * float(plant.params["m"])
        if bounded[iz] == y[iz] and abs(residual) <= 1e-9 * abs(u):
            return
    can_carry = {0: "0 N (a static map)", 1: "its presliding force (max(Fs, Fc) for LuGre)"}
    raise ExperimentError(
        f"linearise: input_value = {u:g} N holds no presliding rest for "
        f"{plant.describe()} (the friction at rest can carry at most "
        f"{can_carry.get(len(friction_states), 'a force that depends on its history')}); "
        "allowed: a smaller force, or regime='sliding'")


def _friction_laws(plant) -> list[tuple[Any, Mapping[str, float]]]:
    """(law, its parameters by their local names) of each friction law of the plant: its
    one law's at the set's names, or each law a cylinder places at its instance's
    (``friction_rod.Fc`` as ``Fc``)."""
    laws = getattr(plant, "friction_laws", None) or {"friction": plant.friction}
    if "friction" in laws:
        return [(laws["friction"], plant.params)]
    return [(law, {n: plant.params[f"{instance}.{n}"] for n in law.block.parameters})
            for instance, law in laws.items()]


def _friction_words(plant) -> str:
    laws = _friction_laws(plant)
    stiffness = sum(law.presliding_stiffness(params) for law, params in laws)
    if stiffness == 0.0:
        return "the static friction map acts as its slope at v = 0"
    names = {n for law, _ in laws for n in law.block.names}
    damping = sum(float(params[n]) for law, params in laws for n in ("sigma1", "sigma2")
                  if n in law.block.names)
    label = "σ1 + σ2" if "sigma1" in names else "σ2"
    return (f"the friction acts as a spring of its presliding stiffness {stiffness:g} N/m "
            f"with damping {label} = {damping:g} N·s/m")


def _where(plant, y, names, units) -> str:
    """The point in words: the position (on a stop, where the plant has a stroke) and
    every pressure state."""
    x = y[names.index("position")]
    text = f"position {x * 1e3:.6g} mm"
    stroke = plant.stroke
    if stroke is not None:
        if x < 0.0:
            text += " (on the rest stop)"
        elif x > stroke:
            text += " (on the far end stop)"
    for name, unit, value in zip(names, units, y, strict=True):
        if unit == "Pa":
            text += f", {name.replace('_', ' ')} {value * 1e-3:.6g} kPa"
    return text


def _check_position(plant, position, who: str = "linearise") -> float:
    """``position`` [m] within the plant's stroke, or one ExperimentError naming ``who``."""
    stroke = plant.stroke
    top = math.inf if stroke is None else stroke
    if not (isinstance(position, int | float | np.floating) and 0.0 <= position <= top):
        raise ExperimentError(f"{who}: position = {position!r}; allowed: a position "
                              f"[m] in [0, {top:g}]")
    return float(position)


def _place(plant, y, names, position) -> None:
    """Move the rest state to ``position`` [m] within the plant's stroke (the other
    states as at rest: a cylinder's chambers at their balanced pressures)."""
    y[names.index("position")] = _check_position(plant, position)


@dataclass(frozen=True, eq=False)
class LinearPlant(ResultVocabulary):
    """A linearised plant: dΔy/dt = A·Δy + B·Δu, Δx = C·Δy + D·Δu (single input).

    ``to_pandas()``: the system matrix; ``plot()``: its Bode plot (``plot_bode``);
    ``write(folder)``: system.csv, bode.png and report.html.

    ``operating_point``: state name -> value, the input's name -> its value, and each
    other input held (``linearise(..., inputs=...)``) -> its value.
    ``rates``: f at the point (zero at an equilibrium; the sliding point moves).
    ``statement``: one sentence naming the regime and the point, for reports.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    state_names: tuple[str, ...]
    state_units: tuple[str, ...]
    input_name: str
    input_unit: str
    output_names: tuple[str, ...]
    operating_point: dict[str, float]
    regime: str
    statement: str
    rates: np.ndarray = field(default_factory=lambda: np.zeros(0))
    state_scales: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def equilibrium(self) -> bool:
        """True for the presliding rest, False for the sliding motion."""
        return self.regime == "presliding"

    @property
    def output_units(self) -> tuple[str, ...]:
        return tuple(self.state_units[self.state_names.index(n)] for n in self.output_names)

    def _squeeze(self, values: np.ndarray):
        return values[0] if len(self.output_names) == 1 else values

    def _scaling(self) -> np.ndarray:
        s = self.state_scales
        if s.size != len(self.state_names) or not np.all(np.isfinite(s) & (s > 0)):
            return np.ones(len(self.state_names))
        return s

    def poles(self) -> np.ndarray:
        """Eigenvalues of A [rad/s]. In presliding the LuGre x − z mode is a pole at 0 that
        the input cannot excite (dz/dt = dx/dt at v = 0)."""
        return np.linalg.eigvals(self.A)

    def dc_gain(self):
        """Static gain Δx/Δu per output (float, or an array for several outputs).

        A pole at the origin cancels where the input cannot move its mode (the presliding
        x − z mode: dz/dt = dx/dt at v = 0) or the output cannot see it (the velocity of
        a damped free mass): with N, W the right and left null spaces of A, the limit
        s → 0 of C(sI − A)⁻¹B is −C·A^#·B (A^# the group inverse: A·Δy = −(B − Π·B),
        WᵀΔy = 0, Π = N(WᵀN)⁻¹Wᵀ). An output that sees a driven pole at the origin (the
        position of a mass with no spring) has an infinite gain (``inf``). A defective
        pole at the origin (a mass with neither spring nor damper) is resolved
        numerically, from the response at two tiny frequencies."""
        a, b, c = self._scaled()
        u_, sv, vt = np.linalg.svd(a)
        zero = sv <= NULL_RTOL * sv[0]
        if not zero.any():
            gain = c @ np.linalg.solve(a, -b)
            return self._squeeze(gain + self.D[:, 0])
        left, right = u_[:, zero], vt[zero].T
        wn = left.T @ right
        if np.linalg.cond(wn) > 1.0 / NULL_RTOL:
            return self._numeric_limit(sv[0])
        amount = np.linalg.solve(wn, left.T @ b)
        drift = c @ (right @ amount)  # the 1/s term of each output
        system = np.vstack([a, left.T])
        rhs = np.concatenate([-(b - right @ amount), np.zeros(left.shape[1])])
        gain = c @ np.linalg.lstsq(system, rhs, rcond=None)[0] + self.D[:, 0]
        size = np.linalg.norm(c, axis=1) * max(np.linalg.norm(b), 1e-300)
        return self._squeeze(np.where(np.abs(drift) > NULL_RTOL * size, np.inf, gain))

    def _numeric_limit(self, fastest: float):
        s1 = 1e-7 * fastest
        g1 = np.abs(self._response(s1))
        g2 = self._response(0.1 * s1)
        growing = np.abs(g2) > 5.0 * g1
        return self._squeeze(np.where(growing, np.inf, g2.real))

    def _scaled(self):
        s = self._scaling()
        return (self.A * s[None, :] / s[:, None], self.B[:, 0] / s, self.C * s[None, :])

    def _response(self, s: complex) -> np.ndarray:
        a, b, c = self._scaled()
        return c @ np.linalg.solve(s * np.eye(a.shape[0]) - a, b) + self.D[:, 0]

    def frequency_response(self, freq_hz) -> np.ndarray:
        """C(jωI − A)⁻¹B + D at ω = 2π·freq_hz, complex: shape (n,) for one output, else
        (outputs, n). A frequency of 0 gives ``dc_gain``."""
        f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
        out = np.empty((len(self.output_names), f.size), dtype=complex)
        for k, fk in enumerate(f):
            if fk == 0.0:
                out[:, k] = np.atleast_1d(self.dc_gain())
            else:
                out[:, k] = self._response(2j * np.pi * fk)
        return self._squeeze(out)

    def to_control(self):
        """The model as a ``control.StateSpace`` with named states, input and outputs
        (needs python-control: ``pip install 'pneumact[control]'``)."""
        control = _require_control()
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.state_names),
                          inputs=[self.input_name], outputs=list(self.output_names),
                          name=f"linearised plant ({self.regime})")

    report_title = "Linearised plant"
    figure_name = "bode"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"system": self.to_pandas()}

    def report_text(self) -> str:
        return self.statement

    def plot(self) -> Figure:
        """The Bode plot of the first output (``plot_bode``)."""
        return plot_bode(self)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """The system matrix [[A, B], [C, D]] as a DataFrame: rows ("d/dt", state) then
        ("output", name); columns ("state", name) then ("input", name). The operating point
        and the statement are in ``.attrs``."""
        import pandas as pd

        if name not in (None, "system"):
            raise ParameterError(f"to_pandas: name = {name!r}; allowed: system")
        rows = pd.MultiIndex.from_tuples(
            [("d/dt", n) for n in self.state_names] + [("output", n) for n in self.output_names])
        cols = pd.MultiIndex.from_tuples(
            [("state", n) for n in self.state_names] + [("input", self.input_name)])
        matrix = np.block([[self.A, self.B], [self.C, self.D]])
        frame = pd.DataFrame(matrix, index=rows, columns=cols)
        frame.attrs.update(regime=self.regime, statement=self.statement,
                           operating_point=dict(self.operating_point),
                           input_unit=self.input_unit)
        return frame

    def __repr__(self) -> str:
        return (f"LinearPlant({self.regime}, {len(self.state_names)} states, "
                f"{self.input_name} -> {', '.join(self.output_names)})")


def linearise(plant, input_value: float, *, regime: str = "presliding",
              velocity: float | None = None, position: float | None = None,
              outputs: Sequence[str] = ("position",),
              inputs: Mapping[str, float] | None = None) -> LinearPlant:
    """The plant (an ``Actuator`` behind any valve, a ``Cylinder`` or a
    ``FrictionRig(drive="force")``) linearised under the constant input ``input_value``
    (command [0, 1], spool command [−1, 1], pressure [Pa] or force [N]).

    ``position`` [m]: the point's position instead of the rest's (the other states as at
    rest); an equilibrium where the input balances the forces there (a cylinder at the
    spool command that balances its chambers, any position), else ``rates`` shows the
    acceleration left.

    ``regime``: ``"presliding"`` (the static equilibrium, v = 0) or ``"sliding"`` (steady
    sliding at ``velocity`` [m/s], non-zero, its sign the direction; a motion, not an
    equilibrium); see the module docstring. ``outputs``: state names, default the
    position. ``inputs``: the plant's other declared inputs held at constant values (name
    -> SI value), e.g. a cylinder under a constant external load, ``{"load": 500.0}``
    [N against extension]; those left out are zero (``{"load": 0.0}`` is the same
    linearisation, bit for bit). Raises ``ParameterError`` (plant, regime, velocity,
    outputs) or ``ExperimentError`` (input value, an input the plant does not declare or
    a value outside its range) naming the field, the value and what is allowed.
    """
    from ..core.assembly import assemble

    kind = input_kind(plant, "linearise")
    if regime not in REGIMES:
        raise ParameterError(f"linearise: regime = {regime!r}; allowed: {', '.join(REGIMES)}")
    if regime == "sliding":
        if velocity is None or not (isinstance(velocity, int | float | np.floating)
                                    and math.isfinite(velocity) and velocity != 0.0):
            raise ParameterError(f"linearise: velocity = {velocity!r}; regime='sliding' needs "
                                 "the sliding velocity, a finite non-zero number [m/s]")
    elif velocity is not None:
        raise ParameterError(f"linearise: velocity = {velocity!r}; allowed only with "
                             "regime='sliding' (presliding is at v = 0)")
    assembly = assemble(plant)
    names = assembly.state_names
    if isinstance(outputs, str):
        outputs = (outputs,)
    outputs = tuple(outputs)
    bad = [n for n in outputs if n not in names]
    if bad or not outputs:
        raise ParameterError(f"linearise: outputs = {list(outputs)!r}; allowed: state names "
                             f"{', '.join(names)}")
    u = _check_input(plant, kind, input_value)
    held = held_inputs(plant, inputs, "linearise")
    held_values = {name: float(value) for name, value in (inputs or {}).items()}
    kernel = assembly.kernel
    vec = assembly.pack()
    sig, ptr = _signals(plant, u, held)
    n = len(names)
    y = np.empty(n)
    kernel.initial_state(T_POINT, T_POINT, vec, sig, ptr, y)
    if position is not None:
        _place(plant, y, names, position)
    iv = names.index("velocity")
    friction_states = list(assembly.role_states("friction"))
    friction_words = _friction_words(plant)
    unit = plant.drive_unit
    applied = ", ".join([_quantity(plant.drive_quantity, u, unit),
                         *(_quantity(name, value, _unit_of(plant, name))
                           for name, value in held_values.items())])
    if regime == "presliding":
        _friction_takes_load(plant, kind, assembly, kernel, y, vec, sig, ptr, u)
        statement = (f"Linearised about the static equilibrium under {applied}, presliding "
                     f"(v = 0, friction at rest: {friction_words}); "
                     f"{_where(plant, y, names, assembly.state_units)}.")
    else:
        assert velocity is not None  # regime 'sliding' checked it above
        v = float(velocity)
        y[iv] = v
        y[friction_states] = np.concatenate([law.steady_states(v, params)[0]
                                             for law, params in _friction_laws(plant)])
        steady = ", ".join(f"{names[i]} = {y[i]:.6g}" for i in friction_states)
        steady = f": {steady}" if steady else ""
        statement = (f"Linearised about steady sliding at v = {v:g} m/s (friction states at "
                     f"their steady values{steady}) under {applied}, from "
                     f"{_where(plant, y, names, assembly.state_units)}: a motion, not an "
                     "equilibrium (the position "
                     "moves at v), with the friction entering through its "
                     "local slopes ∂F/∂v, ∂F/∂z there.")
    a = np.zeros((n, n))
    kernel.jac(T_POINT, T_POINT, y, vec, sig, ptr, a)
    b = _input_derivative(plant, kind, kernel, y, vec, u, held)
    c = np.zeros((len(outputs), n))
    for row, name in enumerate(outputs):
        c[row, names.index(name)] = 1.0
    scales = np.empty(n)
    kernel.state_scales(vec, scales)
    point = {name: float(value) for name, value in zip(names, y, strict=True)}
    point[plant.drive_quantity] = u
    point.update(held_values)
    return LinearPlant(A=a, B=b[:, None], C=c, D=np.zeros((len(outputs), 1)),
                       state_names=names, state_units=assembly.state_units,
                       input_name=plant.drive_quantity, input_unit=unit,
                       output_names=outputs, operating_point=point, regime=regime,
                       statement=statement, rates=_rates(kernel, y, vec, sig, ptr),
                       state_scales=scales)


def _input_derivative(plant, kind: str, kernel, y, vec, u: float,
                      held: Mapping[str, Signal]) -> np.ndarray:
    """∂f/∂u by central differences of rhs (one-sided at an end of the input's range),
    the ``held`` inputs at their values."""
    lo, hi = input_range(plant)
    step = FD_REL_STEP * max(abs(u), _input_scale(plant, kind))
    up, down = u + step, u - step
    if down < lo:
        down = u
    if up > hi:
        up = u
    f_up = _rates(kernel, y, vec, *_signals(plant, up, held))
    f_down = _rates(kernel, y, vec, *_signals(plant, down, held))
    return (f_up - f_down) / (up - down)


# ----------------------------------------------------------------- nonlinear frequency sweep
def _default_settle_time(plant, input_value: float, position: float | None = None,
                         inputs: Mapping[str, float] | None = None) -> float:
    """SETTLE_TIME_CONSTANTS time constants of the slowest stable pole of the presliding
    linearisation (poles at the origin excluded), 0 when there is no such rest."""
    try:
        lin = linearise(plant, input_value, position=position, inputs=inputs)
    except (ParameterError, ExperimentError):
        return 0.0
    poles = lin.poles()
    size = np.max(np.abs(poles)) if poles.size else 0.0
    decay = -poles.real[poles.real < -1e-9 * size]
    return SETTLE_TIME_CONSTANTS / float(decay.min()) if decay.size else 0.0


def frequency_response(plant, input_value: float, amplitude: float, frequencies, *,
                       periods: int = 10, settle_periods: int = 5,
                       points_per_period: int = 64, settle_time: float | None = None,
                       output: str = "position", solver=None,
                       position: float | None = None,
                       inputs: Mapping[str, float] | None = None) -> pd.DataFrame:
    """Stepped-sine frequency response of the nonlinear model.

    For each frequency f the plant starts at rest under ``input_value`` and is driven by
    input_value + amplitude·sin(2πft); the first max(settle_periods/f, settle_time)
    seconds (rounded up to whole periods) are discarded, and the ``output`` over the next
    ``periods`` periods (``points_per_period`` samples each) is fitted by least squares
    with a·sin(2πft) + b·cos(2πft) + offset + drift·t. ``settle_time`` defaults to five
    time constants of the slowest stable pole of the presliding linearisation (the
    chamber's, behind a valve). ``solver`` defaults to Rodas4(rtol=1e-9). ``position``
    [m] and ``inputs`` are ``linearise``'s: each run starts at rest placed there (a
    cylinder, which rests on a stop, held mid-stroke) under the plant's other declared
    inputs held at constant values (a cylinder's ``{"load": F}``).

    Returns a DataFrame with one row per frequency: ``frequency_hz``, ``amplitude`` (of
    the input), ``gain`` (output amplitude per input unit, e.g. m per command unit),
    ``phase_deg`` (of the output's fundamental against the input sine, in (−180, 180]),
    ``response_amplitude`` (the fundamental's amplitude, output units), ``offset`` (mean
    output), ``drift`` (output units per second) and ``residual`` (RMS of what the fit
    leaves, per RMS of the fundamental: 0 for a linear response, the harmonics and noise
    of a nonlinear one).
    """
    import pandas as pd

    from ..simulation import Rodas4, simulate

    kind = input_kind(plant, "linearise")
    u0 = _check_input(plant, kind, input_value)
    held = held_inputs(plant, inputs, "frequency_response")
    start = None if position is None else {
        "position": _check_position(plant, position, "frequency_response")}
    if not (isinstance(amplitude, int | float) and math.isfinite(amplitude) and amplitude > 0):
        raise ExperimentError(f"frequency_response: amplitude = {amplitude!r}; must be > 0")
    _check_input(plant, kind, u0 - amplitude, "input_value - amplitude")
    _check_input(plant, kind, u0 + amplitude, "input_value + amplitude")
    freqs = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if freqs.ndim != 1 or freqs.size == 0 or not np.all(np.isfinite(freqs) & (freqs > 0)):
        raise ExperimentError(f"frequency_response: frequencies = {frequencies!r}; give "
                              "finite frequencies > 0 [Hz]")
    for name, value, least in (("periods", periods, 1), ("settle_periods", settle_periods, 0),
                               ("points_per_period", points_per_period, 8)):
        if not (isinstance(value, int) and value >= least):
            raise ExperimentError(f"frequency_response: {name} = {value!r}; must be an "
                                  f"integer >= {least}")
    if settle_time is None:
        settle_time = _default_settle_time(plant, u0, position, inputs)
    elif not (math.isfinite(settle_time) and settle_time >= 0):
        raise ExperimentError(f"frequency_response: settle_time = {settle_time!r}; must be "
                              ">= 0 [s]")
    solver = Rodas4(rtol=SWEEP_RTOL) if solver is None else solver
    rows = []
    for f in freqs:
        n_settle = max(settle_periods, math.ceil(settle_time * f - 1e-9))
        t0 = n_settle / f
        t_end = (n_settle + periods) / f
        t = t0 + np.arange(periods * points_per_period) / (f * points_per_period)
        experiment = Experiment(Sine(amplitude, float(f), offset=u0), plant.drive_quantity,
                                t_end, n_points=2, name=f"sine sweep {f:g} Hz", drives=held)
        result = simulate(plant, experiment, solver, t_eval=t, y0=start)
        if output not in result.signals:
            raise ExperimentError(f"frequency_response: output = {output!r}; allowed: "
                                  f"{', '.join(result.signals)}")
        y = np.asarray(result.signals[output], dtype=float)
        w = 2.0 * np.pi * f
        tc = t - 0.5 * (t[0] + t[-1])
        basis = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t), tc])
        coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
        fit_amp = math.hypot(coef[0], coef[1])
        resid = y - basis @ coef
        rms_fund = fit_amp / math.sqrt(2.0)
        rows.append({
            "frequency_hz": float(f), "amplitude": float(amplitude),
            "gain": fit_amp / amplitude,
            "phase_deg": math.degrees(math.atan2(coef[1], coef[0])),
            "response_amplitude": fit_amp, "offset": float(coef[2]), "drift": float(coef[3]),
            "residual": float(np.sqrt(np.mean(resid**2)) / rms_fund) if rms_fund > 0
            else math.inf,
        })
    frame = pd.DataFrame(rows)
    frame.attrs.update(input_name=plant.drive_quantity, input_value=u0,
                       input_unit=plant.drive_unit, output=output)
    return frame


# ----------------------------------------------------------------------------- Bode plot
def _default_frequencies(linear: LinearPlant, measured) -> np.ndarray:
    if measured is not None and len(measured):
        f = np.asarray(measured["frequency_hz"], dtype=float)
        return np.logspace(np.log10(f.min() / 3.0), np.log10(f.max() * 3.0), 400)
    mags = np.abs(linear.poles())
    mags = mags[mags > 1e-9 * (mags.max() if mags.size else 1.0)]
    if not mags.size:
        return np.logspace(-2, 3, 400)
    lo = mags.min() / (2 * np.pi) / 10.0
    hi = min(mags.max() / (2 * np.pi) * 10.0, lo * 1e6)
    return np.logspace(np.log10(lo), np.log10(hi), 400)


def plot_bode(linear: LinearPlant, measured: pd.DataFrame | None = None, *,
              freq_hz=None, output: str | None = None) -> Figure:
    """Bode plot of the linear model (lines) with the nonlinear sweep's points
    (``frequency_response`` frames, one marker set per input amplitude): magnitude in
    mm (of position; the output's display unit otherwise) per input unit on log-log
    axes, phase in degrees (the sweep's phases moved by whole turns next to the line's).
    The title states the regime and the operating input."""
    import matplotlib.pyplot as plt

    from ..plotting import DISPLAY_UNITS

    output = linear.output_names[0] if output is None else output
    if output not in linear.output_names:
        raise ParameterError(f"plot_bode: output = {output!r}; allowed: "
                             f"{', '.join(linear.output_names)}")
    row = linear.output_names.index(output)
    unit = linear.output_units[row]
    shown, factor = DISPLAY_UNITS.get(unit, (unit, 1.0))
    f = _default_frequencies(linear, measured) if freq_hz is None else np.asarray(freq_hz,
                                                                                 float)
    g = np.atleast_2d(linear.frequency_response(f))[row]
    phase = np.degrees(np.unwrap(np.angle(g)))
    fig, (ax_mag, ax_ph) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 6.0))
    ax_mag.loglog(f, np.abs(g) * factor, "C0-", lw=1.5, label=f"linear ({linear.regime})")
    ax_ph.semilogx(f, phase, "C0-", lw=1.5)
    if measured is not None and len(measured):
        for k, (amp, part) in enumerate(measured.groupby("amplitude", sort=True)):
            fm = part["frequency_hz"].to_numpy(float)
            line = np.interp(np.log(fm), np.log(f), phase)
            ph = part["phase_deg"].to_numpy(float)
            ph = ph + 360.0 * np.round((line - ph) / 360.0)
            style = dict(ls="none", marker="os^dv"[k % 5], color=f"C{k + 1}", mfc="none")
            ax_mag.loglog(fm, part["gain"].to_numpy(float) * factor, **style,
                          label="nonlinear sweep, "
                          + _quantity("amplitude", amp, linear.input_unit))
            ax_ph.semilogx(fm, ph, **style)
    ax_mag.set_ylabel(f"|{output}/{linear.input_name}| [{shown}/{linear.input_unit}]")
    ax_ph.set_ylabel("phase [deg]")
    ax_ph.set_xlabel("frequency [Hz]")
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="both", alpha=0.3)
    ax_mag.legend(fontsize=8)
    point = linear.operating_point.get(linear.input_name, float("nan"))
    ax_mag.set_title(f"{linear.regime.capitalize()} linearisation at "
                     f"{_quantity(linear.input_name, point, linear.input_unit)}", fontsize=10)
    tight_layout(fig)
    return fig
