"""Exceptions raised for a user's mistake or a failed computation, and pneumact's warnings.

Every message names the field, the value and what is allowed, so the CLI can print it
as one line instead of a traceback. A message may carry a hint that only makes sense
from Python (``api_hint``: "pass names=[...]") or only on the command line
(``cli_hint``: "give --window t0,t1"): ``str(error)`` shows the API's, ``for_cli()`` the
command line's.
"""

from __future__ import annotations


class PneumactError(Exception):
    """Base class of every error pneumact raises on purpose."""

    def __init__(self, message: str = "", *, api_hint: str | None = None,
                 cli_hint: str | None = None) -> None:
        super().__init__(message)
        self.api_hint = api_hint
        self.cli_hint = cli_hint

    @property
    def message(self) -> str:
        """The message without either hint."""
        return super().__str__()

    def __str__(self) -> str:
        return self.message + (f"; {self.api_hint}" if self.api_hint else "")

    def for_cli(self) -> str:
        """The message as the command line shows it (with its hint, not the API's)."""
        return self.message + (f"; {self.cli_hint}" if self.cli_hint else "")


class ParameterError(PneumactError, ValueError):
    """A parameter set is incomplete, misspelled, in the wrong unit or inconsistent."""


class DataError(PneumactError, ValueError):
    """A measured record or an input file is malformed (missing column, NaN, bad time)."""


class ExperimentError(PneumactError, ValueError):
    """An experiment does not fit the actuator it is applied to, or its signal is invalid."""


class ArgumentError(PneumactError, ValueError):
    """An argument of a function (or an option of a command) is outside what it allows:
    a negative count, an unknown choice, options that contradict each other."""


class ArgumentTypeError(ArgumentError, TypeError):
    """An argument has the wrong type; the message says which type was expected."""


class ComponentError(PneumactError, ValueError):
    """A model's components do not fit together: two claim one role, or bind one kernel
    function or constant name (the message names both components and the clash)."""


class SolverError(PneumactError, RuntimeError):
    """The integrator failed (step size underflow, non-finite state)."""


class ExportError(PneumactError, RuntimeError):
    """A model could not be exported (no C compiler, a failed build, a model the export
    does not cover); the message says what to install or change."""


class ResourceError(PneumactError, MemoryError):
    """A run would need more memory (or disk) than the machine has; nothing was started."""


class PassivityWarning(UserWarning):
    """The parameters break a known sufficient condition for a passive LuGre model.

    Shown once per process and parameter set (``params show``/``check`` and the reports
    always say it); silence it with
    ``warnings.filterwarnings("ignore", category=pneumact.PassivityWarning)``.
    """


class PlausibilityWarning(UserWarning):
    """A value is legal but outside the range real actuators and rigs have (a parameter
    a thousand times off, an atmosphere of 30 kPa): often a unit typed wrong. If the
    value is meant, silence it with
    ``warnings.filterwarnings("ignore", category=pneumact.PlausibilityWarning)``."""


class EngineWarning(UserWarning):
    """The C engine was asked for (``auto``, the default) but cannot run this model here,
    so the numba engine runs it; the message says why (no C compiler, a construct the C
    back end does not translate, a failed build). Silence it with
    ``PNEUMACT_ENGINE=numba`` or ``warnings.filterwarnings("ignore",
    category=pneumact.EngineWarning)``."""
