"""Controllers and friction compensation: small strategy objects a closed loop compiles.

A controller is data: its gains, limits and options (derivative kind, anti-windup
scheme, cascade, static compensation, dither) become the *settings* of one parameter
block (``CONTROL_BLOCK``, read by the loop template through the local indices below);
only what changes the controller's states (sampled or continuous, a filtered
derivative, the difference velocity estimate, the LuGre observer) is a compile-time
switch of the kernel. Changing a setting never recompiles; changing a switch compiles
another kernel once per machine.

Sign convention: the error is e = r − x (set-point minus position). A plant whose
position falls when its input rises (the vacuum actuator behind a pressure regulator:
more pressure, less stroke) is driven *reverse-acting*: the loop multiplies the
controller terms by −1, so gains are positive for every plant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

from ..core.component import PARAMETER, SETTING, Block, Part, StateSpec
from ..errors import ParameterError
from ..parameters.catalogue import ParameterSpec as P
from ..parameters.catalogue import declare

__all__ = [
    "CONTROL_BLOCK", "PID", "Cascade", "Compensation", "Controller", "Dither", "LuGreObserver",
    "StaticCompensation",
]

CONTROL_BLOCK = Block.of(settings=(
    "kp", "ki", "kd", "filter_time", "tracking_time", "u_min", "u_max", "kx",
    "velocity_ff", "sample_time", "action", "drive_gain", "bias", "comp_gain",
    "ff_fc", "ff_fs", "ff_vs", "ff_delta", "ff_vsmooth", "dither_amplitude",
    "dither_frequency", "obs_sigma0", "obs_sigma1", "obs_sigma2", "obs_fc", "obs_fs",
    "obs_vs", "obs_gain", "derivative_mode", "anti_windup_mode", "cascade_mode", "kdp"))
CT = {name: CONTROL_BLOCK.index(name) for name in CONTROL_BLOCK.names}
CT_KP, CT_KI, CT_KD = CT["kp"], CT["ki"], CT["kd"]
CT_TF, CT_TT, CT_UMIN, CT_UMAX = CT["filter_time"], CT["tracking_time"], CT["u_min"], CT["u_max"]
CT_KX, CT_VFF, CT_TS, CT_ACTION = CT["kx"], CT["velocity_ff"], CT["sample_time"], CT["action"]
CT_GAIN, CT_BIAS, CT_COMP = CT["drive_gain"], CT["bias"], CT["comp_gain"]
CT_FF_FC, CT_FF_FS, CT_FF_VS = CT["ff_fc"], CT["ff_fs"], CT["ff_vs"]
CT_FF_DELTA, CT_FF_VSMOOTH = CT["ff_delta"], CT["ff_vsmooth"]
CT_DITHER_A, CT_DITHER_F = CT["dither_amplitude"], CT["dither_frequency"]
CT_OBS_S0, CT_OBS_S1, CT_OBS_S2 = CT["obs_sigma0"], CT["obs_sigma1"], CT["obs_sigma2"]
CT_OBS_FC, CT_OBS_FS, CT_OBS_VS, CT_OBS_K = (CT["obs_fc"], CT["obs_fs"], CT["obs_vs"],
                                             CT["obs_gain"])
CT_DERIVATIVE, CT_ANTI_WINDUP = CT["derivative_mode"], CT["anti_windup_mode"]
CT_CASCADE = CT["cascade_mode"]
CT_KDP = CT["kdp"]

#: The block's entries a controller may read as *parameters* (batches, studies, fits and
#: sensitivities vary them by name), with the catalogue's unit for a controller output
#: without unit (a command valve's); a loop states the units for its plant
#: (``Controller.parameter_units``: kp is Pa/m behind a pressure regulator, N/m on a rig).
declare(
    P("kp", "1/m", "proportional gain (controller output per metre of position error)",
      None, 0.0, group="controller"),
    P("ki", "1/(m*s)", "integral gain (controller output per metre-second of error; a "
      "cascade's: per metre)", None, 0.0, group="controller"),
    P("kd", "s/m", "derivative gain (controller output per m/s)", None, 0.0,
      group="controller"),
    P("kdp", "1/Pa", "pressure-difference feedback gain (controller output per pascal of "
      "the piston's pressure force per cap area, a cylinder's)", None, 0.0,
      group="controller"),
    P("kv", "s/m", "cascade: inner velocity gain (controller output per m/s)", None, 0.0,
      group="controller"),
    P("kx", "1/s", "cascade: outer position gain (velocity reference per metre)", None, 0.0,
      group="controller"),
    P("filter_time", "s", "time constant of the derivative filter", None, 0.0, True,
      group="controller"),
    P("tracking_time", "s", "back-calculation anti-windup tracking time", None, 0.0, True,
      group="controller"),
    P("velocity_ff", "s/m", "feed-forward gain on the set-point velocity", None,
      group="controller"),
    P("ff_fc", "N", "static friction compensation: Coulomb level", None, 0.0,
      group="controller"),
    P("ff_fs", "N", "static friction compensation: break-away level", None, 0.0,
      group="controller"),
    P("dither_amplitude", "1", "dither amplitude (controller output units)", None,
      group="controller"),
    P("dither_frequency", "Hz", "dither frequency", None, 0.0, True, group="controller"),
    P("obs_gain", "1/s", "LuGre observer gain k", None, group="controller"),
    P("bias", "1", "controller output its terms add to (the loop's holding input)", None,
      group="controller"),
)

#: the entries a controller may read as parameters (the rest are always settings)
TUNABLE = ("kp", "ki", "kd", "kdp", "filter_time", "tracking_time", "kx", "velocity_ff", "ff_fc",
           "ff_fs", "dither_amplitude", "dither_frequency", "obs_gain")

#: derivative options -> the ``derivative_mode`` setting the kernel reads
DERIVATIVES = {"none": 0, "error": 1, "measurement": 2, "velocity": 3}
ANTI_WINDUPS = {"none": 0, "back-calculation": 1, "clamping": 2}
VELOCITY_ESTIMATES = ("measured", "difference")


def _finite(owner: str, **values: float) -> None:
    for name, value in values.items():
        if isinstance(value, bool) or not (isinstance(value, int | float)
                                           and math.isfinite(value)):
            raise ParameterError(f"{owner}: {name} = {value!r}; must be a finite number")


def _gains(owner: str, **gains: float) -> None:
    """Gains >= 0: the loop applies the plant's direction (a pressure that falls as the
    position rises) itself, so a negative gain is positive feedback."""
    _finite(owner, **gains)
    for name, value in gains.items():
        if value < 0:
            raise ParameterError(f"{owner}: {name} = {value!r}; must be >= 0 (the loop "
                                 "applies the plant's direction itself; a negative gain "
                                 "would be positive feedback)")


def _positive(owner: str, **values: float) -> None:
    _finite(owner, **values)
    for name, value in values.items():
        if value <= 0:
            raise ParameterError(f"{owner}: {name} = {value!r}; must be > 0")


def _choice(owner: str, name: str, value: str, allowed) -> None:
    if value not in allowed:
        raise ParameterError(f"{owner}: {name} = {value!r}; allowed: {', '.join(allowed)}")


# --------------------------------------------------------------------------- compensation
class Compensation:
    """A friction compensation term: a force estimate F̂ [N] the loop adds to the plant
    input through the plant's command-per-newton gain."""

    def settings(self) -> dict[str, float]:
        raise NotImplementedError

    #: its settings a loop reads as parameters -> its own field
    parameter_fields: ClassVar[dict[str, str]] = {}

    def with_settings(self, values: dict[str, float]) -> Compensation:
        """This term with the parameters among ``values`` (loop names) changed."""
        import dataclasses

        changes = {f: float(values[n]) for n, f in self.parameter_fields.items() if n in values}
        return dataclasses.replace(self, **changes) if changes else self  # type: ignore[type-var]


@dataclass(frozen=True)
class StaticCompensation(Compensation):
    """Feed-forward of the steady friction at the *reference* velocity ṙ:
    F̂ = tanh(ṙ/v_smooth)·(Fc + (Fs − Fc)·exp(−|ṙ/vs|^δ)). ``Fs = Fc`` (the default) is
    Coulomb compensation; ``v_smooth`` rounds the sign so the command stays continuous."""

    Fc: float
    Fs: float | None = None
    vs: float = 1e-3
    parameter_fields: ClassVar[dict[str, str]] = {"ff_fc": "Fc", "ff_fs": "Fs"}
    delta: float = 2.0
    v_smooth: float = 1e-4

    def __post_init__(self):
        _finite("StaticCompensation", Fc=self.Fc)
        if self.Fc < 0 or (self.Fs is not None and not self.Fs >= self.Fc):
            raise ParameterError(f"StaticCompensation: Fc = {self.Fc!r}, Fs = {self.Fs!r}; "
                                 "need 0 <= Fc <= Fs (friction opposes the motion)")
        _positive("StaticCompensation", vs=self.vs, delta=self.delta, v_smooth=self.v_smooth)

    def settings(self) -> dict[str, float]:
        fs = self.Fc if self.Fs is None else self.Fs
        return {"ff_fc": self.Fc, "ff_fs": fs, "ff_vs": self.vs, "ff_delta": self.delta,
                "ff_vsmooth": self.v_smooth}


@dataclass(frozen=True)
class Dither(Compensation):
    """A sine a·sin(2π f t) added to the controller output (its own units): keeps the
    plant slipping so it does not stick short of the set-point."""

    amplitude: float
    frequency: float
    parameter_fields: ClassVar[dict[str, str]] = {"dither_amplitude": "amplitude",
                                                  "dither_frequency": "frequency"}

    def __post_init__(self):
        _finite("Dither", amplitude=self.amplitude)
        _positive("Dither", frequency=self.frequency)

    def settings(self) -> dict[str, float]:
        return {"dither_amplitude": self.amplitude, "dither_frequency": self.frequency}


@dataclass(frozen=True)
class LuGreObserver(Compensation):
    """Observer-based LuGre compensation (Canudas de Wit et al. 1995, §5):

        dẑ/dt = v − σ0·|v|/g(v)·ẑ + k·e,   F̂ = σ0·ẑ + σ1·dẑ/dt + σ2·v,

    with g(v) = Fc + (Fs − Fc)·exp(−(v/vs)²) and e = r − x (the paper's −k·(x − x_d)).
    The parameters are the *model's* (they need not equal the plant's)."""

    sigma0: float
    sigma1: float
    sigma2: float
    Fc: float
    Fs: float
    vs: float
    gain: float = 0.0
    parameter_fields: ClassVar[dict[str, str]] = {"obs_gain": "gain"}

    def __post_init__(self):
        _positive("LuGreObserver", sigma0=self.sigma0, Fc=self.Fc, Fs=self.Fs, vs=self.vs)
        _finite("LuGreObserver", sigma1=self.sigma1, sigma2=self.sigma2, gain=self.gain)

    @classmethod
    def from_parameters(cls, params, gain: float = 0.0) -> LuGreObserver:
        """The observer with the LuGre parameters of a parameter set."""
        values = {n: float(params[n]) for n in ("sigma0", "sigma1", "sigma2", "Fc", "Fs",
                                                 "vs")}
        return cls(**values, gain=gain)

    def settings(self) -> dict[str, float]:
        return {"obs_sigma0": self.sigma0, "obs_sigma1": self.sigma1,
                "obs_sigma2": self.sigma2, "obs_fc": self.Fc, "obs_fs": self.Fs,
                "obs_vs": self.vs, "obs_gain": self.gain}


# --------------------------------------------------------------------------- controllers
@dataclass(frozen=True, kw_only=True)
class Controller:
    """What every controller has: output limits, anti-windup, sampling, feed-forward.

    ``u_min``/``u_max``: limits of the output (the plant input's units, before the
    loop's drive gain). ``anti_windup``: ``"back-calculation"`` (the integrator is
    pulled back by (u_sat − u)/T_t, T_t = ``tracking_time``, default √(Ti·Td) or Ti),
    ``"clamping"`` (it stops while saturated and pushing further) or ``"none"``.
    ``sample_time``: a digital controller sampled every T_s with zero-order hold
    (samples at t = k·T_s), else continuous. ``velocity_estimate``: the sampled
    controller's velocity, ``"measured"`` or ``"difference"`` ((x_k − x_{k−1})/T_s).
    ``velocity_feedforward``: gain on the set-point's slope ṙ. ``compensation``: friction
    compensation terms (``StaticCompensation``, ``Dither``, ``LuGreObserver``).
    """

    u_min: float = -math.inf
    u_max: float = math.inf
    anti_windup: str = "back-calculation"
    tracking_time: float | None = None
    sample_time: float | None = None
    velocity_estimate: str = "measured"
    velocity_feedforward: float = 0.0
    compensation: tuple[Compensation, ...] = field(default=())

    cascade: ClassVar[bool] = False

    def __post_init__(self):
        name = type(self).__name__
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("u_min", "u_max"):
                if not isinstance(value, int | float) or math.isnan(value):
                    raise ParameterError(f"{name}: {f.name} = {value!r}; must be a number")
            elif isinstance(value, float | int) and not isinstance(value, bool):
                _finite(name, **{f.name: value})
        if not self.u_min < self.u_max:
            raise ParameterError(f"{name}: u_min = {self.u_min} must be < u_max = {self.u_max}")
        _choice(name, "anti_windup", self.anti_windup, ANTI_WINDUPS)
        _choice(name, "velocity_estimate", self.velocity_estimate, VELOCITY_ESTIMATES)
        if self.sample_time is not None:
            _positive(name, sample_time=self.sample_time)
        elif self.velocity_estimate != "measured":
            raise ParameterError(f"{name}: velocity_estimate = {self.velocity_estimate!r} "
                                 "needs a sample_time (a continuous controller measures v)")
        if self.tracking_time is not None:
            _positive(name, tracking_time=self.tracking_time)
        if not isinstance(self.compensation, tuple) or not all(
                isinstance(c, Compensation) for c in self.compensation):
            raise ParameterError(f"{name}: compensation = {self.compensation!r}; give a tuple "
                                 "of StaticCompensation, Dither, LuGreObserver")
        kinds = [type(c) for c in self.compensation]
        if len(set(kinds)) != len(kinds):
            raise ParameterError(f"{name}: compensation lists {[k.__name__ for k in kinds]};"
                                 " each kind at most once")

    # -- what the loop compiles --------------------------------------------------------
    @property
    def sampled(self) -> bool:
        return self.sample_time is not None

    def has(self, kind: type) -> bool:
        return any(isinstance(c, kind) for c in self.compensation)

    def settings(self) -> dict[str, float]:
        """Every entry of CONTROL_BLOCK this controller fixes (the loop adds the rest)."""
        values = dict.fromkeys(CONTROL_BLOCK.names, 0.0)
        values.update(u_min=self.u_min, u_max=self.u_max, velocity_ff=self.velocity_feedforward,
                      sample_time=self.sample_time or 0.0, ff_delta=2.0, ff_vs=1.0,
                      ff_vsmooth=1.0, obs_sigma0=1.0, obs_fc=1.0, obs_fs=1.0, obs_vs=1.0)
        for term in self.compensation:
            values.update(term.settings())
        values.update(self.gain_settings())
        values.update(derivative_mode=float(DERIVATIVES[getattr(self, "derivative", "none")]),
                      anti_windup_mode=float(ANTI_WINDUPS[self.anti_windup]),
                      cascade_mode=float(self.cascade))
        return values

    def gain_settings(self) -> dict[str, float]:
        raise NotImplementedError

    def switches(self) -> dict[str, object]:
        """Compile-time switches of the loop kernel: only what changes its states
        (gains, derivative kind, anti-windup, cascade, static compensation and dither
        are settings: changing them never recompiles)."""
        return {"SAMPLED": self.sampled, "FILTERED_DERIVATIVE": self.filtered_derivative,
                "DIFFERENCE_VELOCITY": self.velocity_estimate == "difference",
                "OBSERVER": self.has(LuGreObserver)}

    #: the block's entry names this controller calls otherwise (a cascade's inner gain)
    renamed: ClassVar[dict[str, str]] = {}

    def read_parameters(self) -> tuple[str, ...]:
        """The block entries (CONTROL_BLOCK names) this controller reads as parameters."""
        names = list(self.gain_names())
        if self.anti_windup == "back-calculation":
            names.append("tracking_time")
        names.append("velocity_ff")
        for term in self.compensation:
            names.extend(n for n in term.settings() if n in TUNABLE)
        return tuple(names)

    def gain_names(self) -> tuple[str, ...]:
        raise NotImplementedError

    def block(self) -> Block:
        """CONTROL_BLOCK with the entries this controller reads as parameters (by their
        public names), the others settings: the local indices stay those of the kernel."""
        read = {*self.read_parameters(), "bias"}  # the loop's, a parameter of each sample
        return Block(tuple((self.renamed.get(n, n), PARAMETER if n in read else SETTING)
                           for n in CONTROL_BLOCK.names))

    def parameters(self) -> dict[str, float]:
        """The controller's parameters by name (``kp``, ``ki``, ``tracking_time``,
        ``ff_fc`` ...), SI: what a batch, a study or a tuner varies."""
        values = self.settings()
        return {self.renamed.get(n, n): float(values[n]) for n in self.read_parameters()}

    def parameter_units(self, command_unit: str = "1", position_unit: str = "m"
                        ) -> dict[str, str]:
        """The unit of each parameter when the controller output is in ``command_unit``."""
        c = f"({command_unit})" if "/" in command_unit else command_unit

        def per(unit: str) -> str:  # "1/m" -> "Pa/m", "s/m" -> "Pa*s/m"
            if command_unit == "1":
                return unit
            return f"{c}{unit[1:]}" if unit.startswith("1/") else f"{c}*{unit}"

        x = position_unit
        units = {"kp": per(f"1/{x}"), "ki": per(f"1/({x}*s)"), "kd": per(f"s/{x}"),
                 "kdp": per("1/Pa"),
                 "kv": per(f"s/{x}"), "kx": "1/s", "filter_time": "s", "tracking_time": "s",
                 "velocity_ff": per(f"s/{x}"), "ff_fc": "N", "ff_fs": "N",
                 "dither_amplitude": command_unit, "dither_frequency": "Hz",
                 "obs_gain": "1/s"}
        if self.cascade:
            units["ki"] = per(f"1/{x}")
        return {name: units[name] for name in self.parameters()}

    def with_parameters(self, **values: float) -> Controller:
        """This controller with some of its parameters changed (names as in
        ``parameters()``): a tuned controller, a batch row made an object."""
        import dataclasses

        own = self.parameters()
        unknown = [n for n in values if n not in own]
        if unknown:
            raise ParameterError(f"{type(self).__name__}: {', '.join(unknown)} not among its "
                                 f"parameters ({', '.join(own)})")
        fields_of = {"velocity_ff": "velocity_feedforward"}
        changes: dict[str, Any] = {fields_of.get(n, n): float(v) for n, v in values.items()
                                   if n in self.field_parameters()}
        changes["compensation"] = tuple(term.with_settings(values) for term in self.compensation)
        return dataclasses.replace(self, **changes)

    def field_parameters(self) -> tuple[str, ...]:
        return (*self.gain_names(), "tracking_time", "velocity_ff")

    @property
    def filtered_derivative(self) -> bool:
        return DERIVATIVES[getattr(self, "derivative", "none")] in (1, 2)

    def states(self, position_unit: str = "m", command_unit: str = "1"
               ) -> tuple[StateSpec, ...]:
        """The controller's states: its integrator, derivative filter, observer, and,
        sampled, the held output and the last sampled position."""
        integral_unit = "m" if self.cascade else f"{position_unit}*s"
        states = [StateSpec("control_integral", integral_unit)]
        if self.filtered_derivative:
            states.append(StateSpec("derivative_filter", position_unit))
        if self.has(LuGreObserver):
            states.append(StateSpec("friction_estimate_bristle", "m"))
        if self.sampled:
            states.append(StateSpec("held_command", command_unit))
            if self.velocity_estimate == "difference":
                states.append(StateSpec("last_position", position_unit))
        return tuple(states)

    def part(self, loop_settings: dict[str, float], command_unit: str = "1") -> Part:
        values = self.settings()
        values.update(loop_settings)
        values = {self.renamed.get(n, n): v for n, v in values.items()}
        block = self.block()
        return Part(role="controller", block=block,
                    states=self.states(command_unit=command_unit),
                    settings=values, label=repr(self), key="",
                    values={n: values[n] for n in block.parameters},
                    units={**self.parameter_units(command_unit), "bias": command_unit})

    def _tracking(self, ti: float, td: float) -> float:
        if self.tracking_time is not None:
            return self.tracking_time
        if ti <= 0.0:
            return 1.0
        return math.sqrt(ti * td) if td > 0.0 else ti


@dataclass(frozen=True, kw_only=True)
class PID(Controller):
    """u = bias + Kp·e + Ki·∫e dt + D, e = r − x, limited to [u_min, u_max].

    ``derivative``: ``"measurement"`` (D = −Kd·s/(Tf·s + 1)·x, no kick on set-point
    steps; the default), ``"error"`` (the same filter on e), ``"velocity"`` (D = −Kd·v,
    the measured velocity, as in Canudas de Wit et al. 1995) or ``"none"``.
    ``filter_time`` Tf [s] is the derivative filter's time constant.

    ``kdp``: pressure-difference feedback, −kdp·Δp with Δp the pressure force of a
    cylinder's piston per cap area, (p_a − p_atm) − (p_b − p_atm)·A_b/A_a. With
    ``derivative="velocity"`` this is the classic servo-pneumatic state feedback
    u = kp·(r − x) − kd·v − kdp·Δp (+ ki·∫e dt); only a plant with two chambers (a
    ``Cylinder``) has a Δp to feed back.
    """

    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0
    kdp: float = 0.0
    derivative: str = "measurement"
    filter_time: float = 1e-3

    def __post_init__(self):
        super().__post_init__()
        _gains("PID", kp=self.kp, ki=self.ki, kd=self.kd, kdp=self.kdp)
        _choice("PID", "derivative", self.derivative, DERIVATIVES)
        _positive("PID", filter_time=self.filter_time)
        if self.kd == 0.0 and self.derivative != "none":
            object.__setattr__(self, "derivative", "none")

    def gain_names(self) -> tuple[str, ...]:
        pressure = ("kdp",) if self.kdp else ()
        if self.derivative == "none":
            return ("kp", "ki", *pressure)
        if self.filtered_derivative:
            return ("kp", "ki", "kd", *pressure, "filter_time")
        return ("kp", "ki", "kd", *pressure)

    def gain_settings(self) -> dict[str, float]:
        ti = self.kp / self.ki if self.ki and self.kp else 0.0
        td = self.kd / self.kp if self.kp else 0.0
        return {"kp": self.kp, "ki": self.ki, "kd": self.kd, "kdp": self.kdp,
                "filter_time": self.filter_time, "tracking_time": self._tracking(ti, td)}


@dataclass(frozen=True, kw_only=True)
class Cascade(Controller):
    """Servo-drive cascade: an outer P loop on position gives the velocity reference
    v_ref = Kx·e + velocity_feedforward·ṙ, an inner PI loop on velocity gives
    u = bias + Kv·(v_ref − v) + Ki·∫(v_ref − v) dt."""

    kx: float
    kv: float
    ki: float = 0.0
    cascade: ClassVar[bool] = True
    renamed: ClassVar[dict[str, str]] = {"kp": "kv"}

    def __post_init__(self):
        super().__post_init__()
        _gains("Cascade", kx=self.kx, kv=self.kv, ki=self.ki)

    def gain_names(self) -> tuple[str, ...]:
        return ("kx", "kp", "ki")

    def field_parameters(self) -> tuple[str, ...]:
        return ("kx", "kv", "ki", "tracking_time", "velocity_ff")

    def gain_settings(self) -> dict[str, float]:
        ti = self.kv / self.ki if self.ki and self.kv else 0.0
        return {"kx": self.kx, "kp": self.kv, "ki": self.ki, "filter_time": 1.0,
                "tracking_time": self._tracking(ti, 0.0)}
