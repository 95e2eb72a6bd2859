"""Exceptions raised for a user's mistake or a failed computation.

Every message names the field, the value and what is allowed, so the CLI can print it
as one line instead of a traceback.
"""


class PneumactError(Exception):
    """Base class of every error pneumact raises on purpose."""


class ParameterError(PneumactError, ValueError):
    """A parameter set is incomplete, misspelled, in the wrong unit or inconsistent."""


class DataError(PneumactError, ValueError):
    """A measured record or an input file is malformed (missing column, NaN, bad time)."""


class ExperimentError(PneumactError, ValueError):
    """An experiment does not fit the actuator it is applied to, or its signal is invalid."""


class SolverError(PneumactError, RuntimeError):
    """The integrator failed (step size underflow, non-finite state)."""


class PassivityWarning(UserWarning):
    """The parameters break a known sufficient condition for a passive LuGre model."""
