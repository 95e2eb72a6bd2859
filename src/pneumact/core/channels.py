"""Signal channels handed to every kernel, in the order the model's layout gives them.

Every model has the fixed channels ``CHANNELS``, first and in this order, and fills the
ones it uses (the others stay empty): the experiment's drive (pressure, command,
set-point, force, velocity or position), the external loads of the actuator against time
and against position, and the valve's normalised area maps against the command u.

A model may declare more: a component lists the extra channels it reads
(``Part.channels``: the cylinder's supply pressure, ``supply``), and the model's layout is
``CHANNELS``, then its components' extras in the order of its parts, then the channels of
its own that a model adds after its components' (``own_channels``: a closed loop's
position set-point, a feed-forward signal added to the controller output and a force
disturbance on a rig's mass, ``LOOP_OWN``), each name once (``channel_layout``). A model
without extras has exactly ``CHANNELS`` (a loop around it ``LOOP_CHANNELS``), so its
kernel reads the static indices below (``CH_DRIVE`` ...) and its generated text is what
it was before models declared channels. Where a channel's index differs from the static
one, or it has none (an extra), the assembly generates ``CH_<NAME>`` into the kernel
(``layout_constants``): a template reads an extra by that constant (a template global
the generator overrides) and hands it to its component's functions, as it hands them
their block's offset; a loop's plant is a prefix of the loop's layout, so the plant's
own kernel reads the loop's channels where it reads its own. A closed loop's plant drive
channel holds one value, the controller's output, which the loop writes at
``INPUT_OFFSET`` past the channel's start.

Models name their channels (``in_order`` with the model's ``channel_names``); only the
packing (``core.signals.pack_channels``) puts them in order, and only the assembly
(``Assembly.channel_index``) says where one sits: nothing else reads a channel by its
position.

What drives a model is declared too: ``InputChannel`` says an input's name (the quantity
an experiment drives it with), unit, range, the record signals that drive it, the channel
that carries it and how a refusal reads; the component that owns the input declares it (a
valve, the 5/3 valve, the rig's drive, a loop's set-point, the cylinder's load force and
supply pressure) and the model lists them (``inputs()``, its drive first). An experiment
drives the first by its quantity and any other by name (``Experiment.drives``);
``DeclaredInputs.routed`` puts each signal on its input's channel, which must be one of
the model's layout. An input on an extra channel that no experiment drives leaves it
empty, and the component then holds what it holds without the input (the cylinder: its
parameter ``p_supply``; ``core.signals.channel_driven`` tells the two apart).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

from ..errors import ArgumentError, ExperimentError

if TYPE_CHECKING:
    from .component import Part
    from .signals import Signal

#: every model's channels, first and in this order
CHANNELS = ("drive", "load_t", "load_x", "map_res", "map_atm")
#: a closed loop's own channels, after its plant's
LOOP_OWN = ("setpoint", "feedforward", "disturbance")
#: a closed loop's around a plant without extra channels: its plant's, then its own
LOOP_CHANNELS = (*CHANNELS, *LOOP_OWN)
CH_DRIVE = LOOP_CHANNELS.index("drive")
CH_LOAD_T = LOOP_CHANNELS.index("load_t")
CH_LOAD_X = LOOP_CHANNELS.index("load_x")
CH_MAP_RES = LOOP_CHANNELS.index("map_res")
CH_MAP_ATM = LOOP_CHANNELS.index("map_atm")
CH_SETPOINT = LOOP_CHANNELS.index("setpoint")
CH_FEEDFORWARD = LOOP_CHANNELS.index("feedforward")
CH_DISTURBANCE = LOOP_CHANNELS.index("disturbance")
N_CHANNELS = len(CHANNELS)
N_LOOP_CHANNELS = len(LOOP_CHANNELS)
#: [n_terms = 1, kind = PWL, n = 1, t0, value]: where a one-point channel holds its value
INPUT_OFFSET = 4


def channel_layout(extras: Iterable[str] = (), own: Iterable[str] = ()) -> tuple[str, ...]:
    """A model's channels: ``CHANNELS``, then its components' ``extras`` in order, then
    the model's ``own`` (a loop's ``LOOP_OWN``); one ArgumentError if a name is not an
    identifier or appears twice (two components cannot share a channel)."""
    layout = (*CHANNELS, *extras, *own)
    for name in layout[len(CHANNELS):]:
        if not (isinstance(name, str) and name.isidentifier()):
            raise ArgumentError(f"channel {name!r}: a channel's name must be a name of "
                                "letters, digits and underscores (it names the kernel "
                                "constant CH_<NAME>)")
    twice = sorted({name for name in layout if layout.count(name) > 1})
    if twice:
        raise ArgumentError(f"channels {twice} are declared twice in the layout "
                            f"{list(layout)}: each channel belongs to one component")
    return layout


def parts_layout(parts: Iterable[Part], own: Iterable[str] = ()) -> tuple[str, ...]:
    """The layout of a model of ``parts`` (their ``channels``) with its ``own`` channels."""
    return channel_layout((name for part in parts for name in part.channels), own)


def channel_constant(name: str) -> str:
    """The kernel constant holding channel ``name``'s index: ``CH_<NAME>``."""
    return f"CH_{name.upper()}"


def layout_constants(layout: tuple[str, ...]) -> list[tuple[str, int]]:
    """(``CH_<NAME>``, index) for each channel of ``layout`` past ``CHANNELS``, where the
    layout is not a prefix of ``LOOP_CHANNELS`` (whose indices the static constants
    give): nothing for a model without extras, whose kernel text stays as it was."""
    if layout == LOOP_CHANNELS[:len(layout)]:
        return []
    return [(channel_constant(name), index) for index, name in enumerate(layout)
            if index >= len(CHANNELS)]


def in_order(named: Mapping[str, Any], names: tuple[str, ...] = CHANNELS) -> list[Any]:
    """The signals of ``named`` (channel name → signal or None) in the declared order of
    ``names``, for ``experiments.pack_channels``; a name left out is an empty channel."""
    unknown = sorted(set(named) - set(names))
    if unknown:
        raise ExperimentError(f"channels {unknown}: not among the declared {list(names)}")
    return [named.get(name) for name in names]


@dataclass(frozen=True)
class InputChannel:
    """One input a model declares: what an experiment drives it with and what it takes.

    ``name`` is the quantity an experiment names (``Experiment.quantity``), ``unit`` its SI
    unit; values outside [``low``, ``high``] are refused; ``acts_within`` is a narrower span
    where the component acts (beyond it the value is clipped: a regulator's set-point);
    ``record_signals`` are the record signals that drive it, its own first; ``channel`` the
    kernel channel that carries it (one of its model's layout: the drive's, a load's, or
    an extra its component declares, ``Part.channels``). A refusal
    says ``"{where}: its {label} spans a to b; {rule}"`` with the values (and ``{low}``,
    ``{high}`` in ``rule``) shown in ``shown_in`` (unit, factor), or, where the owner
    gives ``check_value`` (a pressure's check, whose hint names a unit mistake), that
    check's message.
    """

    name: str
    unit: str
    low: float = -math.inf
    high: float = math.inf
    record_signals: tuple[str, ...] = ()
    description: str = ""
    label: str = ""
    rule: str = ""
    shown_in: tuple[str, float] = ("", 1.0)
    acts_within: tuple[float, float] | None = None
    check_value: Callable[..., object] | None = field(default=None, compare=False)
    channel: str = "drive"

    def __post_init__(self) -> None:
        if not self.name or not self.record_signals:
            raise ArgumentError(f"InputChannel: name = {self.name!r}, record_signals = "
                                f"{self.record_signals!r}: a name and at least one record "
                                "signal are required")
        if not self.low < self.high:
            raise ArgumentError(f"InputChannel {self.name!r}: low = {self.low!r}, high = "
                                f"{self.high!r}: low must be below high")
        if not (isinstance(self.channel, str) and self.channel.isidentifier()):
            raise ArgumentError(f"InputChannel {self.name!r}: channel = {self.channel!r}: "
                                f"must be a channel's name: one of {', '.join(LOOP_CHANNELS)}"
                                ", or an extra one its component declares (Part.channels)")

    @property
    def record_signal(self) -> str:
        """The record signal that drives this input as declared (its first)."""
        return self.record_signals[0]

    @property
    def span(self) -> tuple[float, float]:
        """The values the input acts over: ``acts_within``, else [low, high]."""
        return self.acts_within if self.acts_within is not None else (self.low, self.high)

    def accepts(self, low: float, high: float) -> bool:
        """Whether a signal spanning ``low`` to ``high`` stays within the declared range."""
        return self.low <= low and high <= self.high

    def check(self, low: float, high: float, where: str) -> None:
        """Refuse a signal spanning ``low`` to ``high`` outside [low, high] with one
        ExperimentError (``where`` names the experiment)."""
        if self.accepts(low, high):
            return
        if self.check_value is not None:
            for value in (low, high):
                self.check_value(f"its {self.label}", value, where=where, error=ExperimentError)
        unit, factor = self.shown_in
        shown = f" {unit}" if unit else ""
        rule = self.rule.format(low=self.low * factor, high=self.high * factor)
        raise ExperimentError(f"{where}: its {self.label} spans {low * factor:g} to "
                              f"{high * factor:g}{shown}; {rule}")

    def describe(self) -> str:
        """"'command' [1] in [0, 1]": the name, unit and range, for messages."""
        return f"{self.name!r} [{self.unit}] in [{self.low:g}, {self.high:g}]"


class DeclaredInputs:
    """The model protocol's questions about what drives a model, answered from its
    declared ``inputs()`` (the first is its drive): one place says name, unit, range and
    record signal."""

    #: channels the model adds after its components' (a closed loop's ``LOOP_OWN``)
    own_channels: ClassVar[tuple[str, ...]] = ()

    def inputs(self) -> tuple[InputChannel, ...]:
        """The inputs this model declares, its drive first."""
        raise NotImplementedError

    def parts(self) -> tuple[Part, ...]:
        """The model's components (``core.component.Part``)."""
        raise NotImplementedError

    @property
    def channel_names(self) -> tuple[str, ...]:
        """The model's channels in kernel order (``parts_layout``): ``CHANNELS``, its
        components' extras, its own; found once per model (a model does not change, and
        every run packs its channels by it)."""
        found = self.__dict__.get("_channel_names")
        if found is None:
            found = parts_layout(self.parts(), self.own_channels)
            object.__setattr__(self, "_channel_names", found)
        return found

    @property
    def drive_input(self) -> InputChannel:
        """The input an experiment drives (the first declared)."""
        return self.inputs()[0]

    @property
    def drive_quantity(self) -> str:
        return self.drive_input.name

    @property
    def drive_unit(self) -> str:
        return self.drive_input.unit

    @property
    def input_signal(self) -> str:
        """The record signal that drives it (its drive's own)."""
        return self.drive_input.record_signal

    @property
    def input_range(self) -> tuple[float, float]:
        """The values its drive acts over (``InputChannel.span``)."""
        return self.drive_input.span

    def check_drive_values(self, low: float, high: float, where: str) -> None:
        """Refuse a drive spanning ``low`` to ``high`` outside its declared range."""
        self.drive_input.check(low, high, where)

    def declared_input(self, name: str, who: str) -> InputChannel:
        """The input named ``name``; one ExperimentError naming ``who`` (the experiment),
        this model and its declared inputs when it declares none of that name."""
        declared = self.inputs()
        for channel in declared:
            if channel.name == name:
                return channel
        listed = ", ".join(c.describe() for c in declared)
        raise ExperimentError(
            f"{who} drives {name!r}, but the {self.drive_label} of this "
            f"{type(self).__name__} needs a {declared[0].name!r} signal (its declared "
            f"inputs: {listed})")

    @property
    def drive_label(self) -> str:
        """What takes its drive, for messages."""
        return self.drive_input.label

    def routed(self, drive: Signal, drives: Mapping[str, Signal] | None = None
               ) -> dict[str, Signal]:
        """Channel name -> signal: ``drive`` on its drive's channel and each of ``drives``
        (input name -> signal) on the channel its declared input names (one of
        ``channel_names``)."""
        routed = {self.drive_input.channel: drive}
        for name, signal in (drives or {}).items():
            if name == self.drive_quantity:
                raise ExperimentError(f"drives = {{{name!r}: ...}}: {name!r} is the drive of "
                                      f"this {type(self).__name__}, given as the drive; "
                                      "drives names its other inputs")
            routed[self.declared_input(name, "channels").channel] = signal
        return routed
