"""What a component declares: its parameter block, its states and its compiled functions.

A component (a friction law, a valve, the actuator mechanics, a rig drive) reads its
parameters from its own *block* of the kernel's parameter vector, through named local
indices defined next to its equations (``SIGMA0 = LUGRE_BLOCK.index("sigma0")``). A
block lists, in order:

- parameters, read from the parameter set by name;
- settings, fixed by the strategy object itself (e.g. the chamber law's polytropic
  index rule), not by the parameter set;
- derived quantities, computed from the block by the component's compiled ``derive``
  whenever a value changes (orifice-flow constants, the polytropic index).

A model assembly (``pneumact.core.assembly``) places the blocks of a model's
components one after another and binds their compiled functions into one kernel.

A component placed more than once in one model (the cylinder's two chambers) is placed
under an *instance* name: its entries are then named ``instance.name`` in the model
(``chamber_a.V_dead``), while its compiled functions still read its block by local index
at the offset the model passes (``CHAMBER_A_LO``), so one component's code serves every
instance.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from ..errors import ComponentError

PARAMETER = "parameter"
SETTING = "setting"
DERIVED = "derived"


@dataclass(frozen=True)
class Block:
    """An ordered list of (name, kind) entries: a component's slice of the vector."""

    entries: tuple[tuple[str, str], ...] = ()

    @classmethod
    def of(cls, *parameters: str, settings: tuple[str, ...] = (),
           derived: tuple[str, ...] = ()) -> Block:
        return cls(tuple((n, PARAMETER) for n in parameters)
                   + tuple((n, SETTING) for n in settings)
                   + tuple((n, DERIVED) for n in derived))

    def __add__(self, other: Block) -> Block:
        names = [n for n, _ in self.entries]
        clash = [n for n, _ in other.entries if n in names]
        if clash:
            raise ValueError(f"block entries {clash} appear twice")
        return Block(self.entries + other.entries)

    def __len__(self) -> int:
        return len(self.entries)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for n, _ in self.entries)

    def of_kind(self, kind: str) -> tuple[str, ...]:
        return tuple(n for n, k in self.entries if k == kind)

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.of_kind(PARAMETER)

    def index(self, name: str) -> int:
        """Local index of ``name`` in the block (the constant its functions use)."""
        return self.names.index(name)


@dataclass(frozen=True)
class StateSpec:
    """A state of a component: name, SI unit, and how output times interpolate it.

    ``monotone``: between two steps the value stays between its values at the step
    ends (shape-preserving cubic), for states with a bound the model guarantees, such as
    the bristle deflection |sigma0*z| <= Fs; other states use the plain cubic Hermite.
    """

    name: str
    unit: str
    monotone: bool = False


@dataclass(frozen=True)
class Part:
    """One component as the assembly sees it.

    ``functions`` maps the name a template calls (``friction_law``, ``valve_rates``) to
    ``"module:function"``; ``constants`` likewise for compile-time constants.
    ``settings`` gives the values of the block's setting entries; ``label`` describes the
    component for people, ``key`` names its compiled variant in the kernel's file name.
    ``values`` gives the values of block parameters the component fixes itself (a
    controller's gains: varied by name like any parameter, but not in the parameter set)
    and ``units`` their units where they depend on the model (a gain's on the plant).
    ``templates`` are kernel templates of the component's own (a friction law's functions
    on its slice of the state vector), bound before the model's templates and visible to
    a closed loop's plant. ``channels`` are the kernel channels the component reads
    beyond the fixed ones (``core.channels``: the cylinder's supply pressure), placed after
    them in the order of the model's parts; the kernel holds each one's index as
    ``CH_<NAME>``, which the template hands to the component's functions.
    """

    role: str
    block: Block
    states: tuple[StateSpec, ...] = ()
    functions: Mapping[str, str] = field(default_factory=dict)
    constants: Mapping[str, str] = field(default_factory=dict)
    settings: Mapping[str, float] = field(default_factory=dict)
    label: str = ""
    key: str = ""
    templates: tuple[str, ...] = ()
    values: Mapping[str, float] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    instance: str = ""
    channels: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.instance and not self.instance.isidentifier():
            raise ComponentError(
                f"Part(role={self.role!r}): instance = {self.instance!r}: must be a name of "
                f"letters, digits and underscores, not starting with a digit (it names the "
                f"component's parameters, instance.name, and its kernel constants)")

    @property
    def name(self) -> str:
        """What names the component in its model: its instance, else its role."""
        return self.instance or self.role

    def qualified(self, entry: str) -> str:
        """The model's name of the block entry ``entry``: ``instance.entry`` for an
        instance, else ``entry``."""
        return instance_entry(self.instance, entry) if self.instance else entry

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The block's parameters as the model names them."""
        return tuple(self.qualified(n) for n in self.block.parameters)


def instance_entry(instance: str, entry: str) -> str:
    """The name of an instance's entry: ``chamber_a.V_dead`` (a dot, FMI's structured
    naming)."""
    return f"{instance}.{entry}"


def required_parameters(parts: Sequence[Part]) -> tuple[str, ...]:
    """The parameters a model of ``parts`` reads: every block's, each once, in order."""
    return tuple(dict.fromkeys(p for part in parts for p in part.parameter_names))
