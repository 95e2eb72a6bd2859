"""The closed loop as a model: a plant under a controller, one compiled kernel.

``ClosedLoop(plant, controller)`` is simulated like any model:
``simulate(loop, step_setpoint(...))``. Its experiment is the position set-point; its
states are the plant's then the controller's; its outputs are the plant's then
``position_setpoint``, ``error``, ``command`` (the controller output), ``plant_input`` (what the
plant receives: drive_gain·command + disturbance) and ``friction_compensation`` (F̂).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from ..core.channels import LOOP_OWN, DeclaredInputs, InputChannel, in_order
from ..core.codegen import Child
from ..core.component import Part
from ..core.signals import Constant, Signal
from ..errors import ExperimentError, ParameterError
from ..models.actuator import Actuator
from ..models.controllers import Controller, LuGreObserver, StaticCompensation
from ..models.cylinder import Cylinder
from ..models.rig import FrictionRig
from ..models.valves import PRESSURE_INPUT
from .plants import held_inputs, input_kind, input_range

__all__ = ["ClosedLoop"]

LOOP_TEMPLATE = "pneumact.models.loop_template"
#: breakpoints closer than this fraction of a period to a sample are that sample
SNAP = 1e-6


#: the most controller samples one run may take: each is a breakpoint of the integrator
#: (8 bytes, and 4-8 µs of compiled work measured: 2e6 samples ≈ 10 s), which runs
#: between Ctrl-C checks; more is a sample time typed in the wrong unit
MAX_CONTROLLER_SAMPLES = 2_000_000

#: the position set-point a loop declares as its input (its range: the plant's stroke)
SETPOINT_INPUT = InputChannel(
    "position", "m", record_signals=("position_setpoint",),
    description="position set-point of the controller", label="set-point",
    rule="the actuator's stroke is {low:g} to x_max = {high:g} mm (positions in m: 4 mm is "
         "0.004)", shown_in=("mm", 1e3))


def _check_samples(period: float, t_start: float, t_end: float) -> None:
    """Refuse a sample time the run cannot use: longer than the run (the controller would
    never act after the start), or so short that the run takes more than
    ``MAX_CONTROLLER_SAMPLES`` samples."""
    duration = t_end - t_start
    if period >= duration:
        raise ExperimentError(
            f"sample_time = {period:g} s is not shorter than the run ({duration:g} s): the "
            "controller would act only at the start; give a sample time well below the "
            "run's length (a digital controller samples every 0.1-10 ms)")
    samples = duration / period
    if samples > MAX_CONTROLLER_SAMPLES:
        raise ExperimentError(
            f"sample_time = {period:g} s takes {samples:.3g} controller samples over the "
            f"{duration:g} s run (about {8 * samples / 1e9:.3g} GB of sample times and "
            f"{samples * 5e-6 / 60:.3g} min of computing); at most "
            f"{MAX_CONTROLLER_SAMPLES:,}: give a longer sample time (in seconds) or leave it "
            "out for a continuous controller")


@dataclass(frozen=True, eq=False)
class ClosedLoop(DeclaredInputs):
    """``plant`` (an ``Actuator`` behind any valve, a ``Cylinder`` through its spool
    command, or a ``FrictionRig`` with a force drive) under ``controller`` (``PID`` or
    ``Cascade``), as one model. Behind a cylinder, ``PID(..., derivative="velocity",
    kdp=...)`` is the servo-pneumatic state feedback on position, velocity and the
    chambers' pressure difference; give it ``u_min=-1, u_max=1``, the spool's travel.

    ``bias``: the plant input (controller units) the controller's terms add to, and the
    input the plant rests under at the start (``holding_input`` finds the one that holds
    a position). ``drive_gain``: plant input per controller unit (the EMPS drive's
    N/V). ``feedforward``: a signal added to the controller output. ``disturbance``: a
    force [N] added to a rig's drive force. ``compensation_gain``: controller units per
    newton of friction compensation (default: 1/drive_gain for a rig, −1/(A_d·drive_gain)
    for a pressure-driven actuator; a command valve has no static one, give it).
    """

    plant: Actuator | Cylinder | FrictionRig
    controller: Controller
    bias: float = 0.0
    drive_gain: float = 1.0
    feedforward: Signal | None = None
    disturbance: Signal | None = None
    compensation_gain: float | None = None
    template: ClassVar[str] = LOOP_TEMPLATE
    #: its own channels, after its plant's (``core.channels``)
    own_channels: ClassVar[tuple[str, ...]] = LOOP_OWN

    def __post_init__(self):
        kind = input_kind(self.plant, "ClosedLoop")
        if not isinstance(self.controller, Controller):
            raise ParameterError(f"ClosedLoop: controller = {self.controller!r}; give a PID "
                                 "or a Cascade")
        for name in ("bias", "drive_gain"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise ParameterError(f"ClosedLoop: {name} = {value!r}; must be a finite number")
        if self.drive_gain == 0.0:
            raise ParameterError("ClosedLoop: drive_gain = 0; the controller would not act")
        hybrid = [part.label for part in self.plant.parts() if "HAS_EVENTS" in part.constants]
        if hybrid:
            raise ParameterError(
                f"ClosedLoop: the plant's {', '.join(hybrid)} switches modes at state events, "
                "which a closed loop's kernel does not locate yet (its stick/slip memory "
                "would be lost); close the loop around a plant with another friction law")
        if self.disturbance is not None and kind != "force":
            raise ParameterError("ClosedLoop: disturbance is a force on a rig's mass; an "
                                 "actuator or a cylinder takes its loads as "
                                 "Actuator(load=...) or Cylinder(load=...)")
        kdp = self.controller.settings()["kdp"]
        if kdp != 0.0 and not self.plant.pressure_feedback:
            raise ParameterError(
                f"ClosedLoop: kdp = {kdp!r} feeds back a pressure difference, which "
                f"{self.plant.describe()} does not have; allowed: kdp = 0, or a plant with "
                "two chambers (a Cylinder)")
        needs_gain = self.controller.has(StaticCompensation) or self.controller.has(
            LuGreObserver)
        if needs_gain and self._compensation_gain() is None:
            raise ParameterError(
                "ClosedLoop: friction compensation behind a command valve needs "
                "compensation_gain (command per newton): the valve has no static force map")

    # -- what the plant is ---------------------------------------------------------------
    @property
    def params(self):
        """The plant's parameter set (the controller's parameters: ``gains``)."""
        return self.plant.params

    @property
    def gains(self) -> dict[str, float]:
        """The controller's parameters by name (SI; units: ``gain_units``): varied by
        name like the plant's in batches, studies, fits and sensitivities."""
        return self.controller.parameters()

    @property
    def gain_units(self) -> dict[str, str]:
        return self.controller.parameter_units(self.command_unit)

    @property
    def sensitivity_refusal(self) -> str | None:
        """Sensitivities pass through the controller (its jumps too); the plant's law may
        refuse them."""
        return self.plant.sensitivity_refusal

    @property
    def plant_kind(self) -> str:
        """What the plant's input is: ``force``, ``pressure``, ``command`` or ``spool``."""
        return input_kind(self.plant, "ClosedLoop")

    @property
    def action(self) -> float:
        """+1, or −1 for a plant whose position falls as its input rises (pressure)."""
        return -1.0 if self.plant_kind == PRESSURE_INPUT.name else 1.0

    @property
    def input_unit(self) -> str:
        """The unit of the plant's declared drive."""
        return self.plant.drive_unit

    @property
    def command_unit(self) -> str:
        if self.drive_gain == 1.0:
            return self.input_unit
        return f"{self.input_unit}/{self.drive_gain:g}"

    @property
    def force_gain(self) -> float | None:
        """Controller units per newton of friction compensation (None: a command valve
        without ``compensation_gain``)."""
        return self._compensation_gain()

    def _compensation_gain(self) -> float | None:
        if self.compensation_gain is not None:
            return float(self.compensation_gain)
        kind = self.plant_kind
        if kind == "force":
            return 1.0 / self.drive_gain
        if kind == PRESSURE_INPUT.name:
            return -1.0 / (float(self.params["A_d"]) * self.drive_gain)
        return None

    # -- the model protocol (``simulation.Model``) ------------------------------------------
    def inputs(self) -> tuple[InputChannel, ...]:
        """Its position set-point, within the plant's stroke (any, for a plant without
        one): ``drive_quantity``, ``input_signal`` and ``check_drive_values`` read it."""
        stroke = self.stroke
        setpoint = SETPOINT_INPUT if stroke is None else replace(SETPOINT_INPUT, low=0.0,
                                                                 high=stroke)
        return (setpoint, *self.plant.inputs()[1:])  # the controller drives the plant's drive

    @property
    def input_signals(self) -> tuple[str, ...]:
        return SETPOINT_INPUT.record_signals

    @property
    def drive_label(self) -> str:
        return "position set-point"

    def driven_by(self, signal: str) -> ClosedLoop:
        """This loop, when ``signal`` is its position set-point."""
        if signal != self.input_signal:
            raise ExperimentError(f"a ClosedLoop is driven by a record's {self.input_signal}, "
                                  f"not its {signal}")
        return self

    @property
    def stroke(self) -> float | None:
        """Its plant's stroke: a set-point beyond it is impossible."""
        return self.plant.stroke

    @property
    def summary_kind(self) -> str:
        """Its runs summarise as its plant's do."""
        return self.plant.summary_kind

    @property
    def required(self) -> tuple[str, ...]:
        return self.plant.required

    def parts(self) -> tuple[Part, ...]:
        loop = {"action": self.action, "drive_gain": float(self.drive_gain),
                "bias": float(self.bias), "comp_gain": self._compensation_gain() or 0.0}
        return (*self.plant.parts(), self.controller.part(loop, self.command_unit))

    def _plant_outputs(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """The plant's output names and units: its own where it says them (a cylinder's
        depend on its valves), else its template's."""
        import importlib

        names = getattr(self.plant, "output_names", None)
        units = getattr(self.plant, "output_units", None)
        if names is not None and units is not None:
            return tuple(names), tuple(units)
        module = importlib.import_module(self.plant.template)
        return tuple(module.OUTPUT_NAMES), tuple(module.OUTPUT_UNITS)

    @property
    def output_names(self) -> tuple[str, ...]:
        from ..models.loop_template import LOOP_OUTPUTS

        # the rig's "drive" output is the drive signal, here the controller's force
        plant = tuple("drive_input" if n == "drive" else n for n in self._plant_outputs()[0])
        return plant + LOOP_OUTPUTS

    @property
    def output_units(self) -> tuple[str, ...]:
        plant = tuple(self.input_unit if n == "drive" else u
                      for n, u in zip(*self._plant_outputs(), strict=True))
        return (*plant, "m", "m", self.command_unit, self.input_unit, "N")

    def _plant_states(self) -> int:
        return sum(len(p.states) for p in self.plant.parts())

    @property
    def has_loop_inputs(self) -> bool:
        """A feed-forward or a disturbance signal (the kernel reads both, or neither)."""
        return self.feedforward is not None or self.disturbance is not None

    def kernel_constants(self) -> dict[str, object]:
        plant: dict[str, object] = dict(self.plant.kernel_constants())
        n_plant_out = len(self._plant_outputs()[0])
        return {**plant, **self.controller.switches(), "PLANT_NSTATE": self._plant_states(),
                "PRESSURE_FEEDBACK": self.plant.pressure_feedback,
                "PLANT_NOUT": n_plant_out, "NOUT": len(self.output_names),
                "HAS_JUMPS": self.controller.sampled, "PRIVATE_INPUTS": True,
                "HAS_LOOP_INPUTS": self.has_loop_inputs}

    def kernel_children(self) -> tuple[Child, ...]:
        """The plant's own kernel, called under ``plant_``."""
        from ..core.assembly import assemble

        return (Child("plant_", assemble(self.plant).kernel_spec()),)

    @property
    def kernel_templates(self) -> tuple[str, ...]:
        from ..core.assembly import INTEGRATORS

        return (LOOP_TEMPLATE, INTEGRATORS)

    def channels(self, setpoint: Signal, drives: Mapping[str, Signal] | None = None
                 ) -> list[Signal | None]:
        """The plant's channels (its drive held at the bias: the controller writes it; the
        plant's other inputs ``drives`` names on theirs), the set-point, the feed-forward
        and the disturbance."""
        held = Constant(self.drive_gain * self.bias)
        plant = dict(zip(self.plant.channel_names, self.plant.channels(held, drives),
                         strict=True))
        # with one of feed-forward and disturbance the other is zero: one kernel for both
        zero = Constant(0.0) if self.has_loop_inputs else None
        return in_order({**plant, "setpoint": setpoint,
                         "feedforward": self.feedforward if self.feedforward is not None
                         else zero,
                         "disturbance": self.disturbance if self.disturbance is not None
                         else zero}, self.channel_names)

    def breakpoints(self, bp: np.ndarray, channels, t_start: float, t_end: float
                    ) -> np.ndarray:
        """The experiment's breakpoints, the feed-forward's and disturbance's corners,
        and every sample time of a sampled controller (others within SNAP·T_s of a
        sample are merged into it)."""
        extra = [c.breakpoints() for c in (self.feedforward, self.disturbance) if c is not None]
        points = np.unique(np.concatenate([bp, *extra, [t_start, t_end]]))
        points = points[(points >= t_start) & (points <= t_end)]
        if self.controller.sample_time is not None:  # a sampled controller
            period = float(self.controller.sample_time)
            _check_samples(period, t_start, t_end)
            k = np.arange(math.ceil(t_start / period - SNAP), math.floor(t_end / period + SNAP)
                          + 1)
            samples = k * period
            nearest = np.round(points / period) * period
            keep = np.abs(points - nearest) > SNAP * period
            keep[[0, -1]] = True
            points = np.unique(np.concatenate([points[keep], samples]))
            points = points[(points >= t_start) & (points <= t_end)]
            if points[0] > t_start:
                points = np.concatenate([[t_start], points])
        return points

    def describe(self) -> str:
        return f"ClosedLoop({self.plant.describe()}, {type(self.controller).__name__})"

    # -- operating points ------------------------------------------------------------------
    def holding_input(self, position: float, lo: float | None = None,
                      hi: float | None = None, *, values: Mapping[str, float] | None = None,
                      inputs: Mapping[str, float] | None = None) -> float:
        """The constant controller output that holds the plant at rest at ``position``
        (friction unloaded), by bisection on the plant's static equilibrium (a cylinder's:
        the spool command at which its chambers balance, (p_a − p_atm)·A_a − (p_b −
        p_atm)·A_b = F_load, which holds any position); default bracket: the controller's
        limits within the plant's input range. ``values``: plant parameters changed for
        this answer (an uncertainty sample). ``inputs``: the plant's other declared inputs
        held at constant values (``linearise``'s), e.g. ``{"load": 500.0}`` [N] for a
        cylinder under a constant load against extension (zero where not given)."""
        from scipy.optimize import brentq

        from ..core.signals import pack_channels
        from ..experiments.actuator import Experiment
        from ..simulation.simulate import prepare
        from ..simulation.solvers import Rodas4

        plant = self.plant
        held = held_inputs(plant, inputs, "holding_input")
        if self.plant_kind == "force":
            return 0.0  # the rig has no spring: any position rests under zero force
        natural = input_range(plant)
        lo = max(self.controller.u_min * self.drive_gain, natural[0]) if lo is None else lo
        hi = min(self.controller.u_max * self.drive_gain, natural[1]) if hi is None else hi
        prep = prepare(plant, Experiment(Constant(lo), plant.drive_quantity, 1.0), Rodas4(),
                       values=values)
        y0 = np.empty_like(prep.y0)
        at = prep.assembly.state_index("position")

        def rest(value):  # at the start, t = 0: a load the plant holds at its value there
            sig, ptr = pack_channels(plant.channels(Constant(value), held))
            prep.kernel.initial_state(0.0, 0.0, prep.vector, sig, ptr, y0)
            return y0[at] - position

        f_lo, f_hi = rest(lo), rest(hi)
        if f_lo * f_hi > 0:
            reach = sorted([f_lo + position, f_hi + position])
            raise ExperimentError(
                f"holding_input: position {position:g} m is out of reach; inputs "
                f"{lo:g}..{hi:g} {self.input_unit} hold {reach[0]:g}..{reach[1]:g} m")
        return brentq(rest, lo, hi, xtol=1e-12 * max(1.0, abs(hi - lo))) / self.drive_gain
