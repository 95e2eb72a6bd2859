"""Ctrl-C reaches work in other threads and processes (issue 42): a fit's starts and a
comparison's laws sent to a Dask cluster are cancelled there when the client is
interrupted, so that the workers do not go on with what had not begun (the stop flag is
per process); the command line does not wait for a thread busy in compiled code."""

from __future__ import annotations

import importlib
import threading
import time

import pytest

import pneumact.progress as progress
import pneumact.simulation.batch.engine as engine
from pneumact.options import Executor, Optimizer
from pneumact.validation import compare

#: the module (``pneumact.identification.fit`` is also the function's name in the package)
fit_module = importlib.import_module("pneumact.identification.fit")


class _InterruptedClient:
    """A Dask client whose gather is interrupted by Ctrl-C; it records what is cancelled."""

    def __init__(self) -> None:
        self.cancelled: list = []

    def submit(self, *args, **kwargs):  # an Executor's scheduler must have submit
        raise AssertionError("not used")

    def map(self, function, *iterables, pure=False):
        return [f"future-{k}" for k in range(len(iterables[0]))]

    def gather(self, futures):
        raise KeyboardInterrupt

    def cancel(self, futures) -> None:
        self.cancelled.extend(futures)


@pytest.fixture
def client(monkeypatch) -> _InterruptedClient:
    fake = _InterruptedClient()
    monkeypatch.setattr(engine, "dask_client", lambda scheduler: (fake, False))
    return fake


def test_an_interrupted_multistart_cancels_its_starts_on_the_cluster(client):
    with pytest.raises(KeyboardInterrupt):
        fit_module._run_starts(object(), [1.0, 2.0, 3.0], 0.0, 1.0, Optimizer(),
                               Executor(scheduler=client), None)
    assert client.cancelled == ["future-0", "future-1", "future-2"]


def test_an_interrupted_comparison_cancels_its_laws_on_the_cluster(client):
    with pytest.raises(KeyboardInterrupt):
        compare._run([("job-a",), ("job-b",)], Executor(scheduler=client), None)
    assert client.cancelled == ["future-0", "future-1"]


def _stopped(error: BaseException, release: threading.Event) -> float:
    """Seconds ``stop_threads`` takes to let ``error`` go on while its pool's one thread
    is busy (as in a kernel's compilation) until ``release`` is set."""
    from concurrent.futures import ThreadPoolExecutor

    started = threading.Event()

    def busy() -> None:
        started.set()
        release.wait(10.0)

    tic = time.perf_counter()
    with pytest.raises(type(error)), progress.stop_threads(ThreadPoolExecutor(1)) as pool:
        pool.submit(busy)
        started.wait(10.0)
        tic = time.perf_counter()
        raise error
    return time.perf_counter() - tic


def test_the_command_line_leaves_a_busy_thread_on_ctrl_c_and_waits_after_a_failure(
        monkeypatch):
    """A thread compiling a kernel held `compare`'s Ctrl-C for 112 s; a failure instead
    must wait, since the caller may go on (a stop request left raised would stop it)."""
    monkeypatch.setattr(progress, "_stop_requests", 0)
    monkeypatch.setattr(progress, "_leave_after_grace", True)
    release = threading.Event()
    try:
        seconds = _stopped(KeyboardInterrupt(), release)
        assert seconds < progress.STOP_GRACE_S + 1.0
        assert progress.stop_requested()  # the thread left behind is still asked to stop
    finally:
        release.set()
    monkeypatch.setattr(progress, "_stop_requests", 0)
    release = threading.Event()
    threading.Timer(1.5 * progress.STOP_GRACE_S, release.set).start()
    assert _stopped(ValueError("a failure"), release) >= 1.4 * progress.STOP_GRACE_S
    assert not progress.stop_requested()
