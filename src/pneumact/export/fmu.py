"""Export an actuator or a cylinder as an FMI 2.0 or 3.0 FMU: Model Exchange,
Co-Simulation or both. What the FMU takes of the model (its inputs, their ranges and
nominal values, its end-stop check, its recommended step) the model says
(``fmu_form``, ``fmu_interface``: ``models.fmu_interface``); nothing here asks its class.

The FMU's physics is the model's kernel written in C by the kernel generator's second
back end (``core.c_source``), from the same component functions the compiled kernels
run: ``rhs``, ``outputs``, ``jac``, ``initial_state``, ``derive`` and, for a law with mode
switches (GMS), ``event_guards`` and ``event_switch``. A fixed C file (``templates/
fmu.c.j2``) holds the FMI side: an instance's arrays and the value references onto them.

What drives the model becomes an FMU input (a one-point input channel of the packed
signals: the pressure, the set-point or the command, and an external force); every
parameter of the set is a tunable parameter with its unit, description and provenance;
every state and every output of the kernel is an output; the derivatives are declared;
inputs and parameters carry their hard ranges and nominal values, and the default
experiment a tolerance and a step that forward Euler takes on the end stops. A run that
goes unstable on an end stop (an explicit importer's step past the stiff contact's
limit, issue 39) ends with fmi2Error and a message naming the limit and the remedy.
The archive holds the C sources (an importer on another platform builds them) and, unless
``binary=False``, the binary built here with the machine's C compiler.

A Co-Simulation FMU (``kind="cs"`` or ``"both"``) steps itself with pneumact's own
integrator: ``integrate_rodas4`` (``core/integrators.py``), translated to C by the same back
end from the same source as the compiled integrator, so a communication step is what
``pa.simulate`` does over that interval with the inputs held (RODAS4, its step control,
tolerances, jumps and state events).

FMI 3.0 (``fmi=3``) takes the same model.c; its glue (``templates/fmu3.c.j2``) maps FMI 3.0's
calls, declares the event indicators as variables and the time as the independent one, and
the sources carry the FMI 3.0 build description (``sources/buildDescription.xml``).
"""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
import os
import re
import tempfile
import uuid
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
from numba.core import types

from ..core.assembly import Assembly, assemble
from ..core.c_source import translate
from ..core.channels import INPUT_OFFSET
from ..core.signals import Constant, Signal, pack_channels
from ..errors import ArgumentError, ExportError
from ..files import atomic_write
from ..models.fmu_interface import FORCE_INPUT, FmuInput, FmuModel
from ..parameters.catalogue import catalogue
from ..simulation.solvers import DEFAULT_MAX_STEPS, Rodas4
from ..version import __version__
from .compiler import (
    binary_folder,
    build_binary,
    find_compiler,
    fmi_headers,
    platform_tuple,
    shared_library_suffix,
)

__all__ = ["ExportedFmu", "FmuVariable", "export_fmu"]

#: the FMI BaseUnit exponents pint's dimensions map onto
BASE_UNITS = {"[mass]": "kg", "[length]": "m", "[time]": "s", "[temperature]": "K",
              "[current]": "A", "[substance]": "mol", "[luminosity]": "cd"}
TEMPLATES = "pneumact.export"
STOP_TIME = 10.0
#: the FMU ends a run whose stop penetration passes this many times the deepest one the
#: forces can cause (an explicit solver gone unstable on the stiff contact, issue 39)
STOP_MARGIN = 10.0
#: the relative tolerance the FMU's DefaultExperiment recommends (a stiff variable-step
#: solver; measured against pa.simulate in docs/fmu-export.md)
RECOMMENDED_TOLERANCE = 1e-6
#: the communication step a Co-Simulation-only FMU recommends: its own integrator takes
#: the steps the tolerance asks for inside it (a control task's period)
CS_STEP = 1e-3
#: the FMI interfaces of each kind: (Model Exchange, Co-Simulation)
KINDS = {"me": (True, False), "cs": (False, True), "both": (True, True)}
#: the FMI versions exported
FMI_VERSIONS = (2, 3)
#: the FMI 3.0 functions fmu3.c.j2 implements; every other one the header declares is a stub
FMI3_IMPLEMENTED = frozenset({
    "fmi3GetVersion", "fmi3SetDebugLogging", "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation", "fmi3FreeInstance", "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode", "fmi3Terminate", "fmi3Reset", "fmi3GetFloat64",
    "fmi3SetFloat64", "fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState",
    "fmi3GetDirectionalDerivative", "fmi3EnterEventMode", "fmi3UpdateDiscreteStates",
    "fmi3EnterContinuousTimeMode", "fmi3CompletedIntegratorStep", "fmi3SetTime",
    "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives", "fmi3GetEventIndicators",
    "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators", "fmi3GetNumberOfContinuousStates", "fmi3DoStep"})

F64 = types.float64
VECTOR = types.float64[::1]
MATRIX = types.float64[:, ::1]
INDICES = types.int64[::1]
FLAGS = types.boolean[::1]


@dataclass(frozen=True)
class FmuVariable:
    """One FMU variable: its name, causality, unit, start value and where it lives."""

    name: str
    causality: str  # parameter, input, output, local
    kind: str  # parameter, input, state, derivative, output
    index: int  # parameter number, signal entry, state or output column
    unit: str
    description: str
    start: float | None = None
    variability: str = "continuous"
    initial: str | None = None
    derivative: int | None = None  # the 1-based index of its state (a derivative)
    minimum: float | None = None
    maximum: float | None = None
    nominal: float | None = None


@dataclass(frozen=True)
class ExportedFmu:
    """What ``export_fmu`` wrote: the archive, its variables, its binary (if built)."""

    path: Path
    identifier: str
    variables: tuple[FmuVariable, ...]
    platform: str | None
    compiler: str | None
    event_indicators: int  # the end stops' guards, then the friction law's mode guards
    mode_switches: int  # of which the friction law's (GMS: one per block)
    kind: str = "me"  # "me" (Model Exchange), "cs" (Co-Simulation) or "both"
    fmi: int = 2  # the FMI version

    def variable_table(self):
        """The FMU's variables, one row each (value reference, causality, unit, start,
        description), as a DataFrame: a receipt of the export, not a result."""
        import pandas as pd

        rows = [{"value_reference": i, **dataclasses.asdict(v)}
                for i, v in enumerate(self.variables)]
        return pd.DataFrame(rows).set_index("name")

    def names(self, causality: str) -> tuple[str, ...]:
        return tuple(v.name for v in self.variables if v.causality == causality)

    def __repr__(self) -> str:
        built = f"binary {self.platform}" if self.platform else "sources only"
        return (f"ExportedFmu({str(self.path)!r}, kind={self.kind!r}, fmi={self.fmi}, "
                f"inputs={list(self.names('input'))}, "
                f"{len(self.names('parameter'))} parameters, "
                f"{len(self.names('output'))} outputs, {self.event_indicators} event "
                f"indicators, "
                f"{built})")


# ------------------------------------------------------------------------------ the model
def exportable(model) -> FmuModel:
    """The model as the FMU runs it (its ``fmu_form``: an external-force input channel);
    a model without the exporter's protocol (``models.fmu_interface``) is refused."""
    if not hasattr(model, "fmu_form"):
        raise ArgumentError(f"export_fmu: model = {type(model).__name__}; an FMU is exported "
                            "from a pa.Actuator or a pa.Cylinder (a friction rig or a closed "
                            "loop is not yet: docs/fmu-export.md)")
    return model.fmu_form()


def kernel_roots(kernel: ModuleType, events: bool, cosimulation: bool = False) -> dict:
    """The kernel functions the FMU calls, with their argument types; a Co-Simulation
    FMU's also the integrator and the states' scales (its absolute tolerances)."""
    run = (F64, F64, VECTOR, VECTOR, VECTOR, INDICES)
    roots: dict[str, tuple] = {"pa_rhs": (kernel.rhs, (*run, VECTOR)),
             "pa_outputs": (kernel.outputs, (*run, VECTOR)),
             "pa_jac": (kernel.jac, (*run, MATRIX)),
             "pa_initial_state": (kernel.initial_state, (F64, F64, VECTOR, VECTOR, INDICES,
                                                         VECTOR)),
             "pa_derive": (kernel.derive, (VECTOR,)),
             "pa_switch_guards": (kernel.switch_guards, (*run, VECTOR))}
    if events:
        roots["pa_event_guards"] = (kernel.event_guards, (*run, VECTOR))
        roots["pa_event_switch"] = (kernel.event_switch, (*run, FLAGS))
    if cosimulation:
        roots["pa_state_scales"] = (kernel.state_scales, (VECTOR, VECTOR))
        roots["pa_integrate"] = (kernel.integrate_rodas4, (
            VECTOR, VECTOR, VECTOR, INDICES, VECTOR, VECTOR, F64, VECTOR, F64, F64, types.int64,
            MATRIX, MATRIX, VECTOR))
    return roots


def has_events(kernel: ModuleType) -> bool:
    return bool(getattr(kernel, "HAS_EVENTS", False))


def guard_counts(kernel: ModuleType, vec: np.ndarray, sig: np.ndarray, ptr: np.ndarray,
                 n_states: int) -> tuple[int, int]:
    """How many guards the model's kinks (end stops) and its friction law's modes have."""
    y = np.zeros(n_states)
    out = np.zeros(n_states + 2)
    switches = int(kernel.switch_guards(0.0, 0.0, y, vec, sig, ptr, out))
    if not has_events(kernel):
        return switches, 0
    return switches, int(kernel.event_guards(0.0, 0.0, y, vec, sig, ptr, out))


# ------------------------------------------------------------------------------ variables
def parameter_variables(model: FmuModel, asm: Assembly, vec: np.ndarray
                        ) -> list[FmuVariable]:
    specs = catalogue()
    info = model.params.info
    values = asm.values(vec)
    out = []
    for k, name in enumerate(asm.parameter_names):
        spec = specs[name]
        note = info.get(name)
        source = f" [{note.source}: {note.given}]" if note is not None else " [catalogue default]"
        # FMI's min is inclusive: a strict bound (> 0) is written as its closure (>= 0)
        out.append(FmuVariable(name, "parameter", "parameter", k, spec.unit,
                               spec.description + source, start=values[name],
                               variability="tunable", initial="exact", minimum=spec.minimum,
                               maximum=spec.maximum, nominal=nominal_of(values[name])))
    return out


def nominal_of(value: float) -> float | None:
    """A parameter's nominal value (its magnitude, for an importer's scaling): |value|,
    none for zero."""
    return abs(value) if value != 0.0 and np.isfinite(value) else None


def fmu_drives(model: FmuModel, starts: Mapping[str, float]) -> dict[str, Signal]:
    """The declared inputs the FMU's inputs fill beside the drive (a cylinder's supply
    pressure), each a one-point channel at its start value, which the FMU's input then
    writes: by name, as an experiment drives them."""
    return {entry.declared: Constant(starts[entry.name])
            for entry in model.fmu_interface().inputs if entry.declared}


def input_starts(model: FmuModel, inputs: Mapping[str, float] | None) -> dict[str, float]:
    """The start value of each FMU input: ``inputs`` (checked: a name the FMU has, an
    absolute pressure, a value in the input's range, a finite force), else the model's
    (at rest: atmospheric pressure, command 0, no force)."""
    declared = {entry.name: entry for entry in model.fmu_interface().inputs}
    starts = {name: entry.start for name, entry in declared.items()}
    unknown = sorted(set(inputs or {}) - set(starts))
    if unknown:
        raise ArgumentError(f"export_fmu: inputs = {unknown}: not inputs of this FMU; its "
                            f"inputs are {sorted(starts)}")
    for key, value in (inputs or {}).items():
        starts[key] = checked_start(declared[key], value)
    return starts


def checked_start(entry: FmuInput, value: float) -> float:
    """``value`` as the start of the input ``entry``: an absolute pressure, a value in its
    range, or finite."""
    from ..checks import check_absolute_pressure, check_finite, check_range

    where = "export_fmu inputs"
    if entry.pressure:
        value = check_absolute_pressure(entry.name, value, where=where)
    if entry.minimum is not None and entry.maximum is not None:
        return check_range(entry.name, value, entry.minimum, entry.maximum, where=where)
    return check_finite(entry.name, value, where=where)


def input_variables(model: FmuModel, asm: Assembly, ptr: np.ndarray,
                    starts: Mapping[str, float]) -> list[FmuVariable]:
    """The model's FMU inputs (the drive, the external force, a declared input such as a
    cylinder's supply pressure) on their signal entries (their channels where the
    assembly places them), with their hard ranges and nominal magnitudes
    (``fmu_interface``)."""
    return [FmuVariable(entry.name, "input", "input",
                        int(ptr[asm.channel_index(entry.channel)]) + INPUT_OFFSET,
                        entry.unit, entry.description, start=starts[entry.name],
                        minimum=entry.minimum, maximum=entry.maximum, nominal=entry.nominal)
            for entry in model.fmu_interface().inputs]


def state_variables(asm: Assembly, nominals: np.ndarray, first: int
                    ) -> tuple[list[FmuVariable], list[FmuVariable]]:
    """The states (outputs) and their derivatives (locals); ``first``: the 1-based index
    of the first state."""
    states, derivatives = [], []
    for i, spec in enumerate(asm.states):
        states.append(FmuVariable(spec.name, "output", "state", i, spec.unit,
                                  f"state: {spec.name.replace('_', ' ')}", initial="calculated",
                                  nominal=float(nominals[i])))
        derivatives.append(FmuVariable(f"der({spec.name})", "local", "derivative", i,
                                       rate_unit(spec.unit), f"d{spec.name}/dt",
                                       initial="calculated", derivative=first + i))
    return states, derivatives


def output_variables(asm: Assembly) -> list[FmuVariable]:
    """The kernel's outputs that are not states already."""
    states = set(asm.state_names)
    return [FmuVariable(name, "output", "output", k, unit, f"output: {name.replace('_', ' ')}",
                        initial="calculated")
            for k, (name, unit) in enumerate(zip(asm.output_names, asm.output_units,
                                                 strict=True))
            if name not in states]


def rate_unit(unit: str) -> str:
    if unit in ("", "1"):
        return "1/s"
    return f"{unit}/s"


def all_variables(model: FmuModel, asm: Assembly, kernel: ModuleType, vec: np.ndarray,
                  ptr: np.ndarray, starts: Mapping[str, float]) -> list[FmuVariable]:
    nominals = np.zeros(len(asm.states))
    kernel.state_scales(vec, nominals)
    nominals = np.where(np.isfinite(nominals) & (nominals > 0.0), nominals, 1.0)
    head = parameter_variables(model, asm, vec) + input_variables(model, asm, ptr, starts)
    states, derivatives = state_variables(asm, nominals, first=len(head) + 1)
    return head + states + derivatives + output_variables(asm)


# ------------------------------------------------------------------------------ units
def unit_definitions(variables: list[FmuVariable]) -> list[dict]:
    """FMI UnitDefinitions of the variables' units (exponents of SI base units, by pint)."""
    from ..io.quantities import unit_registry

    ureg = unit_registry()
    out = []
    for unit in sorted({v.unit for v in variables if v.unit}):
        quantity = ureg.Quantity(1.0, "" if unit == "1" else unit).to_base_units()
        base = [(BASE_UNITS[d], _exponent(e)) for d, e in quantity.dimensionality.items()]
        if quantity.magnitude != 1.0:
            base.append(("factor", repr(float(quantity.magnitude))))
        out.append({"name": unit, "base": base})
    return out


def _exponent(value) -> str:
    if float(value) != int(value):
        raise ExportError(f"a unit with the fractional exponent {value} has no FMI BaseUnit")
    return str(int(value))


# ------------------------------------------------------------------------------ files
def glue_source(identifier: str, guid: str, asm: Assembly, variables: list[FmuVariable],
                vec: np.ndarray, sig: np.ndarray, ptr: np.ndarray, guards: tuple[int, int],
                stop_check: tuple[str, ...] | None, kind: str = "me", fmi: int = 2) -> str:
    kinds = {"parameter": 0, "input": 1, "state": 2, "derivative": 3, "output": 4,
             "indicator": 5, "time": 6}
    slot_ptr: list[int] = [0]
    slots: list[int] = []
    for name in asm.parameter_names:
        slots.extend(asm.slots[name])
        slot_ptr.append(len(slots))
    nominals = [v.nominal for v in variables if v.kind == "state"]
    me, cs = KINDS[kind]
    kernel = asm.numba_kernel  # the C back end translates the numba kernel
    solver = Rodas4()
    status_text = ", ".join(_c_string(kernel.STATUS_TEXT.get(code, "unknown status"))
                            for code in range(1, max(kernel.STATUS_TEXT) + 1))
    extra = {"stubs": fmi3_stubs()} if fmi == 3 else {}
    return render("fmu3.c.j2" if fmi == 3 else "fmu.c.j2", identifier=identifier, guid=guid,
                  n_states=len(asm.states), me=me, cs=cs, interfaces=interfaces(kind), **extra,
                  **stop_check_context(asm, variables, stop_check),
                  info_length=kernel.INFO_LENGTH, info_status=kernel.INFO_STATUS,
                  info_h=kernel.INFO_H, info_t=kernel.INFO_T, rtol=repr(solver.rtol),
                  h_init=repr(solver.h_init), max_steps=DEFAULT_MAX_STEPS,
                  status_text=status_text,
                  n_vector=len(vec), n_outputs=len(asm.output_names), n_switches=guards[0],
                  n_events=guards[1],
                  n_sig=len(sig), n_channels=len(ptr), n_variables=len(variables),
                  prm_start=_c_list(vec), sig_start=_c_list(sig),
                  ptr=", ".join(str(int(p)) for p in ptr), nominals=_c_list(nominals),
                  var_kind=", ".join(str(kinds[v.kind]) for v in variables),
                  var_index=", ".join(str(v.index) for v in variables),
                  slot_ptr=", ".join(map(str, slot_ptr)), slots=", ".join(map(str, slots)))


def stop_check_context(asm: Assembly, variables: list[FmuVariable],
                       stop_check: tuple[str, ...] | None) -> dict:
    """What ``templates/stop_check.c.j2`` reads: the position state, the vector slots of
    the model's end-stop parameters (its ``fmu_interface().stop_check``) and the signal
    entry of the external force; ``stop_check`` false where the model has no check."""
    if stop_check is None:
        return {"stop_check": False}
    force = next(v.index for v in variables if v.name == FORCE_INPUT[0])
    return {"stop_check": True, "position_state": asm.state_index("position"),
            "mechanics_slots": ", ".join(str(asm.slots[name][0]) for name in stop_check),
            "force_entry": force, "stop_margin": repr(STOP_MARGIN)}


def fmi3_variables(variables: list[FmuVariable], guards: tuple[int, int]
                   ) -> list[FmuVariable]:
    """FMI 3.0's variables beyond FMI 2.0's (after them: the value references of the others
    stay): the event indicators (FMI 3.0 declares them as variables) and the time."""
    names = [f"end_stop_guard[{k + 1}]" for k in range(guards[0])]
    names += [f"friction_mode_guard[{k + 1}]" for k in range(guards[1])]
    extra = [FmuVariable(name, "local", "indicator", k, "", "event indicator: "
                         + ("an end stop's contact" if k < guards[0] else
                            "a friction block's stick/slip switch"), initial="calculated")
             for k, name in enumerate(names)]
    return [*variables, *extra, FmuVariable("time", "independent", "time", 0, "s",
                                            "simulation time")]


def fmi3_stubs() -> str:
    """C definitions of the FMI 3.0 functions the glue does not implement (clocks, other
    types, serialisation, adjoints, scheduled execution, …), read off FMPy's header: each
    logs that it is not supported and returns fmi3Error (an instance, NULL)."""
    header = (fmi_headers() / "fmi3FunctionTypes.h").read_text()
    out = []
    for ret, name, params in re.findall(r"typedef\s+([\w\s*]+?)\s*\b(fmi3\w+)TYPE\s*\((.*?)\);",
                                        header, re.S):
        if name in FMI3_IMPLEMENTED:
            continue
        params = " ".join(params.split())
        names = [re.sub(r"\[\]$", "", p.split()[-1]).lstrip("*") for p in params.split(",")
                 if p.strip() and p.strip() != "void"]
        ignored = " ".join(f"(void){n};" for n in names)
        if ret.strip() == "fmi3Status":
            first = names[0] if names and "fmi3Instance" in params.split(",")[0] else None
            body = (f"{ignored} log_error((Instance *){first}, \"{name} is not supported\"); "
                    "return fmi3Error;" if first else f"{ignored} return fmi3Error;")
        else:
            body = f"{ignored} return NULL;"
        out.append(f"{ret.strip()} {name}({params}) {{ {body} }}")
    return "\n".join(out)


def interfaces(kind: str) -> str:
    """The FMI interfaces of ``kind``, in words."""
    return {"me": "Model Exchange", "cs": "Co-Simulation",
            "both": "Model Exchange and Co-Simulation"}[kind]


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _c_list(values) -> str:
    return ", ".join(repr(float(v)) if np.isfinite(v) else
                     ("INFINITY" if v > 0 else "(-INFINITY)" if v < 0 else "NAN")
                     for v in values)


def model_description(model: FmuModel, identifier: str, guid: str,
                      variables: list[FmuVariable], indicators: int, kind: str = "me",
                      fmi: int = 2) -> str:
    index = {id(v): i + 1 for i, v in enumerate(variables)}
    outputs = [index[id(v)] for v in variables if v.causality == "output"]
    derivatives = [index[id(v)] for v in variables if v.kind == "derivative"]
    provenance = model.params.provenance.get("source", "") if isinstance(
        model.params.provenance, Mapping) else ""
    description = (f"pneumact {model.describe()}, parameter set '{model.params.name}'"
                   + (f" ({provenance})" if provenance else ""))
    me, cs = KINDS[kind]
    extra = {}
    if fmi == 3:
        extra["event_indicators"] = [index[id(v)] for v in variables if v.kind == "indicator"]
    return render("modelDescription3.xml.j2" if fmi == 3 else "modelDescription.xml.j2",
                  model_name=identifier, guid=guid, me=me, cs=cs, **extra,
                  description=description, version=__version__,
                  date=datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
                  n_indicators=indicators, identifier=identifier, units=unit_definitions(variables),
                  stop_time=STOP_TIME, tolerance=RECOMMENDED_TOLERANCE,
                  step_size=model.fmu_interface().recommended_step if me else CS_STEP,
                  variables=[_xml_fields(v) for v in variables],
                  outputs=outputs, derivatives=derivatives,
                  initial_unknowns=sorted(set(outputs) | set(derivatives)))


def _xml_fields(v: FmuVariable) -> dict:
    fields = dataclasses.asdict(v)
    for key in ("start", "minimum", "maximum", "nominal"):
        if fields[key] is not None:
            fields[key] = repr(float(fields[key]))
    fields["unit"] = v.unit if v.unit not in ("",) else None
    return fields


def render(template: str, **context) -> str:
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader(TEMPLATES, "templates"),
                             autoescape=template.endswith(".xml.j2"),
                             undefined=jinja2.StrictUndefined, keep_trailing_newline=True)
    return env.get_template(template).render(**context)


def identifier_for(path: Path) -> str:
    """The model identifier: the file's stem as a C identifier."""
    stem = re.sub(r"\W", "_", path.stem)
    return stem if stem and not stem[0].isdigit() else f"fmu_{stem}"


# ------------------------------------------------------------------------------ the export
def export_fmu(model, path: str | os.PathLike[str], *,
               inputs: Mapping[str, float] | None = None, binary: bool = True,
               compiler: str | None = None, kind: str = "me", fmi: int = 2) -> ExportedFmu:
    """Write ``model`` as an FMI 2.0 (``fmi=2``) or 3.0 (``fmi=3``) FMU at ``path``.

    ``kind``: ``"me"`` Model Exchange (the importer's solver integrates the equations),
    ``"cs"`` Co-Simulation (the FMU steps itself with pneumact's RODAS4 at pa.simulate's
    tolerance, the inputs held over each communication step) or ``"both"``.

    ``inputs``: start values of the FMU's inputs by name (default: at rest, atmospheric
    pressure, no force). ``binary``: build this platform's binary with the C compiler
    (``compiler``, ``$CC`` or cc/gcc/clang); the C sources are always inside. The file is
    written atomically: a failed export leaves an existing file as it was.
    """
    path = Path(path)
    if kind not in KINDS:
        raise ArgumentError(f"export_fmu: kind = {kind!r}; one of {', '.join(map(repr, KINDS))}"
                            " (Model Exchange, Co-Simulation, both)")
    if fmi not in FMI_VERSIONS:
        raise ArgumentError(f"export_fmu: fmi = {fmi!r}; the FMI versions exported are 2 and 3")
    if path.suffix != ".fmu":
        raise ArgumentError(f"export_fmu: path = {str(path)!r}; an FMU's file name ends in .fmu")
    fmu_model = exportable(model)
    starts = input_starts(fmu_model, inputs)
    if binary:  # before any work: a missing compiler or FMPy's headers fail fast
        compiler = find_compiler(compiler)
        fmi_headers()
    asm = assemble(fmu_model)
    kernel = asm.numba_kernel  # the C back end translates the numba kernel
    vec = asm.pack()
    sig, ptr = pack_channels(fmu_model.channels(Constant(0.0), fmu_drives(fmu_model, starts)))
    variables = all_variables(fmu_model, asm, kernel, vec, ptr, starts)
    for v in variables:
        if v.kind == "input":
            sig[v.index] = v.start
    guards = guard_counts(kernel, vec, sig, ptr, len(asm.states))
    if fmi == 3:
        variables = fmi3_variables(variables, guards)
    # what the FMU calls, the model's run-time C library calls too: typed once
    unit = translate(kernel_roots(kernel, guards[1] > 0, cosimulation=KINDS[kind][1]),
                     share=kernel.__name__)
    identifier = identifier_for(path)
    guid = str(uuid.UUID(hashlib.md5(unit.source.encode() + repr(
        [dataclasses.astuple(v) for v in variables]).encode()).hexdigest()))
    description = model_description(fmu_model, identifier, guid, variables, sum(guards), kind,
                                    fmi)
    files: dict[str, str | bytes] = {"modelDescription.xml": description,
             "sources/model.c": unit.source, "sources/model.h": unit.header,
             "sources/fmu.c": glue_source(identifier, guid, asm, variables, vec, sig, ptr,
                                          guards, fmu_model.fmu_interface().stop_check, kind,
                                          fmi)}
    if fmi == 3:
        files["sources/buildDescription.xml"] = render("buildDescription.xml.j2",
                                                       identifier=identifier)
    platform, used = None, None
    if binary:
        platform = binary_folder() if fmi == 2 else platform_tuple()
        library, used = build(files, identifier, compiler)
        files[f"binaries/{platform}/{identifier}{shared_library_suffix()}"] = library
    write_archive(path, files)
    return ExportedFmu(path, identifier, tuple(variables), platform, used, sum(guards),
                       guards[1], kind, fmi)


def build(files: dict, identifier: str, compiler: str | None) -> tuple[bytes, str]:
    """The binary built from the FMU's sources, and the compiler that built it."""
    with tempfile.TemporaryDirectory(prefix="pneumact-fmu-") as folder:
        root = Path(folder)
        for name in ("sources/model.c", "sources/model.h", "sources/fmu.c"):
            (root / Path(name).name).write_text(files[name])
        output = root / f"{identifier}{shared_library_suffix()}"
        used = build_binary([root / "model.c", root / "fmu.c"], output, compiler)
        return output.read_bytes(), used


def write_archive(path: Path, files: Mapping[str, str | bytes]) -> None:
    with atomic_write(path) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, content in files.items():
            archive.writestr(name, content)
