"""Parts of the reproduction on known answers: Sobol's sample size chosen by the
convergence check (and each doubling runs only the new runs), fitted friction lines
drawn per direction (never through v = 0), the jobs run in a worker process beside the
sections (the same results as run here, errors raised here)."""

from __future__ import annotations

import math
import operator

import matplotlib
import numpy as np
import pandas as pd
import pytest

import reference as ref
from pneumact.identification import Estimates, StageResult
from pneumact.reproduction import (
    SOBOL_TARGET_WIDTH,
    _Beside,
    sobol_by_convergence,
    sobol_converged,
)
from pneumact.sensitivity.problem import Factor, Problem


class _Counting:
    """y = Σ a_i·x_i (x_i uniform on [0, 1]), counting the runs it is asked for."""

    def __init__(self, weights) -> None:
        self.weights = np.asarray(weights, float)
        self.runs = 0

    def __call__(self, values: np.ndarray) -> pd.DataFrame:
        self.runs += len(values)
        return pd.DataFrame({"y": values @ self.weights})


def _problem(k: int) -> Problem:
    return Problem(tuple(Factor(f"x{i}", 0.0, 1.0, 0.5) for i in range(k)))


def test_sobol_stops_at_the_first_size_that_orders_the_inputs():
    """Inputs of clearly unequal weight: the check stops before the cap, at the first n
    whose ST intervals stand apart (the previous n's did not), and the doublings ran
    each run once."""
    evaluate = _Counting(ref.CONVERGENCE_WEIGHTS)
    study, table = sobol_by_convergence(_problem(3), evaluate, 8, ref.CONVERGENCE_N_CAP)
    n = int(table["n"].max())
    assert n == ref.CONVERGENCE_N_ORDERED
    assert sobol_converged(table)
    assert not sobol_converged(table[table["n"] < n])
    assert evaluate.runs == n * (3 + 2) == len(study.sample)


def test_sobol_is_converged_by_narrow_intervals_alone():
    """Two inputs that tie (their order cannot settle) with intervals within the target:
    converged by the width alone."""
    table = pd.DataFrame({"output": "y", "parameter": ["a", "b"], "n": 64,
                          "ST": [0.5, 0.5], "ST_width": [0.5 * SOBOL_TARGET_WIDTH] * 2})
    assert sobol_converged(table)
    assert not sobol_converged(table.assign(ST_width=2 * SOBOL_TARGET_WIDTH))


def test_sobol_stops_at_the_cap_when_the_intervals_stay_wide():
    """Equal inputs with a small cap: the intervals never narrow to the target, the check
    stops at the cap, and its table says so (widest interval above the target)."""
    evaluate = _Counting(np.ones(6))
    _, table = sobol_by_convergence(_problem(6), evaluate, 8, 16)
    assert int(table["n"].max()) == 16
    assert table.loc[table["n"] == 16, "ST_width"].max() > SOBOL_TARGET_WIDTH
    assert evaluate.runs == 16 * (6 + 2)


def test_stage_fit_is_drawn_per_direction_not_through_zero():
    """Eq. 13's fitted force jumps by 2·Fc at v = 0: each fitted line keeps one sign of v."""
    matplotlib.use("Agg")
    v = np.array([-8.0, -5.0, -2.0, 2.0, 5.0, 8.0])
    fitted = np.sign(v) * 10.0 + 0.5 * v
    data = pd.DataFrame({"x": v, "measured": fitted + 0.1, "fitted": fitted})
    estimates = Estimates(("Fc",), np.array([10.0]), np.array([0.1]), np.eye(1) * 0.01, 4,
                          ("N",))
    stage = StageResult("sliding", estimates, ("r",), data, "velocity [mm/s]",
                        "friction force [N]")
    fig = stage.plot()
    lines = [line for line in fig.axes[0].lines if line.get_linestyle() == "-"]
    assert len(lines) == 2
    for line in lines:
        x = np.asarray(line.get_xdata(), float)
        assert (x < 0).all() or (x > 0).all(), x
    import matplotlib.pyplot as plt

    plt.close(fig)


@pytest.mark.parametrize("x", [np.array([1.0, 2.0, 3.0])])
def test_stage_fit_on_one_sign_is_one_line(x):
    """A stage whose x keeps one sign (the spring's position) is one line, as before."""
    matplotlib.use("Agg")
    data = pd.DataFrame({"x": x, "measured": x, "fitted": x})
    estimates = Estimates(("k",), np.array([1.0]), np.array([0.1]), np.eye(1) * 0.01, 2,
                          ("N/m",))
    fig = StageResult("spring", estimates, ("r",), data, "position [mm]", "force [N]").plot()
    assert len([line for line in fig.axes[0].lines if line.get_linestyle() == "-"]) == 1
    import matplotlib.pyplot as plt

    plt.close(fig)


@pytest.mark.parametrize("worker", [True, False])
def test_jobs_beside_the_sections_give_what_they_give_here(worker):
    """A worker process (when more than one CPU) or, without one, here: the same
    results, a job's error raised where its result is asked for, the worker let go
    once its last result is taken."""
    jobs = {"sum": (operator.add, (2, 3)), "factorial": (math.factorial, (20,)),
            "bad": (math.factorial, (-1,))}
    with _Beside(jobs, worker=worker) as beside:
        assert beside.result("sum") == 5
        with pytest.raises(ValueError, match="negative"):
            beside.result("bad")
        assert beside.result("factorial") == math.factorial(20)
        assert beside.pool is None and not beside.futures
        assert beside.result("sum") == 5  # asked again: run here


def test_jobs_beside_stop_with_the_block():
    """Leaving the block with jobs unfinished (a section failed) ends the worker."""
    with pytest.raises(RuntimeError, match="a section failed"):
        with _Beside({"slow": (sum, (range(10 ** 9),))}) as beside:
            raise RuntimeError("a section failed")
    assert beside.pool is None


def test_global_study_split_between_the_processes_is_the_whole_study(vgt):
    """SRC² across conditions in two parts (the slow cycles beside the sections, the
    others here) joins into the study of all the conditions at once."""
    import dataclasses
    import warnings

    from pneumact import sensitivity as sa
    from pneumact.models import Actuator
    from pneumact.reproduction import GLOBAL_VALVES, Sizes, _global_across, _joined

    params = vgt
    sizes = dataclasses.replace(Sizes.quick(), periods=(5.0, 40.0), condition_n=14,
                                slow_source_periods=(80.0,), global_apart_from=40.0)
    assert GLOBAL_VALVES == ("source", "command")
    # the slowest cycle behind the source only; never the fast ones (Fig. 5's alone)
    conditions = (sa.conditions((5.0, 40.0, 80.0), valves=("source",))
                  + sa.conditions((5.0, 40.0), valves=("command",)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sa.SensitivityWarning)
        whole = sa.across_conditions(Actuator(params), conditions, "src",
                                     features=["loop_width_pressure"], n=14, seed=0)
    joined = _joined([_global_across(params, sizes, 0, slow=True),
                      _global_across(params, sizes, 0, slow=False)],
                     [c.label for c in conditions])
    pd.testing.assert_frame_equal(joined.conditions, whole.conditions)
    pd.testing.assert_frame_equal(joined.indices, whole.indices)
    assert len(joined.results) == len(conditions)


def test_a_section_run_in_the_worker_joins_the_report_as_run_here(vgt):
    """An independent section (``Sizes.apart``) made in the worker process comes back
    with the same blocks, figures (PNG bytes), tables and files as made here, and joins
    the report with its heading numbered there."""
    import pickle

    from pneumact.io.report import Report
    from pneumact.reproduction import Sizes, _Parts, _section_apart

    matplotlib.use("Agg")
    name, sizes = "pneumatics", Sizes.quick()
    with _Beside({name: (_section_apart, (name, vgt, sizes))}) as beside:
        apart, _ = beside.result(name)
    here, _ = _section_apart(name, vgt, sizes)
    assert apart.report.blocks == here.report.blocks
    assert sorted(apart.writers) == sorted(here.writers) and apart.writers
    assert pickle.dumps(apart.writers) == pickle.dumps(here.writers)
    for table, frame in here.tables.items():
        pd.testing.assert_frame_equal(apart.tables[table], frame)
    whole = _Parts(Report("whole")).report
    whole.heading("before")
    joined = _Parts(whole)
    joined.extend(apart)
    headings = [b for b in whole.blocks if b.kind == "heading"]
    assert [b.anchor for b in headings] == ["s1", "s2"]
    assert len(whole.blocks) == 1 + len(apart.report.blocks)


def test_the_worker_s_jobs_come_in_the_order_the_sections_ask_for_them(vgt):
    """The quick mode sends no richer campaign and no SRC² at all (nothing to do: run
    here, they would keep a section waiting behind the worker's sections); the full mode
    sends SRC² at the slow cycles before the richer campaigns (asked for last), and keeps
    ``richer_here`` in the main process."""
    from pneumact.reproduction import RICHER_JOB, Sizes, beside_jobs, richer_cases

    jobs, here = beside_jobs(vgt, Sizes.quick(), 0)
    assert not richer_cases(Sizes.quick())
    assert [n for n in jobs if n not in here] == ["eq13", *Sizes.quick().apart]
    full = Sizes.full()
    jobs, here = beside_jobs(vgt, full, 0)
    sent = [n for n in jobs if n not in here]
    assert sent == ["global_across", *(f"{RICHER_JOB}{case}" for case in richer_cases(full)
                                       if case not in full.richer_here)]
    assert {f"{RICHER_JOB}{case}" for case in full.richer_here} <= set(here)
    assert set(full.richer_here) < set(richer_cases(full))  # both processes have some
