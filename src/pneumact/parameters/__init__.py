"""Parameter sets as data: shipped TOML files with units and provenance, loaded into SI.

Typical use: ``params = load_params("vgt-paper")`` (or a path to a .toml file), then
``params["V0"]`` is 6e-05 (m^3, written "60 cm^3" in the file). Each component declares
the parameters it reads (``catalogue()`` lists them with unit, meaning and range); a
model assembly lays out the ones its components need.
"""

from pneumact.io.quantities import parse_value, unit_registry
from pneumact.parameters.catalogue import ParameterSpec, catalogue, declare, declare_relation
from pneumact.parameters.files import (
    as_parameter_set,
    available_params,
    load_params,
    params_to_toml,
    write_params,
)
from pneumact.parameters.parameter_set import ParameterInfo, ParameterSet
from pneumact.parameters.validation import (
    lugre_passivity_problem,
    row_problems,
    validate,
)

__all__ = [
    "ParameterInfo",
    "ParameterSet",
    "ParameterSpec",
    "as_parameter_set",
    "available_params",
    "catalogue",
    "declare",
    "declare_relation",
    "load_params",
    "lugre_passivity_problem",
    "params_to_toml",
    "parse_value",
    "row_problems",
    "unit_registry",
    "validate",
    "write_params",
]
