"""Simulation: the model assembly, its compiled kernel, the solvers and the entry points.

``simulate`` runs one model under one experiment; ``simulate_sensitivities`` carries
forward parameter sensitivities along; ``simulate_batch`` (``simulation.batch``) runs
many parameter sets on all cores or a Dask cluster.
"""

from ..core.assembly import Assembly, assemble, explain_unknown_names
from ..parameters.catalogue import explain_unknown
from .forward_sensitivity import SensitivityResult, simulate_sensitivities
from .result import Result, SolverStats
from .simulate import simulate
from .solvers import DormandPrince, Rodas4, Solver

__all__ = ["Assembly", "DormandPrince", "Result", "Rodas4", "SensitivityResult", "Solver",
           "SolverStats", "assemble", "simulate", "simulate_sensitivities"]

# an assembly's refusal of an unknown name says what the catalogue knows of it (a renamed
# name's new one, the instances): core sits below the catalogue, so it is told here
explain_unknown_names(explain_unknown)
