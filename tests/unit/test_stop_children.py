"""Ctrl-C reaches work in other processes (issue 42): a fit's starts and a comparison's
laws sent to a Dask cluster are cancelled there when the client is interrupted, so that
the workers do not go on with what had not begun (the stop flag is per process)."""

from __future__ import annotations

import importlib

import pytest

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
