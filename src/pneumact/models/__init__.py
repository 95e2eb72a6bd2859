"""Models: friction laws, chamber and valves, the assembled actuator, the double-acting
cylinder and the test rig."""

from .actuator import Actuator
from .cylinder import Cylinder
from .friction import (
    GMS,
    BoucWen,
    CoulombViscous,
    Dahl,
    ElastoPlastic,
    FrictionModel,
    LuGre,
    StribeckMap,
    friction_law,
    friction_models,
)
from .inputs import DECLARED_INPUTS, INPUT_SIGNALS, input_signal, valve_for_signal
from .pneumatics import (
    Adiabatic,
    ChamberLaw,
    HeatTransfer,
    Isothermal,
    Polytropic,
    conductance_of_area,
    flow_function_values,
    iso6358_mass_flow,
    orifice_mass_flow,
)
from .rig import FrictionRig
from .valves import (
    VALVES,
    CommandValve,
    Iso6358Valve,
    PressureRegulator,
    PressureSource,
    Valve,
)

__all__ = [
    "DECLARED_INPUTS", "GMS", "INPUT_SIGNALS", "VALVES", "Actuator", "Adiabatic", "BoucWen",
    "ChamberLaw", "CommandValve", "CoulombViscous", "Cylinder", "Dahl", "ElastoPlastic",
    "FrictionModel", "FrictionRig", "HeatTransfer", "Iso6358Valve", "Isothermal", "LuGre",
    "Polytropic", "PressureRegulator", "PressureSource", "StribeckMap", "Valve",
    "conductance_of_area", "flow_function_values", "friction_law", "friction_models",
    "input_signal", "iso6358_mass_flow", "orifice_mass_flow", "valve_for_signal"
]
