"""One progress report for every long computation of pneumact.

Each public function that takes ``progress=`` calls it with a ``Progress``: what stage
is running, how much of it is done out of how much, and how many items failed so far.
A simulation reports the simulated fraction (``done`` of ``total`` = 1), a batch the sets
done of all sets, a fit each multistart start or profile point, a validation the records,
a reproduction each step. The command line draws its progress bars from these reports in
one place (``pneumact.cli.common``).

A base module (it imports only ``pneumact.errors``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .errors import ArgumentTypeError

__all__ = ["Progress", "ProgressCallback", "check_progress", "notify"]


@dataclass(frozen=True)
class Progress:
    """A progress report: ``done`` of ``total`` units of ``stage`` (a fraction when
    ``total`` is 1), ``failed`` of them failed (a batch's sets that did not run)."""

    stage: str
    done: float
    total: float = 1.0
    failed: int = 0

    @property
    def fraction(self) -> float:
        """``done / total`` in [0, 1] (1 for an empty stage)."""
        if self.total <= 0:
            return 1.0
        return min(1.0, max(0.0, self.done / self.total))


#: what ``progress=`` takes: a function called with each ``Progress`` report
ProgressCallback = Callable[[Progress], None]


def check_progress(progress: object, where: str) -> ProgressCallback | None:
    """``progress`` itself if it is None or callable; else an ``ArgumentTypeError`` naming
    ``where``."""
    if progress is not None and not callable(progress):
        raise ArgumentTypeError(f"{where}: progress = {progress!r}: must be a function "
                        "progress(report) taking a pneumact.progress.Progress")
    return progress


def notify(progress: ProgressCallback | None, stage: str, done: float, total: float = 1.0,
           failed: int = 0) -> None:
    """Call ``progress`` (when given) with ``Progress(stage, done, total, failed)``."""
    if progress is not None:
        progress(Progress(stage, float(done), float(total), int(failed)))
