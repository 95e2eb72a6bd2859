"""Simulation: the compiled kernels, the solvers and the one ``simulate`` entry point."""

from .result import Result
from .simulate import simulate
from .solvers import DormandPrince, Rodas4, Solver

__all__ = ["DormandPrince", "Result", "Rodas4", "Solver", "simulate"]
