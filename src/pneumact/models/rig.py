"""Friction test rig: a mass with friction, driven for the classic friction experiments.

A drive is a compiled function ``drive(t, ts, x, v, p, o, sig, ptr)`` returning
``(kinematic, v, a, F, ∂F/∂x, ∂F/∂v, drive_value)``: a kinematic drive prescribes the
velocity (and acceleration) of the mass, a force drive applies a force to it. The rig's
parameter block (the mass, and the spring stiffness of the spring drive) starts at
offset ``o`` of the vector ``p``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar

from ..core.channels import CH_DRIVE, DeclaredInputs, InputChannel, in_order
from ..core.component import Block, Part, StateSpec, required_parameters
from ..core.jit import njit
from ..core.signals import channel_eval
from ..parameters.catalogue import ParameterSpec, declare
from .friction import FrictionModel, LuGre

if TYPE_CHECKING:
    from collections.abc import Mapping

    from ..core.signals import Signal
    from ..parameters.files import ParameterSetLike
    from ..parameters.parameter_set import ParameterSet

P = ParameterSpec
declare(
    P("m", "kg", "moving mass (diaphragm, rod, linkage)", None, 1e-9, False, 1e5,
      group="mechanics", plausible=(1e-3, 1e3)),
    P("k_drive", "N/m", "stiffness of the spring that pulls the rig mass (stick-slip)", 2.0,
      0.0, True, 1e10, group="rig", plausible=(1e-3, 1e8)),
    P("v_drive", "m/s", "pulling speed of the stick-slip rig", 0.1, -100.0, False, 100.0,
      group="rig", plausible=(-10.0, 10.0)),
)

#: the drive, a setting of the rig block: the force and kinematic drives share one kernel
#: (changing the drive never recompiles); the spring drive has a parameter of its own
DRIVE_KIND = {"force": 0.0, "velocity": 1.0, "position": 2.0, "spring": 3.0}
RIG_BLOCK = Block.of("m", settings=("drive_kind",))
SPRING_RIG_BLOCK = RIG_BLOCK + Block.of("k_drive")
RG_M = RIG_BLOCK.index("m")
RG_KIND = RIG_BLOCK.index("drive_kind")
RG_KDRIVE = SPRING_RIG_BLOCK.index("k_drive")
RIG_SIZE = len(RIG_BLOCK)
SPRING_RIG_SIZE = len(SPRING_RIG_BLOCK)


@njit(cache=True, inline="always")
def spring_drive(t, ts, x, v, p, o, sig, ptr):  # pragma: no cover - compiled
    """A spring k_drive whose free end follows x_d(t) [m] pulls the mass (stick-slip)."""
    xd = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    kd = p[o + RG_KDRIVE]
    return False, 0.0, 0.0, kd * (xd - x), -kd, 0.0, xd


@njit(cache=True)
def _drive_slope(sig, ptr, s, s_seg):  # pragma: no cover - compiled
    """The drive channel's slope at ``s`` (not inlined: read only by the position drive)."""
    return channel_eval(sig, ptr, CH_DRIVE, s, s_seg)[1]


@njit(cache=True, inline="always")
def prescribed_drive(t, ts, x, v, p, o, sig, ptr):  # pragma: no cover - compiled
    """The drive the block's ``drive_kind`` says, from one read of its channel: a force
    F(t) [N] on the mass, or its prescribed velocity v(t) [m/s] (the slope: its
    acceleration), or its prescribed position x(t) [m] (the slope: its velocity; the
    acceleration by a forward difference of the slope). The channel is read once, as
    each read inlined here made every rig kernel compile 0.4 s longer."""
    kind = p[o + RG_KIND]
    value, slope = channel_eval(sig, ptr, CH_DRIVE, t, ts)
    if kind == 1.0:
        return True, value, slope, 0.0, 0.0, 0.0, value
    if kind == 2.0:
        dt = 1e-7 * max(1.0, abs(t))
        later = _drive_slope(sig, ptr, t + dt, ts)
        return True, slope, (later - slope) / dt, 0.0, 0.0, 0.0, value
    return False, 0.0, 0.0, value, 0.0, 0.0, value


@njit(cache=True)
def no_drive_params(t, ts, x, v, p, o, sig, ptr, g, row):  # pragma: no cover - compiled
    """g[row, o + k] = ∂F_drive/∂p_k: zero for drives without parameters of their own."""
    for k in range(RIG_SIZE):
        g[row, o + k] = 0.0


@njit(cache=True)
def spring_drive_params(t, ts, x, v, p, o, sig, ptr, g, row):  # pragma: no cover
    for k in range(SPRING_RIG_SIZE):
        g[row, o + k] = 0.0
    g[row, o + RG_KDRIVE] = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0] - x


@njit(cache=True)
def drive_start(t, ts, p, o, sig, ptr):  # pragma: no cover - compiled
    """(x0, v0): at rest at the origin under a force or a spring, else the prescribed
    motion's initial velocity (velocity drive) or position and velocity (position)."""
    kind = p[o + RG_KIND]
    if kind == 1.0:
        return 0.0, channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    if kind == 2.0:
        return channel_eval(sig, ptr, CH_DRIVE, t, ts)
    return 0.0, 0.0


#: the rig's drives, each the input it declares (any value: unbounded)
DRIVE_INPUTS = {channel.name: channel for channel in (
    InputChannel("force", "N", record_signals=("force",),
                 description="force applied to the mass", label="force drive"),
    InputChannel("spring", "m", record_signals=("spring",),
                 description="position of the pulling spring's free end",
                 label="spring drive"),
    InputChannel("velocity", "m/s", record_signals=("velocity",),
                 description="prescribed velocity of the mass", label="velocity drive"),
    InputChannel("position", "m", record_signals=("position",),
                 description="prescribed position of the mass", label="position drive"),
)}
#: drive name -> (unit of the drive signal, meaning)
DRIVES = {name: (c.unit, c.description) for name, c in DRIVE_INPUTS.items()}


@dataclass(frozen=True, eq=False)
class FrictionRig(DeclaredInputs):
    """A mass ``m`` with a friction law, driven by ``drive`` (force, spring, velocity or
    position) — the set-up of Canudas de Wit et al. (1995) for the classic experiments."""

    params: ParameterSet
    friction: FrictionModel = field(default_factory=LuGre)
    drive: str = "force"
    template: ClassVar[str] = "pneumact.models.rig_template"

    if TYPE_CHECKING:  # the constructor takes a set's name or path too (loaded in it)
        def __init__(self, params: ParameterSetLike, friction: FrictionModel = ...,
                     drive: str = ...) -> None: ...

    def __post_init__(self):
        from ..checks import as_instance
        from ..errors import ExperimentError
        from ..parameters.files import as_parameter_set

        object.__setattr__(self, "params", as_parameter_set(self.params, "FrictionRig"))
        object.__setattr__(self, "friction", as_instance(
            "friction", self.friction, FrictionModel, where="FrictionRig",
            examples="pa.LuGre(), pa.Dahl(), pa.BoucWen(), pa.CoulombViscous() or "
                     "pa.StribeckMap()"))
        if not isinstance(self.drive, str) or self.drive not in DRIVES:
            raise ExperimentError(
                f"FrictionRig: drive = {self.drive!r}; allowed: {', '.join(DRIVES)}")
        self.params.require(self.required, "FrictionRig")

    @property
    def sensitivity_refusal(self) -> str | None:
        """Why forward sensitivities are refused: the friction law's reason, if any."""
        return self.friction.sensitivity_refusal

    # -- the model protocol (``simulation.Model``) -----------------------------------------
    def inputs(self) -> tuple[InputChannel, ...]:
        """Its drive (force, spring, velocity or position), any value: the record signal
        of the same name drives it."""
        return (DRIVE_INPUTS[self.drive],)

    @property
    def input_signals(self) -> tuple[str, ...]:
        return (self.drive,)

    def driven_by(self, signal: str) -> FrictionRig:
        """This rig, when ``signal`` is its drive (a rig has one drive)."""
        from ..errors import DataError

        if signal != self.drive:
            raise DataError(f"a FrictionRig(drive={self.drive!r}) is driven by a record's "
                            f"{self.drive}, not its {signal}")
        return self

    @property
    def plant_kind(self) -> str:
        """What its input acts on: the drive (force, spring, velocity, position)."""
        return self.drive

    #: what ``Result.summary()`` computes of its runs: the mass's motion
    summary_kind: ClassVar[str] = "motion"

    #: no chambers: nothing for a pressure feedback to read
    pressure_feedback: ClassVar[bool] = False

    def kernel_constants(self) -> dict[str, object]:
        """A rig has no compile-time switches."""
        return {}

    @property
    def stroke(self) -> float | None:
        """A rig's mass has no end stops."""
        return None

    def breakpoints(self, bp, channels, t_start: float, t_end: float):
        """The experiment's breakpoints: a rig adds none."""
        return bp

    @property
    def required(self) -> tuple[str, ...]:
        return required_parameters(self.parts())

    def parts(self) -> tuple[Part, ...]:
        module = __name__
        spring = self.drive == "spring"
        params = "spring_drive_params" if spring else "no_drive_params"
        rig = Part(role="rig", block=SPRING_RIG_BLOCK if spring else RIG_BLOCK,
                   states=(StateSpec("position", "m"), StateSpec("velocity", "m/s")),
                   functions={"drive_eval": f"{module}:"
                                            f"{'spring' if spring else 'prescribed'}_drive",
                              "drive_params": f"{module}:{params}",
                              "drive_start": f"{module}:drive_start"},
                   settings={"drive_kind": DRIVE_KIND[self.drive]},
                   label=f"{self.drive} drive", key="spring" if spring else "driven")
        return rig, self.friction.part()

    def channels(self, drive_signal: Signal, drives: Mapping[str, Signal] | None = None
                 ) -> list[Signal | None]:
        """Its drive on its channel (and any other input ``drives`` names: it declares
        none)."""
        return in_order(self.routed(drive_signal, drives))

    def describe(self) -> str:
        return f"FrictionRig(friction={self.friction!r}, drive={self.drive!r})"
