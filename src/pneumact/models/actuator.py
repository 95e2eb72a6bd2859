"""The assembled diaphragm actuator: mechanics (paper eq. 1) + friction + chamber + valve."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, ClassVar

from ..checks import as_instance, check_type
from ..core.channels import DeclaredInputs, InputChannel, in_order
from ..core.component import Part, StateSpec, required_parameters
from ..core.signals import Constant, Signal
from ..errors import ArgumentError, ExperimentError
from ..parameters.files import as_parameter_set
from .fmu_interface import FmuInterface, drive_input, force_input, refuse_load_against_time
from .friction import FrictionModel, LuGre
from .mechanics import MECHANICS_BLOCK, explicit_step
from .pneumatics import ChamberLaw, Isothermal
from .valves import COMMAND_INPUT, PRESSURE_INPUT, SETPOINT_INPUT, PressureSource, Valve

if TYPE_CHECKING:
    from collections.abc import Mapping

    from ..parameters.files import ParameterSetLike
    from ..parameters.parameter_set import ParameterSet

#: the FMU input that takes what drives each valve (the record signal it replaces); its
#: unit and description are the valve's declared input's
FMU_DRIVES = {PRESSURE_INPUT.record_signal: "pressure_input",
              SETPOINT_INPUT.record_signal: "pressure_setpoint",
              COMMAND_INPUT.record_signal: "valve_command"}
#: the signal of its chamber pressure [Pa, absolute] in a run: its valve's state behind a
#: valve, the template's output ``pressure`` always (the template and the valves spell it
#: in their kernel sources, which keep their kernels' keys; tests hold them to this name)
CHAMBER_PRESSURE = "pressure"
#: the mechanics' parameters the FMU's end-stop check reads, in the template's order
STOP_CHECK_PARAMETERS = ("m", "F0", "k", "x_max", "k_stop", "c_stop", "A_d", "p_atm")

#: the external force on the diaphragm, against larger x (with the spring, against the
#: vacuum's pull): an input beside the valve's drive of an actuator built with
#: ``load=LOAD_INPUT`` (a load-free actuator's kernel has no load code, so it declares
#: none), on the load-against-time channel the template reads; a record's ``load`` drives
#: it (a run writes its load under that name). 1 MN bounds any force in newtons on a
#: diaphragm actuator (one atmosphere on a 1 m² diaphragm is 0.1 MN).
LOAD_INPUT = InputChannel(
    "load", "N", -1e6, 1e6, record_signals=("load",), channel="load_t",
    description="external force on the diaphragm, against larger x",
    label="load force", rule="a load force on a diaphragm actuator must stay within "
                             "[{low:g}, {high:g}] N (is it in N?)")


@dataclass(frozen=True, eq=False)
class Actuator(DeclaredInputs):
    """A spring-return vacuum diaphragm actuator.

    ``friction``, ``valve`` and ``chamber`` are strategy objects; ``load`` is an external
    force F_ext(t) [N] the actuator holds, or ``LOAD_INPUT`` to declare it as the input
    ``load`` (an experiment or a record drives it by name; zero where none does), and
    ``load_map`` a force against position F_ext(x) [N] (both oppose motion towards larger
    x; none by default: the paper's actuator, whose kernel has no load code). The chamber
    law matters only behind a valve (with a pressure source the chamber pressure is
    given).
    """

    params: ParameterSet
    friction: FrictionModel = field(default_factory=LuGre)
    valve: Valve = field(default_factory=PressureSource)
    chamber: ChamberLaw = field(default_factory=Isothermal)
    load: Signal | InputChannel | None = None
    load_map: Signal | None = None
    template: ClassVar[str] = "pneumact.models.actuator_template"

    if TYPE_CHECKING:  # the constructor takes a set's name or path too (loaded in it)
        def __init__(self, params: ParameterSetLike, friction: FrictionModel = ...,
                     valve: Valve = ..., chamber: ChamberLaw = ...,
                     load: Signal | InputChannel | None = ...,
                     load_map: Signal | None = ...) -> None: ...

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "params", as_parameter_set(self.params, "Actuator"))
        set_(self, "friction", as_instance(
            "friction", self.friction, FrictionModel, where="Actuator",
            examples="pa.LuGre(), pa.Dahl(), pa.BoucWen(), pa.CoulombViscous() or "
                     "pa.StribeckMap()"))
        set_(self, "valve", as_instance(
            "valve", self.valve, Valve, where="Actuator",
            examples="pa.PressureSource(), pa.CommandValve(), pa.PressureRegulator() or "
                     "pa.Iso6358Valve()"))
        set_(self, "chamber", as_instance(
            "chamber", self.chamber, ChamberLaw, where="Actuator",
            examples="pa.Isothermal(), pa.Adiabatic() or pa.Polytropic(exponent)"))
        if isinstance(self.load, InputChannel) and self.load != LOAD_INPUT:
            raise ArgumentError(
                f"Actuator: load = the input {self.load.describe()} "
                f"({self.load.description}): the input an actuator declares for its load "
                "is pneumact.models.actuator.LOAD_INPUT; give that, a Signal the actuator "
                "holds, or None")
        if not isinstance(self.load, InputChannel | None):
            check_type("load", self.load, Signal, where="Actuator",
                       what="a Signal (e.g. pa.experiments.Ramp(...)), "
                            "pneumact.models.actuator.LOAD_INPUT (the input 'load', driven "
                            "by name) or None")
        if self.load_map is not None:
            check_type("load_map", self.load_map, Signal, where="Actuator",
                       what="a Signal (e.g. pa.experiments.Ramp(...)) or None")
        if self.chamber.temperature_state:
            raise ArgumentError(
                f"Actuator: chamber = {type(self.chamber).__name__}(): only the cylinder's "
                "chambers carry a temperature state; the actuator's chamber takes "
                "pa.Isothermal(), pa.Adiabatic() or pa.Polytropic(exponent)")
        if isinstance(self.valve, PressureSource) and not isinstance(self.chamber, Isothermal):
            raise ArgumentError(
                f"Actuator: chamber = {type(self.chamber).__name__}() has no effect with "
                "PressureSource(): the pressure is prescribed, so the chamber's gas law "
                "never enters; drop chamber=, or drive a valve (CommandValve, "
                "PressureRegulator)")
        self.params.require(self.required, "Actuator")

    @property
    def sensitivity_refusal(self) -> str | None:
        """Why forward sensitivities are refused: the friction law's reason, if any."""
        return self.friction.sensitivity_refusal

    # -- the model protocol (``simulation.Model``) -----------------------------------------
    def inputs(self) -> tuple[InputChannel, ...]:
        """Its valve's input (a source's pressure, a regulator's set-point, a command in
        [0, 1]), with the range the parameters give it: ``drive_quantity``,
        ``input_signal``, ``input_range`` and ``check_drive_values`` read it; then its
        load force (``LOAD_INPUT``) where it is built with ``load=LOAD_INPUT``."""
        drive = self.valve.declared_input(self.params)
        return (drive, LOAD_INPUT) if self.load_is_input else (drive,)

    @property
    def load_is_input(self) -> bool:
        """Whether its load is the declared input ``load`` (``load=LOAD_INPUT``)."""
        return isinstance(self.load, InputChannel)

    @property
    def held_load(self) -> Signal | None:
        """The load against time it holds (``load=`` a Signal), None where it holds none."""
        return self.load if isinstance(self.load, Signal) else None

    def declared_input(self, name: str, who: str) -> InputChannel:
        """Its input named ``name``; its load, where it declares none, is refused saying
        how to declare it."""
        if name == LOAD_INPUT.name and not self.load_is_input:
            listed = ", ".join(c.describe() for c in self.inputs())
            if self.load is not None:
                how = f"it holds its load (load = {self.load!r}): give load=LOAD_INPUT instead"
            else:
                how = "it is built without one: give load=LOAD_INPUT"
            raise ExperimentError(
                f"{who} drives {name!r}, but this Actuator declares no load input (its "
                f"declared inputs: {listed}); {how} (pneumact.models.actuator) to drive "
                f"the input {LOAD_INPUT.describe()}")
        return super().declared_input(name, who)

    @property
    def input_signals(self) -> tuple[str, ...]:
        """The record signals it can be driven by (behind the valve each one drives), in
        the order a record's input is chosen: a logged set-point, a pressure, a command."""
        from .inputs import INPUT_SIGNALS

        return tuple(dict.fromkeys(INPUT_SIGNALS.values()))

    def driven_by(self, signal: str) -> Actuator:
        """This actuator behind the valve that a record's ``signal`` drives."""
        from .inputs import valve_for_signal

        if signal == self.input_signal:
            return self
        return replace(self, valve=valve_for_signal(signal))

    @property
    def plant_kind(self) -> str:
        """What its input acts on: ``pressure`` (a source or a regulator) or ``command``."""
        return self.valve.drive

    @property
    def drive_label(self) -> str:
        """What takes its input, for messages: its valve."""
        return self.valve.name

    #: what ``Result.summary()`` computes of its runs: the pressure-position hysteresis
    summary_kind: ClassVar[str] = "hysteresis"

    #: no chamber pair whose pressure difference a controller could feed back
    pressure_feedback: ClassVar[bool] = False

    @property
    def stroke(self) -> float | None:
        """x_max [m]: set-points and measured positions beyond it are impossible."""
        return float(self.params["x_max"])

    def breakpoints(self, bp, channels, t_start: float, t_end: float):
        """The experiment's breakpoints: an actuator adds none."""
        return bp

    @property
    def required(self) -> tuple[str, ...]:
        return required_parameters(self.parts())

    def parts(self) -> tuple[Part, ...]:
        mechanics = Part(role="mechanics", block=MECHANICS_BLOCK,
                         states=(StateSpec("position", "m"), StateSpec("velocity", "m/s")),
                         label="diaphragm mechanics")
        return mechanics, self.friction.part(), self.valve.part(self.chamber)

    @property
    def has_load(self) -> bool:
        return self.load is not None or self.load_map is not None

    def kernel_constants(self) -> dict[str, bool]:
        """Compile-time switch of the kernel: no load code without a load. With a load
        against time or against position, both are read (the absent one is zero), so
        that every loaded actuator of a combination shares one kernel."""
        return {"HAS_LOAD": self.has_load}

    def channels(self, drive: Signal, drives: Mapping[str, Signal] | None = None
                 ) -> list[Signal | None]:
        """Its valve's drive and the inputs ``drives`` names (its load, where declared) on
        their channels, the loads it holds (zero where it has load code and none is held
        or driven) and its valve's area maps."""
        res_map, atm_map = self.valve.maps()
        zero = Constant(0.0) if self.has_load else None
        held = self.held_load
        return in_order({"load_t": held if held is not None else zero,
                         "load_x": self.load_map if self.load_map is not None else zero,
                         "map_res": res_map, "map_atm": atm_map,
                         **self.routed(drive, drives)})

    # -- the FMU exporter's protocol (``models.fmu_interface``) ---------------------------
    def fmu_form(self) -> Actuator:
        """This actuator as its FMU runs it: the external force an input channel (a load
        against time it holds is refused: in the FMU it is the input)."""
        refuse_load_against_time("actuator", self.held_load)
        return replace(self, load=Constant(0.0))

    def fmu_interface(self) -> FmuInterface:
        """The drive behind its valve (an absolute pressure in [0, 10 MPa] starting at the
        atmosphere, or a command in [0, 1] starting closed), the external force (nominal:
        one atmosphere on the diaphragm), the diaphragm's end-stop check and the Euler step
        its stops allow."""
        from ..checks import MAX_ABSOLUTE_PRESSURE

        p = self.params
        p_atm = float(p["p_atm"])
        declared = self.drive_input
        name, unit, description = (FMU_DRIVES[declared.record_signal], declared.unit,
                                   declared.description)
        if unit == "Pa":
            drive = drive_input(name, unit, description, p_atm, p_atm, 0.0,
                                MAX_ABSOLUTE_PRESSURE, pressure=True)
        else:
            drive = drive_input(name, unit, description, 0.0, 1.0, declared.low,
                                declared.high)
        step = explicit_step(float(p["m"]), float(p["k"]), float(p["F0"]),
                             float(p["k_stop"]), float(p["c_stop"]))
        return FmuInterface((drive, force_input(p_atm * float(p["A_d"]))),
                            STOP_CHECK_PARAMETERS, step)

    def describe(self) -> str:
        return (f"Actuator(friction={self.friction!r}, valve={self.valve.name}, "
                f"chamber={type(self.chamber).__name__})")
