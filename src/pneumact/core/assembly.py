"""The model assembly: one model and its components joined into a compiled kernel.

An ``Assembly`` is built from a model (``Actuator``, ``FrictionRig``) and owns its
layout, so no other module indexes states, parameters or outputs by position:

- the parameter vector: the blocks the components declare, one after another, each
  holding the component's parameters, its settings and its derived quantities; a
  parameter shared by two components (the diaphragm area) has a slot in each block; a
  component placed under an instance name (``Part.instance``) names its entries
  ``instance.name`` (``chamber_a.V_dead``), and its block's constants by the instance
  (``CHAMBER_A_LO``);
- ``pack`` (values by name -> vector, settings filled, derived quantities computed) and
  ``update`` (change values by name, re-derive), ``values`` (vector -> names);
- the state and output names with units, and their columns;
- the signal channels: the fixed ones, the extras its components declare, the model's
  own (``core.channels``), and where each sits (``channel_index``);
- the kernel: generated from the model template, the integrators and the batch loop
  with the components' compiled functions (``core.codegen``).

Derived quantities (orifice-flow constants, the polytropic index) are computed by the
kernel's compiled ``derive``, which the integrators also call at the start of every run:
a vector changed by name, by a batch row or by a sensitivity perturbation is always
consistent.
"""

from __future__ import annotations

import contextlib
import importlib
import threading
import weakref
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass
from functools import cached_property
from types import ModuleType

import numpy as np

from ..errors import ComponentError, ParameterError
from . import codegen
from .c_engine import Kernel, build_ahead, current_engine, engine_kernel
from .channels import layout_constants, parts_layout
from .component import DERIVED, PARAMETER, SETTING, Part, StateSpec

__all__ = ["Assembly", "assemble", "explain_unknown_names"]

INTEGRATORS = "pneumact.core.integrators"


@dataclass(frozen=True)
class Slot:
    """One entry of the parameter vector: its index, name (the model's: ``instance.name``
    for an instance's), kind and component (its instance, else its role)."""

    index: int
    name: str
    kind: str
    role: str


class Assembly:
    """A model's layout and kernel (see the module docstring)."""

    def __init__(self, model):
        self.model = model
        self._kernels: dict[str, Kernel] = {}
        #: engine -> the vector of the model's own parameter set (``pack``)
        self._packed: dict[str, np.ndarray] = {}
        self.parts: tuple[Part, ...] = tuple(model.parts())
        refuse_duplicates(self.parts, self.describe())
        self.template: str = model.template
        entries: list[Slot] = []
        self.block_ranges: dict[str, tuple[int, int]] = {}
        for part in self.parts:
            lo = len(entries)
            for name, kind in part.block.entries:
                entries.append(Slot(len(entries), part.qualified(name), kind, part.name))
            self.block_ranges[part.name] = (lo, len(entries))
        self.entries: tuple[Slot, ...] = tuple(entries)
        slots: dict[str, list[int]] = {}
        for slot in entries:
            if slot.kind == PARAMETER:
                slots.setdefault(slot.name, []).append(slot.index)
        self.slots: dict[str, tuple[int, ...]] = {k: tuple(v) for k, v in slots.items()}
        #: parameters whose values the components fix (a controller's gains), and the
        #: units the model gives them
        self.own_values: dict[str, float] = {part.qualified(n): float(v)
                                             for part in self.parts
                                             for n, v in part.values.items()}
        self.parameter_units: dict[str, str] = {part.qualified(n): u for part in self.parts
                                                for n, u in part.units.items()}
        self.states: tuple[StateSpec, ...] = tuple(s for part in self.parts for s in part.states)
        #: the kernel's channels in order (``core.channels.channel_layout``)
        self.channels: tuple[str, ...] = parts_layout(self.parts,
                                                      getattr(model, "own_channels", ()))
        module = importlib.import_module(self.template)
        # a model may name its outputs itself (a closed loop: its plant's, then its own)
        self.output_names: tuple[str, ...] = tuple(
            getattr(model, "output_names", None) or module.OUTPUT_NAMES)
        self.output_units: tuple[str, ...] = tuple(
            getattr(model, "output_units", None) or module.OUTPUT_UNITS)

    # -- names -------------------------------------------------------------------------
    @property
    def size(self) -> int:
        """Length of the parameter vector."""
        return len(self.entries)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Every parameter the components read, in vector order."""
        return tuple(self.slots)

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    @property
    def state_units(self) -> tuple[str, ...]:
        return tuple(s.unit for s in self.states)

    def state_index(self, name: str) -> int:
        return self.state_names.index(name)

    def role_states(self, role: str) -> tuple[int, ...]:
        """Columns of the states of the component ``role`` (a friction law's: any number),
        or of its instances', in order, where the model places it under instance names
        (two friction laws on the cylinder)."""
        first, found = 0, list[int]()
        for part in self.parts:
            if part.name == role:
                return tuple(range(first, first + len(part.states)))
            if part.role == role and part.instance:
                found.extend(range(first, first + len(part.states)))
            first += len(part.states)
        if any(part.role == role and part.instance for part in self.parts):
            return tuple(found)
        raise KeyError(f"{self.describe()} has no component {role!r}")

    def role_span(self, role: str) -> tuple[int, int, int]:
        """(first slot, end slot, first state) of the instances of ``role``, placed one
        after another: a model's ``spanned_roles`` are read under the role's own constants
        (``FRICTION_LO``, ``FRICTION_HI``, ``S_FRICTION``) by a template written for one
        component of that role (the cylinder's, for two friction laws)."""
        placed = [i for i, part in enumerate(self.parts) if part.role == role and part.instance]
        if not placed or placed != list(range(placed[0], placed[-1] + 1)):
            raise ComponentError(f"{self.describe()}: the instances of {role!r} must be "
                                 "placed one after another to be read as one span")
        names = [self.parts[i].name for i in placed]
        start = sum(len(part.states) for part in self.parts[:placed[0]])
        return self.block_ranges[names[0]][0], self.block_ranges[names[-1]][1], start

    def channel_index(self, name: str) -> int:
        """Where channel ``name`` sits in the packed channels; one ComponentError naming
        the model's channels when it has none of that name."""
        if name not in self.channels:
            raise ComponentError(f"{self.describe()} has no channel {name!r}; its channels "
                                 f"are {', '.join(self.channels)}")
        return self.channels.index(name)

    def signal_source(self, name: str) -> tuple[int, int] | None:
        """(0, state column) or (1, output column) of a signal name; states win."""
        if name in self.state_names:
            return 0, self.state_index(name)
        if name in self.output_names:
            return 1, self.output_names.index(name)
        return None

    def check_parameters(self, names: Sequence[str], what: str) -> list[str]:
        """``names`` as a list, or one ParameterError naming one this model does not have
        (with the closest of its parameters, and all of them)."""
        import difflib

        for name in names:
            if name in self.slots:
                continue
            said = next((text for text in (explain(name) for explain in _NAME_EXPLAINERS)
                         if text), "")
            close = difflib.get_close_matches(name, list(self.slots), n=1)
            guess = f"did you mean '{close[0]}'?" if close else ""
            hint = f" ({'; '.join(text for text in (said, guess) if text)})" \
                if said or guess else ""
            raise ParameterError(
                f"{what}: '{name}' is not a parameter of {self.describe()}{hint}; its "
                f"parameters are {', '.join(self.parameter_names)}")
        return list(names)

    def describe(self) -> str:
        model = self.model
        return model.describe() if hasattr(model, "describe") else type(model).__name__

    # -- the vector --------------------------------------------------------------------
    def pack(self, params: Mapping[str, float] | None = None) -> np.ndarray:
        """The kernel vector: parameters from ``params`` (default: the model's set;
        given values, else catalogue defaults; those a component fixes, such as a
        controller's gains, from the component), settings from the components, derived
        quantities computed. The model's own vector is packed once per engine (its
        parameter set and components do not change) and handed out as a copy."""
        if params is None:
            engine = current_engine()
            packed = self._packed.get(engine)
            if packed is None:
                packed = self._packed[engine] = self._pack(self.model.params)
            return packed.copy()
        return self._pack(params)

    def _pack(self, params: Mapping[str, float]) -> np.ndarray:
        settings = {part.qualified(name): value for part in self.parts
                    for name, value in part.settings.items()}
        own = self.own_values
        vec = np.zeros(self.size)
        for slot in self.entries:
            if slot.kind == PARAMETER:
                vec[slot.index] = own[slot.name] if slot.name in own else params[slot.name]
            elif slot.kind == SETTING:
                vec[slot.index] = settings[slot.name]
        self.kernel.derive(vec)
        return vec

    def update(self, vec: np.ndarray, changes: Mapping[str, float]) -> np.ndarray:
        """Set parameter values by name (every slot of each) and re-derive, in place."""
        for name, value in changes.items():
            for index in self.slots[name]:
                vec[index] = float(value)
        self.kernel.derive(vec)
        return vec

    def values(self, vec: np.ndarray) -> dict[str, float]:
        """Parameter name -> value in ``vec``."""
        return {name: float(vec[idx[0]]) for name, idx in self.slots.items()}

    def column_slots(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """(pointer, indices): the slots of each name, in CSR form, for the batch loop."""
        ptr = np.zeros(len(names) + 1, dtype=np.int64)
        idx: list[int] = []
        for c, name in enumerate(names):
            idx.extend(self.slots[name])
            ptr[c + 1] = len(idx)
        return ptr, np.asarray(idx, dtype=np.int64)

    def directions(self, vec: np.ndarray, names: Sequence[str]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """How each parameter moves the vector, derived slots included: dvec/dθ in CSR
        form (pointer, slot, value); the derived part by central differences of the
        compiled ``derive`` (derived quantities depend on parameters only)."""
        derived = np.array([s.kind == DERIVED for s in self.entries])
        ptr = np.zeros(len(names) + 1, dtype=np.int64)
        idx: list[int] = []
        val: list[float] = []
        for p, name in enumerate(names):
            column = np.zeros(self.size)
            column[list(self.slots[name])] = 1.0
            if derived.any():
                value = vec[self.slots[name][0]]
                step = 1e-6 * (abs(value) if value != 0.0 else 1.0)
                up, down = vec.copy(), vec.copy()
                self.update(up, {name: value + step})
                self.update(down, {name: value - step})
                column[derived] = (up[derived] - down[derived]) / (2.0 * step)
            nonzero = np.flatnonzero(column)
            idx.extend(nonzero.tolist())
            val.extend(column[nonzero].tolist())
            ptr[p + 1] = len(idx)
        return ptr, np.asarray(idx, dtype=np.int64), np.asarray(val, dtype=float)

    # -- the kernel ----------------------------------------------------------------------
    def kernel_spec(self) -> codegen.KernelSpec:
        imports: list[tuple[str, str]] = []
        for part in self.parts:
            imports.extend(part.functions.items())
            imports.extend(part.constants.items())
        constants: list[tuple[str, object]] = [("NSTATE", len(self.states)),
                                               ("NPARAM", self.size),
                                               ("NOUT", len(self.output_names))]
        for role, (lo, hi) in self.block_ranges.items():
            constants += [(f"{role.upper()}_LO", lo), (f"{role.upper()}_HI", hi)]
        first = 0
        for part in self.parts:  # where each component's states start (even if it has none)
            constants.append((f"S_{part.name.upper()}", first))
            first += len(part.states)
        for role in getattr(self.model, "spanned_roles", ()):
            lo, hi, start = self.role_span(role)
            constants += [(f"{role.upper()}_LO", lo), (f"{role.upper()}_HI", hi),
                          (f"S_{role.upper()}", start)]
        constants += [(f"S_{s.name.upper()}", i) for i, s in enumerate(self.states)]
        constants += [(output_constant(name), i) for i, name in enumerate(self.output_names)]
        constants.append(("MONOTONE", tuple(bool(s.monotone) for s in self.states)))
        constants += layout_constants(self.channels)  # none without extra channels
        # PRIVATE_INPUTS: the model writes its own input into the channels (a closed
        # loop's controller output), so a batch gives each row its own copy of them
        switches: dict[str, object] = {"PRIVATE_INPUTS": False,
                                       **getattr(self.model, "kernel_constants", dict)()}
        constants += sorted(switches.items())
        keys = [part.key for part in self.parts if part.key]
        model = self.template.rpartition(".")[2].removesuffix("_template")
        label = "_".join([model, *keys])
        templates = getattr(self.model, "kernel_templates", (self.template, INTEGRATORS))
        children = tuple(getattr(self.model, "kernel_children", tuple)())
        components = tuple(dict.fromkeys(t for part in self.parts for t in part.templates))
        return codegen.KernelSpec(label, tuple(templates), tuple(imports),
                                  tuple(dict.fromkeys(constants)), children, components)

    @property
    def kernel(self) -> Kernel:
        """The compiled kernel of the engine in force (``core.c_engine.current_engine``):
        the numba kernel module, or the C kernel that looks like it."""
        return self.kernel_on(current_engine())

    def kernel_on(self, engine: str) -> Kernel:
        """The kernel on ``engine`` ('auto', 'c' or 'numba'), built on first use and
        cached on disk; the numba module is what the C back end translates."""
        kernel = self._kernels.get(engine)
        if kernel is None:
            with _KERNEL_LOCK:
                kernel = self._kernels.get(engine)
                if kernel is None:
                    kernel = self._kernels[engine] = engine_kernel(self._spec, engine)
        return kernel

    def building_kernel(self) -> AbstractContextManager[None]:
        """A block during which the kernel of the engine in force is built in a thread
        where it can be (``c_engine.build_ahead``: a cold start's compiler beside what
        the block builds); nothing to do once this assembly holds that kernel."""
        if current_engine() in self._kernels:
            return contextlib.nullcontext()
        return build_ahead(self._spec)

    @property
    def numba_kernel(self) -> ModuleType:
        """The numba kernel module (what the C back end translates, what the FMU carries)."""
        return codegen.load(self._spec)

    @cached_property
    def _spec(self) -> codegen.KernelSpec:
        return self.kernel_spec()


_ASSEMBLIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()
_KERNEL_LOCK = threading.RLock()  # building a kernel (one at a time in this process)


def part_name(part: Part) -> str:
    """A component as a message names it: its label, else its role."""
    return part.label or part.role


def refuse_duplicates(parts: Sequence[Part], model: str) -> None:
    """One ComponentError, naming both components, if two of ``parts`` have one role (or
    instance name: a role placed twice needs one per placement) or bind one kernel name (a
    function or a constant: one namespace, the generated module's): the kernel would
    otherwise silently take the last one's."""
    claims: dict[tuple[bool, str], int] = {}
    for index, part in enumerate(parts):
        names = [("instance" if part.instance else "role", part.name)]
        names += [("kernel function", name) for name in part.functions]
        names += [("kernel constant", name) for name in part.constants]
        for what, name in names:
            first = claims.setdefault((what in ("role", "instance"), name), index)
            if first != index:
                raise ComponentError(
                    f"{model}: components {part_name(parts[first])!r} and "
                    f"{part_name(part)!r} both claim the {what} {name!r}; a role and a "
                    f"kernel name each belong to one component of a model")


def output_constant(name: str) -> str:
    """The kernel constant holding the index of output ``name`` ("OUT_<NAME>")."""
    return f"OUT_{name.upper()}"


#: functions that say why a name is no parameter, where more can be said than a close
#: match (``explain_unknown_names``); '' when they know nothing of it
_NAME_EXPLAINERS: list[Callable[[str], str]] = []


def explain_unknown_names(explain: Callable[[str], str]) -> None:
    """Register ``explain`` (name -> why it is no parameter, or ''): an assembly's refusal
    of an unknown name says it (the parameter catalogue registers its renamed names and
    component instances, a layer above this one)."""
    if explain not in _NAME_EXPLAINERS:
        _NAME_EXPLAINERS.append(explain)


def assemble(model) -> Assembly:
    """The assembly of ``model`` (one per model object, reused)."""
    with _LOCK:
        assembly = _ASSEMBLIES.get(model)
        if assembly is None:
            assembly = _ASSEMBLIES[model] = Assembly(model)
        return assembly
