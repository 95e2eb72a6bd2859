"""Parameter sets as data: shipped TOML files with units and provenance, loaded into SI.

Typical use: ``params = load_params("vgt-paper")`` (or a path to a .toml file), then
``params["V0"]`` is 6e-05 (m^3, written "60 cm^3" in the file), ``params.require(names,
"Actuator")`` checks what a model needs, ``params.vector()`` feeds the kernels.
"""

from pneumact.parameters.loader import (
    ParameterInfo,
    ParameterSet,
    available_params,
    load_params,
    lugre_passivity_problem,
    validate,
)
from pneumact.parameters.spec import I_POLYTROPIC, INDEX, PARAMETERS, SPECS, VECTOR_LENGTH

__all__ = [
    "INDEX",
    "I_POLYTROPIC",
    "PARAMETERS",
    "SPECS",
    "VECTOR_LENGTH",
    "ParameterInfo",
    "ParameterSet",
    "available_params",
    "load_params",
    "lugre_passivity_problem",
    "validate",
]
