"""One progress-callback signature: every public function with a ``progress`` parameter
calls it with ``pneumact.progress.Progress`` reports.

The functions are found by walking the public API (``pneumact`` and its subpackages'
``__all__``), so a new function with ``progress=`` must get a cheap call here. Cheap
functions run to the end (every report a ``Progress``, the last one complete); the long
ones (a paper identification, the reproduction, a study across conditions) are stopped
at their first report, which must already be a ``Progress``.
"""

from __future__ import annotations

import inspect

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
from pneumact.progress import Progress
from public_api import dotted_name, public_objects


class StopReportsError(Exception):
    """Raised by a callback to end a long call at its first report."""


def public_progress_functions() -> set[str]:
    """``module.qualname`` of every public function that takes ``progress``."""
    return {dotted_name(obj) for obj in public_objects()
            if inspect.isfunction(obj) and "progress" in inspect.signature(obj).parameters}


@pytest.fixture(scope="module")
def setup(vgt):
    model = pa.Actuator(vgt, valve=pa.PressureSource())
    cycle = pa.PressureCycle(high=100e3, low=40e3, period=2.0, n_points=201)
    run = pa.simulate(model, cycle)
    # three records of one run, each with its own sensor noise (the same data twice is
    # refused as a repeated record)
    rng = np.random.default_rng(0)
    records = [pa.Record.from_arrays(
        run.time, {"pressure": run["pressure"] + rng.normal(0.0, 20.0, run.time.size),
                   "position": run["position"] + rng.normal(0.0, 1e-6, run.time.size)},
        source=f"{kind}.csv", meta={"kind": kind})
               for kind in ("sweep", "ramp", "presliding")]
    return model, cycle, records


def _run(call) -> list:
    seen: list = []
    call(seen.append)
    return seen


def _first(call) -> list:
    seen: list = []

    def stop(report) -> None:
        seen.append(report)
        raise StopReportsError

    with pytest.raises(StopReportsError):
        call(stop)
    return seen


def _as_sweep(record):
    return [pa.Record.from_arrays(record.time, record.signals, record.units, "sweep",
                                  {"kind": "sweep"})]


def _table(model) -> pd.DataFrame:
    return pd.DataFrame({"Fc": [model.params["Fc"], 1.2 * model.params["Fc"]]})


def _sensitivity_outputs(setup, progress):
    from pneumact import sensitivity as sa

    model, cycle, _ = setup
    problem = sa.Problem.around(model.params, {"Fc": 0.1})
    evaluate = sa.model_outputs(model, cycle, problem, ["loop_width_pressure"],
                                progress=progress, executor=1)
    evaluate(np.array([[model.params["Fc"]], [1.1 * model.params["Fc"]]]))


def _sensitivity_signal(setup, progress):
    from pneumact import sensitivity as sa

    model, cycle, _ = setup
    problem = sa.Problem.around(model.params, {"Fc": 0.1})
    evaluate = sa.model_signal(model, cycle, problem, "position", [0.5, 1.0],
                               progress=progress, executor=1)
    evaluate(np.array([[model.params["Fc"]]]))


def _closed_loop(setup, progress):
    from pneumact.control import PID, ClosedLoop, run_loop

    rig = pa.FrictionRig(_canudas(), pa.LuGre(), drive="force")
    run_loop(ClosedLoop(rig, PID(kp=3.0, ki=4.0)), pa.SetpointStep(0.0, 0.1, 0.0, 1.0, 101),
             progress=progress)


def _tuning(setup, progress):
    from pneumact.control import Move, canudas_hunting, tune

    loop, _ = canudas_hunting(_canudas())
    tune(loop, "settling=10,no-hunting", moves=(Move("step", 0.0, 1.0, 20.0),), n_global=2,
         max_evaluations=2, progress=progress)


def _canudas():
    from conftest import load_quietly

    return load_quietly("canudas1995")


def _comparison(setup, progress):
    from conftest import small_rig_comparison

    return small_rig_comparison(progress)


#: function -> (runs to the end?, call(setup, progress))
CALLS = {
    "pneumact.validation.compare.compare_friction_models": (True, _comparison),
    "pneumact.simulation.simulate.simulate": (
        True, lambda s, p: pa.simulate(s[0], s[1], progress=p)),
    "pneumact.simulation.batch.engine.simulate_batch": (
        True, lambda s, p: pa.simulate_batch(s[0], s[1], _table(s[0]), executor=1,
                                             progress=p)),
    "pneumact.identification.fit.fit": (
        True, lambda s, p: pa.fit(s[0], s[2][:1], ["Fc"], optimizer=pa.Optimizer(max_nfev=2),
                                  progress=p)),
    "pneumact.validation.validate.validate": (
        True, lambda s, p: pa.validate(s[0], s[2][:2], progress=p)),
    "pneumact.sensitivity.methods.model_outputs": (True, _sensitivity_outputs),
    "pneumact.sensitivity.along.model_signal": (True, _sensitivity_signal),
    "pneumact.control.study.run_loop": (True, _closed_loop),
    "pneumact.control.tuning.tune": (True, _tuning),
    "pneumact.identification.paper.identify_paper": (
        False, lambda s, p: pa.identify_paper(s[2], s[0].params, progress=p)),
    "pneumact.identification.paper.identify_signature": (
        True, lambda s, p: pa.identify_signature(_as_sweep(s[2][0]), s[0].params,
                                                 progress=p)),
    "pneumact.reproduction.reproduce": (
        False, lambda s, p: pa.reproduce("unused", quick=True, progress=p)),
    "pneumact.sensitivity.operating.across_conditions": (
        False, lambda s, p: _across(s, p)),
}


def _across(setup, progress):
    from pneumact import sensitivity as sa

    sa.across_conditions(setup[0], [sa.Condition(period=2.0, valve="source")], "src",
                         variations={"Fc": 0.1}, features=["loop_width_pressure"], n=4,
                         progress=progress, executor=1)


def test_every_public_progress_function_is_covered():
    assert public_progress_functions() == set(CALLS)


@pytest.mark.parametrize("name", sorted(CALLS))
def test_progress_receives_progress_reports(name, setup):
    to_the_end, call = CALLS[name]
    reports = (_run if to_the_end else _first)(lambda progress: call(setup, progress))
    assert reports, f"{name} never reported progress"
    assert all(isinstance(r, Progress) for r in reports), reports[:3]
    assert all(r.stage and 0 <= r.done <= r.total for r in reports), reports
    if to_the_end:
        assert reports[-1].fraction == 1.0, reports[-1]


def test_a_progress_that_is_not_a_function_is_refused(setup):
    with pytest.raises(pa.ArgumentTypeError, match="progress"):
        pa.simulate(setup[0], setup[1], progress=3)


def test_a_multistart_says_its_time_and_memory_before_a_start_finishes(setup,
                                                                        estimates_log):
    """fit --multistart gave no estimate until its first starts had finished (minutes
    for a slow fit): one evaluation is timed first and the range is said before."""
    model, _, records = setup
    before_first_start: list[int] = []

    def progress(report: Progress) -> None:
        if report.stage == "multistart" and not before_first_start:
            before_first_start.append(len(estimates_log))

    pa.fit(model, records[:1], ["Fc"], optimizer=pa.Optimizer(max_nfev=2),
           multistart=pa.Multistart(4, seed=1), executor=2, progress=progress)
    assert before_first_start == [1], estimates_log
    note = estimates_log[0]
    assert note.startswith("multistart: 5 starts on 2 threads; one evaluation"), note
    assert "MiB of memory" in note and " to " in note
