"""Exports of a model to the tools engineers put it in: an FMI 2.0 Model Exchange FMU
(Simulink, Dymola, OpenModelica, GT-SUITE and any FMI importer)."""

from .compiler import find_compiler
from .fmu import ExportedFmu, FmuVariable, export_fmu

__all__ = ["ExportedFmu", "FmuVariable", "export_fmu", "find_compiler"]
