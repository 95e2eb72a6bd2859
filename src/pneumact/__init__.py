"""pneumact: pneumatic diaphragm actuators with dynamic friction.

    import pneumact as pa
    params = pa.load_params("vgt-paper")
    actuator = pa.Actuator(params, friction=pa.LuGre(), valve=pa.PressureSource())
    result = pa.simulate(actuator, pa.PressureCycle(high=100e3, low=20e3))
    result.to_pandas(); result.save("run.csv"); result.plot_hysteresis()

Names are imported on first use (PEP 562), so ``import pneumact`` is quick and a
command pays only for what it needs.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from .version import __version__ as __version__

#: public name -> module that defines it
_EXPORTS: dict[str, str] = {
    "experiments": "pneumact.experiments",
    "Experiment": "pneumact.experiments",
    "PressureCycle": "pneumact.experiments",
    "CommandCycle": "pneumact.experiments",
    "Actuator": "pneumact.models",
    "Adiabatic": "pneumact.models",
    "HeatTransfer": "pneumact.models",
    "BoucWen": "pneumact.models",
    "CommandValve": "pneumact.models",
    "CoulombViscous": "pneumact.models",
    "Cylinder": "pneumact.models",
    "Dahl": "pneumact.models",
    "ElastoPlastic": "pneumact.models",
    "GMS": "pneumact.models",
    "FrictionRig": "pneumact.models",
    "Isothermal": "pneumact.models",
    "LuGre": "pneumact.models",
    "Polytropic": "pneumact.models",
    "PressureRegulator": "pneumact.models",
    "Iso6358Valve": "pneumact.models",
    "PressureSource": "pneumact.models",
    "StribeckMap": "pneumact.models",
    "ParameterSet": "pneumact.parameters",
    "available_params": "pneumact.parameters",
    "load_params": "pneumact.parameters",
    "write_params": "pneumact.parameters",
    "Assembly": "pneumact.simulation",
    "Checkpoint": "pneumact.options",
    "Executor": "pneumact.options",
    "DormandPrince": "pneumact.simulation",
    "Result": "pneumact.simulation",
    "Rodas4": "pneumact.simulation",
    "SensitivityResult": "pneumact.simulation",
    "simulate": "pneumact.simulation",
    "simulate_sensitivities": "pneumact.simulation",
    "BatchResult": "pneumact.simulation.batch",
    "simulate_batch": "pneumact.simulation.batch",
    "fit": "pneumact.identification",
    "compare_friction_models": "pneumact.validation",
    "FrictionComparison": "pneumact.validation",
    "friction_rig_for": "pneumact.validation",
    "export_fmu": "pneumact.export",
    "ExportError": "pneumact.errors",
    "Bounds": "pneumact.options",
    "Multistart": "pneumact.options",
    "Offsets": "pneumact.options",
    "Optimizer": "pneumact.options",
    "Profile": "pneumact.options",
    "Weights": "pneumact.options",
    "identify_paper": "pneumact.identification",
    "identify_signature": "pneumact.identification",
    "inverse_friction": "pneumact.identification",
    "synthetic_campaign": "pneumact.identification",
    "validate": "pneumact.validation",
    "train_test": "pneumact.validation",
    "reproduce": "pneumact.reproduction",
    "Record": "pneumact.io",
    "read_record": "pneumact.io",
    "read_records": "pneumact.io",
    "control": "pneumact.control",
    "ClosedLoop": "pneumact.control",
    "PID": "pneumact.control",
    "Cascade": "pneumact.control",
    "SetpointStep": "pneumact.experiments",
    "SetpointRamp": "pneumact.experiments",
    "SetpointProfile": "pneumact.experiments",
    "ArgumentError": "pneumact.errors",
    "ArgumentTypeError": "pneumact.errors",
    "ComponentError": "pneumact.errors",
    "DataError": "pneumact.errors",
    "EngineWarning": "pneumact.errors",
    "ExperimentError": "pneumact.errors",
    "ParameterError": "pneumact.errors",
    "PassivityWarning": "pneumact.errors",
    "PlausibilityWarning": "pneumact.errors",
    "ResourceError": "pneumact.errors",
    "PneumactError": "pneumact.errors",
    "SolverError": "pneumact.errors",
}

__all__ = [
    "GMS",
    "PID",
    "Actuator",
    "Adiabatic",
    "ArgumentError",
    "ArgumentTypeError",
    "Assembly",
    "BatchResult",
    "BoucWen",
    "Bounds",
    "Cascade",
    "Checkpoint",
    "ClosedLoop",
    "CommandCycle",
    "CommandValve",
    "ComponentError",
    "CoulombViscous",
    "Cylinder",
    "Dahl",
    "DataError",
    "DormandPrince",
    "ElastoPlastic",
    "EngineWarning",
    "Executor",
    "Experiment",
    "ExperimentError",
    "ExportError",
    "FrictionComparison",
    "FrictionRig",
    "HeatTransfer",
    "Iso6358Valve",
    "Isothermal",
    "LuGre",
    "Multistart",
    "Offsets",
    "Optimizer",
    "ParameterError",
    "ParameterSet",
    "PassivityWarning",
    "PlausibilityWarning",
    "PneumactError",
    "Polytropic",
    "PressureCycle",
    "PressureRegulator",
    "PressureSource",
    "Profile",
    "Record",
    "ResourceError",
    "Result",
    "Rodas4",
    "SensitivityResult",
    "SetpointProfile",
    "SetpointRamp",
    "SetpointStep",
    "SolverError",
    "StribeckMap",
    "Weights",
    "available_params",
    "compare_friction_models",
    "control",
    "experiments",
    "export_fmu",
    "fit",
    "friction_rig_for",
    "identify_paper",
    "identify_signature",
    "inverse_friction",
    "load_params",
    "read_record",
    "read_records",
    "reproduce",
    "simulate",
    "simulate_batch",
    "simulate_sensitivities",
    "synthetic_campaign",
    "train_test",
    "validate",
    "write_params",
]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'pneumact' has no attribute {name!r}")
    value = importlib.import_module(module)
    if name != module.rpartition(".")[2]:
        value = getattr(value, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs
    from pneumact import control, experiments
    from pneumact.control import PID, Cascade, ClosedLoop
    from pneumact.errors import (
        ArgumentError,
        ArgumentTypeError,
        DataError,
        EngineWarning,
        ExperimentError,
        ExportError,
        ParameterError,
        PassivityWarning,
        PlausibilityWarning,
        PneumactError,
        ResourceError,
        SolverError,
    )
    from pneumact.experiments import (
        CommandCycle,
        Experiment,
        PressureCycle,
        SetpointProfile,
        SetpointRamp,
        SetpointStep,
    )
    from pneumact.export import export_fmu
    from pneumact.identification import (
        fit,
        identify_paper,
        identify_signature,
        inverse_friction,
        synthetic_campaign,
    )
    from pneumact.io import Record, read_record, read_records
    from pneumact.models import (
        GMS,
        Actuator,
        Adiabatic,
        BoucWen,
        CommandValve,
        CoulombViscous,
        Cylinder,
        Dahl,
        ElastoPlastic,
        FrictionRig,
        HeatTransfer,
        Iso6358Valve,
        Isothermal,
        LuGre,
        Polytropic,
        PressureRegulator,
        PressureSource,
        StribeckMap,
    )
    from pneumact.options import (
        Bounds,
        Checkpoint,
        Executor,
        Multistart,
        Offsets,
        Optimizer,
        Profile,
        Weights,
    )
    from pneumact.parameters import ParameterSet, available_params, load_params, write_params
    from pneumact.reproduction import reproduce
    from pneumact.simulation import (
        Assembly,
        DormandPrince,
        Result,
        Rodas4,
        SensitivityResult,
        simulate,
        simulate_sensitivities,
    )
    from pneumact.simulation.batch import BatchResult, simulate_batch
    from pneumact.validation import (
        FrictionComparison,
        compare_friction_models,
        friction_rig_for,
        train_test,
        validate,
    )
