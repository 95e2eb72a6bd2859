"""Closed-loop position control: controllers as components of the compiled loop,
friction compensation, set-point experiments, loop metrics and the linearised plant."""

from .controllers import PID, Cascade, Controller, Dither, LuGreObserver, StaticCompensation
from .loop import ClosedLoop

__all__ = ["PID", "Cascade", "ClosedLoop", "Controller", "Dither", "LuGreObserver",
           "StaticCompensation"]
