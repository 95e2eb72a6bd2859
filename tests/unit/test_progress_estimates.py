"""Progress bars' time left from the rate measured in this session, and an estimate
once the first chunk is done (issue 42, finding 8: "left 0:00:55" at 500 of 100 000 rows
when hours remained)."""

from __future__ import annotations

import itertools
import time

import pytest

from pneumact.cli.common import progress_display, remaining_time
from pneumact.progress import Progress


def test_remaining_time_is_items_over_the_rate():
    assert remaining_time(99_500, 10.0) == "2:45:50"
    assert remaining_time(10, 0.0) == "-:--:--"


def test_reused_items_are_not_speed_and_the_first_chunk_gives_an_estimate(estimates_log,
                                                                          monkeypatch):
    clock = itertools.count(0.0, 1.0)  # each reading one second later
    monkeypatch.setattr(time, "perf_counter", lambda: next(clock))
    with progress_display("batch", counts=True) as update:
        update(Progress("batch", 50_000, 100_000))  # resumed: half reused at once
        update(Progress("batch", 50_001, 100_000))  # the first chunk (and compiling)
        update(Progress("batch", 50_006, 100_000))  # a burst of chunks 1 s after it
        assert not estimates_log  # not a rate yet
        update(Progress("batch", 50_011, 100_000))  # 10 sets in the 2 s after it
    # 5 sims/s, 49 989 left: 2.8 h, not the seconds the reused half implies
    assert any("about 2:46:38" in note for note in estimates_log), estimates_log


def test_a_big_sobol_sample_is_announced_before_it_is_drawn(estimates_log, monkeypatch):
    """sobol --n 1048576 drew its sample for a minute behind a silent "0/?" bar."""
    import numpy as np

    from pneumact.sensitivity import methods
    from pneumact.sensitivity.problem import Factor, Problem

    problem = Problem((Factor("a", 1.0, 2.0, 1.5), Factor("b", 0.5, 1.5, 1.0)))
    drawn: list[int] = []

    def evaluate(values: np.ndarray) -> np.ndarray:
        drawn.append(len(estimates_log))  # the notes logged before the first run
        return values[:, 0] + values[:, 1] ** 2

    methods.sobol(problem, evaluate, n=64, resamples=2)
    assert drawn == [0] and not estimates_log  # 256 runs: nothing to announce
    monkeypatch.setattr(methods, "ANNOUNCED_SAMPLE_RUNS", 256)
    methods.sobol(problem, evaluate, n=64, resamples=2)
    assert drawn[-1] == 1, estimates_log
    assert "drawing the sample first: 256 runs x 2 parameters" in estimates_log[0]


def test_a_sobol_sample_past_the_memory_limit_is_refused_before_it_is_drawn(monkeypatch):
    """sobol's sample was announced but its memory never checked against the limit
    (issue 42, item 3): refused before any draw, naming the sizes and the limit."""
    import numpy as np

    import pneumact as pa
    from pneumact.sensitivity import methods
    from pneumact.sensitivity.problem import Factor, Problem

    problem = Problem((Factor("a", 1.0, 2.0, 1.5), Factor("b", 0.5, 1.5, 1.0)))
    runs: list[int] = []

    def evaluate(values: np.ndarray) -> np.ndarray:
        runs.append(len(values))
        return values[:, 0]

    monkeypatch.setenv("PNEUMACT_MEMORY_LIMIT", "1MiB")
    with pytest.raises(pa.ResourceError, match=r"65 536 runs x 2 parameters .*limit of 1 MiB"):
        methods.sobol(problem, evaluate, n=16384, resamples=2)
    assert runs == []
    methods.sobol(problem, evaluate, n=64, resamples=2)  # 256 runs: 8 KiB
    assert runs == [256]
