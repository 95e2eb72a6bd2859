"""Which measured signal drives which valve: a record made through the pressure regulator
logs its set-point, one made with an imposed pressure carries that pressure, one made
through the valve carries its command. Each valve declares its ``input_signal``;
validation and fitting use them to drive a model the way a record was made."""

from __future__ import annotations

from ..core.channels import InputChannel
from ..errors import DataError
from .actuator import LOAD_INPUT as ACTUATOR_LOAD_INPUT
from .cylinder import COMMAND_A_INPUT, COMMAND_B_INPUT, LOAD_INPUT, SPOOL_INPUT, SUPPLY_INPUT
from .rig import DRIVE_INPUTS
from .valves import VALVES, PressureRegulator, PressureSource, Valve

__all__ = ["DECLARED_INPUTS", "DEFAULT_INPUT", "INPUTS", "INPUT_SIGNALS", "input_signal",
           "quantity_driven_by", "valve_for_signal"]

#: every input a component of the package declares (a valve's, the 5/3 valve's spool
#: command, the rig's drives, the cylinder's and the actuator's load forces, the
#: cylinder's supply pressure, its two 3/2 valves' commands): the
#: quantities an experiment may name, with their units
DECLARED_INPUTS: tuple[InputChannel, ...] = (
    *dict.fromkeys(cls.declared for cls in VALVES.values()), *DRIVE_INPUTS.values(),
    SPOOL_INPUT, LOAD_INPUT, ACTUATOR_LOAD_INPUT, SUPPLY_INPUT, COMMAND_A_INPUT,
    COMMAND_B_INPUT)

#: The record signal that drives each valve (by its ``cli_name``), in the order a record's
#: input is chosen when it carries several: a logged set-point first (the record was made
#: through the regulator), then the measured pressure (applied as a pressure source),
#: then the valve command.
INPUT_SIGNALS: dict[str, str] = {
    cls.cli_name: cls.input_signal for cls in sorted(
        VALVES.values(), key=lambda c: (c is not PressureRegulator, c is not PressureSource))}


#: How a record's input is chosen (``validate``'s ``input``): ``auto`` (the first of
#: setpoint, pressure, command the record carries, the model's valve changed to the one
#: it drives), ``model`` (the model's own valve, whose input the record must carry), or
#: one signal name.
INPUTS = ("auto", "model", *dict.fromkeys(INPUT_SIGNALS.values()))
DEFAULT_INPUT = "auto"


def input_signal(valve: Valve) -> str:
    """The record signal that drives ``valve`` (setpoint, pressure or command)."""
    return valve.input_signal


def valve_for_signal(signal: str) -> Valve:
    """A default valve driven by a record's ``signal`` (setpoint, pressure or command)."""
    for cls in VALVES.values():
        if cls.input_signal == signal:
            return cls()
    raise DataError(f"no valve is driven by a record's {signal!r}; the input signals are "
                    f"{', '.join(dict.fromkeys(INPUT_SIGNALS.values()))}")


def quantity_driven_by(signal: str) -> str:
    """The input (an experiment's quantity) a record's ``signal`` drives: a regulator's
    ``setpoint`` drives its pressure input, any other signal the input of its name."""
    for channel in DECLARED_INPUTS:
        if signal in channel.record_signals:
            return channel.name
    known = sorted({s for c in DECLARED_INPUTS for s in c.record_signals})
    raise DataError(f"no declared input is driven by a record's {signal!r}; the record "
                    f"signals that drive one are {', '.join(known)}")
