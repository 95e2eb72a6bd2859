"""The parameter catalogue: every parameter a component declares, with unit and range.

Components declare the parameters they read, next to the equations that read them
(``models/friction/`` declares sigma0 … vs, ``models/valves.py`` the orifice areas,
and so on), with ``declare(...)``; relations between parameters (Fs >= Fc, p_res <
p_atm) are declared the same way with ``declare_relation(...)``. The catalogue is only a
lookup of those declarations (name -> unit, meaning, default, range): it fixes no vector
layout. A model assembly lays out the parameters its components declare
(``pneumact.core.assembly``).

A component placed more than once in one model (the cylinder's chambers) declares its
parameters once, for its *kind* (``declare_kind("chamber", P("V_dead", ...))``), and the
instance names it is placed under (``declare_instances("chamber", chamber_a=...)``): the
catalogue then lists ``chamber_a.V_dead`` with the kind's entry (unit, ranges, meaning,
the instance's description added). A name that was renamed (``V_dead_a``) is refused
with its new name (``renamed``).

``catalogue()`` imports the model modules on first use so that every declaration is
made before a name is looked up.
"""

from __future__ import annotations

import importlib
import math
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

import numpy as np

from ..core.component import instance_entry

__all__ = [
    "ParameterSpec",
    "Relation",
    "catalogue",
    "declare",
    "declare_instances",
    "declare_kind",
    "declare_relation",
    "declare_renamed",
    "declared",
    "explain_unknown",
    "instances_of",
    "relations",
]

#: Modules whose import declares parameters, in the order the catalogue lists them.
DECLARING_MODULES = (
    "pneumact.models.mechanics",
    "pneumact.models.friction",
    "pneumact.models.pneumatics",
    "pneumact.models.valves",
    "pneumact.models.rig",
    "pneumact.models.cylinder",
    "pneumact.models.controllers",
    "pneumact.models.sensors",
)


#: a unit slip: a value typed in a unit this many times too large or too small ...
SLIP_FACTOR = 1000.0
#: ... recognised when the value lies at least this many times outside the plausible
#: range (just outside it is only implausible: a warning)
SLIP_MARGIN = 10.0


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter: SI unit (a pint expression), meaning, default and allowed range."""

    name: str
    unit: str
    description: str
    default: float | None = None
    minimum: float | None = None  # inclusive lower bound, exclusive if strict_minimum
    strict_minimum: bool = False
    maximum: float | None = None  # inclusive upper bound
    group: str = "misc"
    #: (low, high) real actuators and rigs lie in; a legal value outside it warns
    #: (``PlausibilityWarning``): often a unit typed wrong
    plausible: tuple[float, float] | None = None

    def allowed(self) -> str:
        """'must be > 0', 'must be in (0.53, 1]', or '' when any finite value will do."""
        lo, hi = self.minimum, self.maximum
        if lo is not None and hi is not None:
            return f"must be in {'(' if self.strict_minimum else '['}{lo:g}, {hi:g}]"
        if lo is not None:
            return f"must be {'>' if self.strict_minimum else '>='} {lo:g}"
        if hi is not None:
            return f"must be <= {hi:g}"
        return ""

    def violation(self, value: float) -> str:
        """What ``value`` breaks: 'must be > 0', 'must be <= 1e+10' ('' if nothing)."""
        lo, hi = self.minimum, self.maximum
        if lo is not None and (value <= lo if self.strict_minimum else value < lo):
            text = f"must be {'>' if self.strict_minimum else '>='} {lo:g}"
        elif hi is not None and value > hi:
            text = f"must be <= {hi:g}"
        else:
            return ""
        return f"{text} {self.unit}".rstrip()

    def is_plausible(self, value: float) -> bool:
        """Whether ``value`` lies in the plausible range (True when none is stated)."""
        if self.plausible is None:
            return True
        lo, hi = self.plausible
        return lo <= value <= hi

    def unit_slip(self, value: float) -> str:
        """'did you mean 12850 N/m?' when ``value`` lies more than ``SLIP_MARGIN`` times
        outside the plausible range and a factor ``SLIP_FACTOR`` brings it inside (a
        unit typed a thousand times too large or small); '' otherwise."""
        if self.plausible is None or not math.isfinite(value):
            return ""
        lo, hi = self.plausible
        for outside, scaled in ((value > SLIP_MARGIN * hi, value / SLIP_FACTOR),
                                (value < lo / SLIP_MARGIN, value * SLIP_FACTOR)):
            if outside and lo <= scaled <= hi:
                return (f"likely a unit slip by a factor {SLIP_FACTOR:g}: did you mean "
                        f"{scaled:g} {self.unit}?".replace(" ?", "?"))
        return ""

    def hint(self, value: float) -> str:
        """The likely mistake behind an impossible or implausible ``value``, or ''."""
        if self.unit != "Pa" or self.plausible is None:
            return ""
        from pneumact.checks import pressure_hint

        return pressure_hint(value, self.plausible)

    def in_range(self, values):
        """Elementwise: whether each value is finite and inside the allowed range."""
        values = np.asarray(values, dtype=float)
        ok = np.isfinite(values)
        if self.minimum is not None:
            ok &= values > self.minimum if self.strict_minimum else values >= self.minimum
        if self.maximum is not None:
            ok &= values <= self.maximum
        return ok


@dataclass(frozen=True)
class Relation:
    """A condition between parameters that every parameter set must meet.

    ``holds(*values)`` works elementwise on arrays (the batch engine checks whole tables
    at once); ``explain(*values)`` says what is wrong for one set of scalar values.
    """

    names: tuple[str, ...]
    holds: Callable[..., object]
    explain: Callable[..., str]


_SPECS: dict[str, ParameterSpec] = {}
#: a component kind's parameters by their local names (chamber: V_dead)
_KINDS: dict[str, dict[str, ParameterSpec]] = {}
#: instance name -> its kind (chamber_a -> chamber)
_INSTANCES: dict[str, str] = {}
#: old name -> new name, for names refused with their new one
_RENAMED: dict[str, str] = {}
_RELATIONS: list[Relation] = []
_LOCK = threading.Lock()
_LOADED = False


def declare(*specs: ParameterSpec) -> tuple[str, ...]:
    """Register parameters (a component module calls this at import); returns the names.

    Declaring a name twice is allowed only with the identical spec (two components
    sharing one physical parameter, such as the diaphragm area).
    """
    return _register(_SPECS, specs, "")


def declare_kind(kind: str, *specs: ParameterSpec) -> tuple[str, ...]:
    """Register the parameters of a component ``kind`` that a model places under instance
    names (``declare_instances``); their names are local (``V_dead``) and, alone, not
    parameters of any model. Returns the local names."""
    return _register(_KINDS.setdefault(kind, {}), specs, f" of kind {kind!r}")


def _register(into: dict[str, ParameterSpec], specs: tuple[ParameterSpec, ...],
              where: str) -> tuple[str, ...]:
    """``specs`` into ``into`` by name, a name declared again only with the identical
    spec; returns the names."""
    for spec in specs:
        old = into.get(spec.name)
        if old is not None and old != spec:
            raise RuntimeError(f"parameter {spec.name!r}{where} declared twice with "
                               f"different specs: {old} and {spec}")
        into[spec.name] = spec
    return tuple(s.name for s in specs)


def declare_instances(kind: str, **instances: str) -> tuple[str, ...]:
    """Register instance names of the declared ``kind``, each with what it is
    (``chamber_a="the cap-side chamber A"``): ``instance.name`` is then a parameter with
    the kind's entry of ``name``, the instance's description added. Returns the names."""
    if kind not in _KINDS:
        raise RuntimeError(f"declare_instances: kind {kind!r} is not declared "
                           f"(declare_kind first); kinds: {sorted(_KINDS)}")
    names = []
    local_names = set(_KINDS[kind])
    for instance, what in instances.items():
        if _INSTANCES.setdefault(instance, kind) != kind:
            raise RuntimeError(f"instance {instance!r} declared of kinds "
                               f"{_INSTANCES[instance]!r} and {kind!r}")
        for local, spec in _KINDS[kind].items():
            name = instance_entry(instance, local)
            declare(replace(spec, name=name, description=f"{spec.description}; {what}"))
            names.append(name)
        # the kind's relations between its own parameters hold in each instance (a
        # friction law's Fs >= Fc: friction_rod.Fs >= friction_rod.Fc)
        for relation in tuple(_RELATIONS):
            if set(relation.names) <= local_names:
                declare_relation(tuple(instance_entry(instance, n) for n in relation.names),
                                 relation.holds, relation.explain)
    return tuple(names)


def declared(name: str) -> ParameterSpec:
    """The spec declared so far under ``name``, without loading the declaring modules (a
    module that declares a kind from parameters other modules declared before it)."""
    return _SPECS[name]


def instances_of(kind: str) -> tuple[str, ...]:
    """The instance names declared of ``kind``, in declaration order (what a model that
    places it may name: a message refusing another names these)."""
    _load()
    return tuple(instance for instance, of in _INSTANCES.items() if of == kind)


def declare_renamed(**renamed: str) -> None:
    """Register old names (``V_dead_a="chamber_a.V_dead"``): a set or an argument using one
    is refused naming the new name (``explain_unknown``)."""
    _RENAMED.update(renamed)


def explain_unknown(name: str) -> str:
    """Why ``name`` is no parameter, where more can be said than that: its new name (a
    renamed one), the known instances (an unknown instance), or the parameters of the
    instance's kind (an unknown one); '' otherwise."""
    _load()
    if name in _RENAMED:
        return f"renamed: use '{_RENAMED[name]}'"
    instance, dot, local = name.partition(".")
    if not dot:
        return ""
    kind = _INSTANCES.get(instance)
    if kind is None:
        return (f"no component instance '{instance}'; instances: "
                f"{', '.join(_INSTANCES) or 'none'}")
    return (f"'{local}' is no parameter of {instance}, a {kind}; a {kind}'s parameters: "
            f"{', '.join(_KINDS[kind])}")


def declare_relation(names: tuple[str, ...], holds: Callable[..., object],
                     explain: Callable[..., str]) -> None:
    """Register a relation between parameters (checked when all of them have a value)."""
    relation = Relation(tuple(names), holds, explain)
    if relation not in _RELATIONS:
        _RELATIONS.append(relation)


def _load() -> None:
    global _LOADED
    if _LOADED:
        return
    with _LOCK:
        if not _LOADED:
            for module in DECLARING_MODULES:
                importlib.import_module(module)
            _LOADED = True


def catalogue() -> Mapping[str, ParameterSpec]:
    """Every declared parameter, name -> spec, in declaration order (read-only)."""
    _load()
    return MappingProxyType(_SPECS)


def relations() -> tuple[Relation, ...]:
    """Every declared relation between parameters."""
    _load()
    return tuple(_RELATIONS)


def is_finite_number(value: object) -> bool:
    """A real number (not a bool) that is finite."""
    return (isinstance(value, (int, float, np.integer, np.floating))
            and not isinstance(value, (bool, np.bool_)) and math.isfinite(float(value)))
