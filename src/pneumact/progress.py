"""One progress report for every long computation of pneumact.

Each public function that takes ``progress=`` calls it with a ``Progress``: what stage
is running, how much of it is done out of how much, and how many items failed so far.
A simulation reports the simulated fraction (``done`` of ``total`` = 1), a batch the sets
done of all sets, a fit each multistart start or profile point, a validation the records,
a reproduction each step. The command line draws its progress bars from these reports in
one place (``pneumact.cli.common``).

Ctrl-C stops long work within a simulation: the main thread receives the interrupt,
``stop_threads`` asks the pool's threads to stop (each simulation starts with
``raise_if_stopped``), cancels the starts not begun and waits for the running ones, which
end at their next simulation. A process that exits right after the stop (the command
line: ``leave_stopped_work``) waits for them at most ``STOP_GRACE_S`` and then leaves them:
a thread compiling a kernel cannot be interrupted from Python and would hold the exit
for a minute.

A base module (it imports only ``pneumact.errors``).
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Executor as FuturesExecutor
from dataclasses import dataclass

from .errors import ArgumentTypeError

__all__ = ["Progress", "ProgressCallback", "check_progress", "leave_stopped_work", "notify",
           "raise_if_stopped", "stop_requested", "stop_threads"]


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


# ----------------------------------------------------------------------- stopping work
_stop_lock = threading.Lock()
_stop_requests = 0  # > 0 while a pool is being stopped (nested pools count each)
#: seconds a stopped pool's running work may take to end when the process exits after it
STOP_GRACE_S = 1.0
_leave_after_grace = False


def leave_stopped_work(leave: bool = True) -> None:
    """Whether a pool stopped by Ctrl-C waits for its running work at most
    ``STOP_GRACE_S`` and then leaves it running (True: for a process that exits right
    after, as the command line does; its stop request then stays, so that nothing more
    starts) or waits until it ends (False, the default: a notebook gets its threads back
    idle). A pool stopped by a failure always waits."""
    global _leave_after_grace
    _leave_after_grace = leave


def _joined(pool: FuturesExecutor, seconds: float) -> bool:
    """Whether every thread of ``pool`` ended within ``seconds``."""
    deadline = time.monotonic() + seconds
    for thread in list(getattr(pool, "_threads", ())):
        thread.join(max(0.0, deadline - time.monotonic()))
        if thread.is_alive():
            return False
    return True


def stop_requested() -> bool:
    """Whether long work was asked to stop (Ctrl-C, or a failure beside it)."""
    return _stop_requests > 0


def raise_if_stopped() -> None:
    """Raise ``KeyboardInterrupt`` when long work was asked to stop: called before each
    simulation, so that the threads of a pool end at their next one."""
    if _stop_requests > 0:
        raise KeyboardInterrupt


@contextlib.contextmanager
def stop_threads(pool: FuturesExecutor) -> Iterator[FuturesExecutor]:
    """Shut ``pool`` down on leaving; when the block raises (Ctrl-C in the main thread,
    or a failure), first ask its threads to stop, cancel what has not begun and wait for
    the running work (one simulation at most) before the exception goes on."""
    global _stop_requests
    try:
        yield pool
    except BaseException as stopping:
        with _stop_lock:
            _stop_requests += 1
        left_running = False
        try:  # only a Ctrl-C leaves work running: after a failure the caller may go on
            leave = (_leave_after_grace and isinstance(stopping, KeyboardInterrupt)
                     and hasattr(pool, "_threads"))
            pool.shutdown(wait=not leave, cancel_futures=True)
            left_running = leave and not _joined(pool, STOP_GRACE_S)
        finally:
            if not left_running:
                with _stop_lock:
                    _stop_requests -= 1
        raise
    pool.shutdown(wait=True)
