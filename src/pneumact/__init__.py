"""pneumact: pneumatic diaphragm actuators with dynamic friction.

    import pneumact as pa
    params = pa.load_params("vgt-paper")
    actuator = pa.Actuator(params, friction=pa.LuGre(), valve=pa.PressureSource())
    result = pa.simulate(actuator, pa.experiments.PressureCycle(high=100e3, low=20e3))
    result.to_pandas(); result.save("run.csv"); result.plot_hysteresis()
"""

from . import experiments
from .batch import BatchResult, simulate_batch
from .errors import (
    DataError,
    ExperimentError,
    ParameterError,
    PassivityWarning,
    PneumactError,
    SolverError,
)
from .experiments import CommandCycle, Experiment, PressureCycle
from .models import (
    Actuator,
    Adiabatic,
    BoucWen,
    CommandValve,
    CoulombViscous,
    Dahl,
    FrictionRig,
    Isothermal,
    LuGre,
    Polytropic,
    PressureRegulator,
    PressureSource,
    StribeckMap,
)
from .parameters import ParameterSet, available_params, load_params
from .simulation import DormandPrince, Result, Rodas4, simulate
from .simulation.sensitivity import SensitivityResult, simulate_sensitivities

__version__ = "0.1.0"

__all__ = [
    "Actuator",
    "Adiabatic",
    "BatchResult",
    "BoucWen",
    "CommandCycle",
    "CommandValve",
    "CoulombViscous",
    "Dahl",
    "DataError",
    "DormandPrince",
    "Experiment",
    "ExperimentError",
    "FrictionRig",
    "Isothermal",
    "LuGre",
    "ParameterError",
    "ParameterSet",
    "PassivityWarning",
    "PneumactError",
    "Polytropic",
    "PressureCycle",
    "PressureRegulator",
    "PressureSource",
    "Result",
    "Rodas4",
    "SensitivityResult",
    "SolverError",
    "StribeckMap",
    "available_params",
    "experiments",
    "load_params",
    "simulate",
    "simulate_batch",
    "simulate_sensitivities",
]
