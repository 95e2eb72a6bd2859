"""What a model tells the FMU exporter (issue 41, items 5 and 6): its inputs with their
ranges and nominal values, the data of its end-stop check and its recommended step.

A model that exports has ``fmu_form()`` (itself as the FMU runs it, or an
``ArgumentError`` saying why it does not export) and ``fmu_interface()`` (an
``FmuInterface``); the exporter asks these and nothing else of the model's kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from collections.abc import Mapping

    from ..core.channels import InputChannel
    from ..core.signals import Signal
    from ..parameters.parameter_set import ParameterSet

#: the FMU input of the external force (every exported model has it)
FORCE_INPUT = ("external_force", "N", "external force on the rod (opposes motion towards "
                                      "larger x)")


#: the channels the drive and the external force ride on (``core.channels``)
DRIVE_CHANNEL = "drive"
LOAD_CHANNEL = "load_t"


@dataclass(frozen=True)
class FmuInput:
    """One FMU input: a one-point input channel of the packed signals (``channel``, its
    name: the assembly says where it sits), with its unit, start value, hard range (None:
    unbounded) and nominal magnitude. ``pressure``: an absolute pressure (a start value is
    checked as one). ``declared``: the model's declared input that fills the channel
    (driven by name with the start value when the FMU is packed; '' for the drive and
    the external force, whose channels the model fills itself)."""

    name: str
    unit: str
    description: str
    channel: str
    start: float
    nominal: float
    minimum: float | None = None
    maximum: float | None = None
    pressure: bool = False
    declared: str = ""


@dataclass(frozen=True)
class FmuInterface:
    """The model's side of the FMU: its inputs (the drive, then the external force),
    the parameters the end-stop check reads (``templates/stop_check.c.j2``'s order: mass,
    preload, spring, stroke, k_stop, c_stop, area, p_atm; None: no check) and the
    forward-Euler step its end stops allow (the DefaultExperiment's stepSize)."""

    inputs: tuple[FmuInput, ...]
    stop_check: tuple[str, ...] | None
    recommended_step: float


def drive_input(name: str, unit: str, description: str, start: float, nominal: float,
                minimum: float | None, maximum: float | None, pressure: bool = False
                ) -> FmuInput:
    """The drive's FMU input (the drive channel)."""
    return FmuInput(name, unit, description, DRIVE_CHANNEL, start, nominal, minimum, maximum,
                    pressure)


def refuse_load_against_time(kind: str, load) -> None:
    """In an FMU the external force is an input: a model holding a load against time is
    refused, naming its ``kind``, rather than exported with the load silently dropped."""
    if load is not None:
        from ..errors import ArgumentError

        raise ArgumentError(f"export_fmu: the {kind} has a load against time; in the FMU "
                            "the external force is an input: export it without load= "
                            "and drive the input 'external_force'")


def force_input(nominal: float) -> FmuInput:
    """The external force's FMU input (the load-against-time channel), starting at 0."""
    return FmuInput(*FORCE_INPUT, channel=LOAD_CHANNEL, start=0.0, nominal=nominal)


def declared_fmu_input(name: str, declared: InputChannel, start: float, *,
                       pressure: bool = False) -> FmuInput:
    """An FMU input of a declared input beside the drive (a cylinder's supply pressure):
    on its channel, starting at ``start`` (nominal too), within its declared range."""
    return FmuInput(name, declared.unit, declared.description, declared.channel, start,
                    abs(start) or 1.0, declared.low, declared.high, pressure, declared.name)


class FmuModel(Protocol):
    """What the exporter asks of a model (an ``Actuator``, a ``Cylinder``): besides what
    the kernel generator reads (``parts``, ``channels``), its parameter set, a
    description and the two methods above."""

    @property
    def params(self) -> ParameterSet: ...

    def channels(self, drive: Signal, drives: Mapping[str, Signal] | None = None, /
                 ) -> list[Signal | None]: ...

    def describe(self) -> str: ...

    def fmu_form(self) -> FmuModel: ...

    def fmu_interface(self) -> FmuInterface: ...
