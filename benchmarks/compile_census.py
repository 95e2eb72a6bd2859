"""A pytest plugin for ``bench_suite.py --census``: every top-level numba compilation of
the run, with the test that caused it, one JSON line each in
``$PNEUMACT_CENSUS_DIR/<worker>.jsonl`` (what the suite's cold minutes are spent on)."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

from numba.core import event

_started: list[float] = []


class _TopLevelCompiles(event.Listener):
    """Records compilations that are not nested in another (their time includes the
    functions they compile on the way)."""

    def __init__(self, path: Path):
        self.path = path

    def on_start(self, ev):
        _started.append(time.perf_counter())

    def on_end(self, ev):
        seconds = time.perf_counter() - _started.pop()
        if _started:
            return
        function = getattr(ev.data.get("dispatcher"), "py_func", None)
        row = {"test": os.environ.get("PYTEST_CURRENT_TEST", "?").rsplit(" ", 1)[0],
               "module": getattr(function, "__module__", "?"),
               "function": getattr(function, "__qualname__", "?"), "seconds": seconds}
        with open(self.path, "a", encoding="utf-8") as out:
            out.write(json.dumps(row) + "\n")


def pytest_configure(config):
    folder = os.environ.get("PNEUMACT_CENSUS_DIR")
    if folder:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        event.register("numba:compile", _TopLevelCompiles(Path(folder) / f"{worker}.jsonl"))
