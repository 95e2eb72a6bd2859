"""The C engine beside numba: the same trajectories, the engine chosen and refused clearly.

Issue 43: ``pa.simulate(..., engine="c" | "numba" | "auto")`` and ``PNEUMACT_ENGINE``; the C
engine's library is the C back end's translation of the same kernel functions, so the two
engines must agree to rounding (here: bit for bit, or 1e-12 relative where noted), the
ISO 6358 valve and the double-acting cylinder of issue 41 included (open, and closed by
the state feedback with its pressure difference).
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.control import PID, ClosedLoop
from pneumact.core.assembly import assemble
from pneumact.core.c_build import compiler_path
from pneumact.core.c_engine import CKernel, engine_kernel
from pneumact.errors import ArgumentError, EngineWarning
from pneumact.experiments import SetpointStep, Sine

pytestmark = pytest.mark.integration
needs_compiler = pytest.mark.skipif(compiler_path() is None,
                                    reason="no C compiler: the C engine cannot run here")


def _models() -> dict[str, tuple[object, pa.Experiment]]:
    vgt = load_quietly("vgt-paper")
    rig = pa.FrictionRig(load_quietly("canudas1995"), pa.LuGre(), drive="force")
    short = {"period": 4.0, "n_points": 801}
    return {
        "source": (pa.Actuator(vgt, valve=pa.PressureSource()), pa.PressureCycle(**short)),
        "command": (pa.Actuator(vgt, valve=pa.CommandValve()), pa.CommandCycle(**short)),
        "regulator": (pa.Actuator(vgt, valve=pa.PressureRegulator()),
                      pa.PressureCycle(**short)),
        "iso6358": (pa.Actuator(vgt.replace(iso_b=0.3, iso_m=0.6), valve=pa.Iso6358Valve()),
                    pa.CommandCycle(**short)),
        "gms": (pa.Actuator(load_quietly("vgt-paper-gms4"), friction=pa.GMS(4)),
                pa.PressureCycle(**short)),
        "cylinder": (pa.Cylinder(load_quietly("iso15552-32"), chamber=pa.Adiabatic(),
                                 load=Sine(30.0, 2.0, offset=50.0)),
                     pa.Experiment(Sine(0.6, 1.0, phase=-1.5), "spool", 2.0, n_points=801)),
        "rig": (pa.FrictionRig(load_quietly("canudas1995"), drive="velocity"),
                pa.Experiment(Sine(0.01, 0.5), "velocity", 4.0, n_points=801)),
        "loop": (ClosedLoop(rig, PID(kp=3.0, ki=4.0, kd=6.0, derivative="velocity")),
                 SetpointStep(0.0, 5.0, 0.0, 10.0, 1001)),
        "cylinder loop": (ClosedLoop(pa.Cylinder(load_quietly("iso15552-32")),
                                     PID(kp=100.0, kd=0.5, kdp=3e-6, derivative="velocity",
                                         u_min=-1.0, u_max=1.0)),
                          SetpointStep(0.09, 0.11, 0.5, 1.0, 1001)),
    }


@pytest.mark.numba
@needs_compiler
@pytest.mark.parametrize("name", ["source", "command", "regulator", "iso6358", "gms",
                                  "cylinder", "rig", "loop", "cylinder loop"])
def test_the_c_engine_follows_numba(name):
    """Every signal of the C engine's run equals numba's to 1e-12 of its range."""
    model, experiment = _models()[name]
    c = pa.simulate(model, experiment, engine="c")
    numba = pa.simulate(model, experiment, engine="numba")
    assert isinstance(assemble(model).kernel_on("c"), CKernel)
    assert (c.meta["engine"], numba.meta["engine"]) == ("c", "numba")
    assert c.meta["steps"] == numba.meta["steps"]
    a, b = c.to_pandas(), numba.to_pandas()
    assert list(a.columns) == list(b.columns)
    span = np.maximum(np.ptp(b.to_numpy(), axis=0), np.finfo(float).tiny)
    worst = np.max(np.abs(a.to_numpy() - b.to_numpy()) / span)
    assert worst <= ref.ENGINE_AGREEMENT, (name, worst)


@pytest.mark.numba
@needs_compiler
def test_sensitivities_are_the_same_on_both_engines():
    """Forward sensitivities (their own library, built on first use) equal numba's, the
    states' and the derived outputs' alike."""
    model, experiment = _models()["command"]
    runs = {engine: pa.simulate_sensitivities(model, experiment, ["sigma0", "Fc"],
                                              engine=engine) for engine in ("c", "numba")}
    kernel = assemble(model).kernel_on("c")
    assert "integrate_rodas4_sens" in vars(kernel)  # the C function, not numba's
    for signal in ("position", "velocity", "pressure", "friction"):
        a, b = runs["c"][signal], runs["numba"][signal]
        span = np.maximum(np.abs(b).max(axis=0), np.finfo(float).tiny)
        assert np.max(np.abs(a - b) / span) <= ref.ENGINE_AGREEMENT, signal


def _loops(rng: np.random.Generator, count: int):
    """Records of every shape the features meet: loops at several speeds and noise
    levels, quantised pressures, a position that never moves, a few samples."""
    for k in range(count):
        n = int(rng.integers(3, 1500))
        t = np.cumsum(rng.uniform(1e-3, 1e-2, n))
        p = 1e4 * np.sin(t * rng.uniform(0.5, 5.0) + rng.uniform(0, 20)) \
            + rng.normal(0, rng.choice([0.0, 10.0, 1e3]), n)
        if k % 5 == 1:
            p = np.round(p, -3)
        x = np.cumsum(rng.normal(0, 1e-4, n)) + (p - p.mean()) * 1e-7 * rng.choice([1, -1])
        if k % 7 == 0:
            x = np.zeros(n)
        yield t, p, x, np.gradient(x, t) if n > 1 else x


@pytest.mark.numba
@needs_compiler
def test_the_shared_functions_on_c_are_numba_s_bit_for_bit():
    """Signal evaluation and every loop feature (``core.c_common``: the library all models
    share on the C engine) return numba's values exactly, NaNs where numba's are."""
    from pneumact.core import features
    from pneumact.core.c_common import common_functions
    from pneumact.core.features import N_FEATURES

    c = common_functions()
    for t, p, x, v in _loops(np.random.default_rng(ref.FAMILY_SEED), 60):
        ref_t, ref_x = t[::3].copy(), x[::3] + 1e-6
        for has_pressure in (True, False):
            for has_reference in (True, False):
                a, b = np.zeros(N_FEATURES), np.ones(N_FEATURES)
                args = (t, x, v, p, has_pressure, ref_t, ref_x, has_reference)
                features.all_features(*args, a)
                c["all_features"](*args, b)
                np.testing.assert_array_equal(a, b)
        for name in ("breakaway", "loop_width_pressure", "loop_width_position", "loop_area",
                     "presliding_travel"):
            assert np.array_equal(getattr(features, f"_{name}")(p, x), c[name](p, x),
                                  equal_nan=True), name
        assert np.array_equal(features._sliding_speed(t, p, x), c["sliding_speed"](t, p, x),
                              equal_nan=True)
        np.testing.assert_array_equal(features._turning_points(p), c["turning_points"](p))
        threshold = 0.1 * features._stroke(x) + 1e-9
        assert np.array_equal(features._motion_onset(p, x, threshold),
                              c["motion_onset"](p, x, threshold), equal_nan=True)


@pytest.mark.numba
@needs_compiler
def test_signals_evaluate_the_same_on_both_engines():
    """A signal of every kind of term (ramps, a sine, jumps) read on either engine."""
    from pneumact.core.c_engine import engine_scope
    from pneumact.core.signals import PiecewiseLinear, Step
    from pneumact.core.signals import Sine as SineTerm

    signal = PiecewiseLinear([0.0, 1.0, 1.0, 3.0], [0.0, 2.0, -1.0, 4.0]) \
        + 0.5 * SineTerm(0.3, 1.7, t_start=0.4, t_stop=3.1) + Step(2.2, 0.0, 1.5)
    grid = np.linspace(-1.0, 4.0, 2001)
    with engine_scope("c"):
        on_c = signal.evaluate(grid)
    with engine_scope("numba"):
        on_numba = signal.evaluate(grid)
    np.testing.assert_array_equal(on_c[0], on_numba[0])
    np.testing.assert_array_equal(on_c[1], on_numba[1])


@needs_compiler
def test_a_warm_run_on_c_never_imports_numba(tmp_path):
    """A run on C and its summary, in a process of its own whose libraries are built: numba
    is not even imported (its import, 0.4-0.8 s, and its compiler, about a second, were
    most of issue 43's warm command); the numba functions are declared by
    ``core.jit.njit`` and none of them is made."""
    import subprocess
    import sys

    script = """
import sys, warnings
import numpy as np
import pneumact as pa
from pneumact.core.jit import LazyDispatcher
warnings.simplefilter("ignore")
model = pa.Actuator(pa.load_params("vgt-paper"), valve=pa.CommandValve())
run = pa.simulate(model, pa.CommandCycle(period=4.0, n_points=801), engine="c")
summary = run.summary()
assert np.isfinite(summary["stroke"]), summary
made = sorted(f"{name}.{key}" for name, module in list(sys.modules.items())
              if name.startswith("pneumact") for key, value in vars(module).items()
              if isinstance(value, LazyDispatcher) and value.made)
print("MADE", made, "NUMBA", "numba" in sys.modules)
"""
    env = {**os.environ, "PNEUMACT_ENGINE": "c"}
    first = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                           text=True, timeout=600)
    assert first.returncode == 0, first.stderr  # builds what is not built yet
    second = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True, timeout=600)
    assert second.returncode == 0, second.stderr
    assert "MADE [] NUMBA False" in second.stdout, second.stdout


def test_an_unknown_engine_is_refused_naming_the_choices(monkeypatch):
    model, experiment = _models()["source"]
    with pytest.raises(ArgumentError, match=r"engine = 'fast'.*auto, c, numba"):
        pa.simulate(model, experiment, engine="fast")
    monkeypatch.setenv("PNEUMACT_ENGINE", "gpu")
    with pytest.raises(ArgumentError, match=r"PNEUMACT_ENGINE = 'gpu'.*auto, c, numba"):
        pa.simulate(model, experiment)


def test_without_a_compiler_auto_runs_numba_and_says_why(monkeypatch):
    """No compiler on the machine: 'auto' warns once, naming what to install, and runs
    numba; 'c' refuses."""
    monkeypatch.setenv("CC", "no-such-compiler-here")
    model, _ = _models()["source"]
    spec = assemble(model).kernel_spec()
    with pytest.warns(EngineWarning, match="no-such-compiler-here.*numba engine runs it"):
        kernel = engine_kernel(spec, "auto")
    assert not isinstance(kernel, CKernel)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        engine_kernel(spec, "auto")  # said once per kernel and process
    with pytest.raises(pa.PneumactError, match="no-such-compiler-here"):
        engine_kernel(spec, "c")


@pytest.mark.numba
@needs_compiler
def test_a_batch_gives_the_same_table_on_both_engines():
    """simulate_batch on C and on numba: the same features, row by row."""
    from pneumact.simulation.batch import simulate_batch

    model, experiment = _models()["command"]
    base = model.params
    table = pd.DataFrame({"Fc": base["Fc"] * np.array([0.8, 1.0, 1.2]),
                          "sigma0": base["sigma0"] * np.array([1.3, 1.0, 0.7])})
    runs = {engine: simulate_batch(model, experiment, table, executor=2, engine=engine)
            for engine in ("c", "numba")}
    c, numba = (runs[e].table.select_dtypes("number") for e in ("c", "numba"))
    pd.testing.assert_frame_equal(c, numba, check_exact=False, rtol=ref.ENGINE_AGREEMENT)


@pytest.mark.numba
def test_the_command_line_chooses_the_engine(tmp_path, monkeypatch):
    """``pneumact --engine numba simulate`` runs numba (the CSV says nothing else: the run
    equals the API's); an unknown engine is refused before anything runs."""
    from typer.testing import CliRunner

    from pneumact.cli import app

    monkeypatch.setenv("PNEUMACT_ENGINE", "auto")  # the command sets it: undone after
    runner = CliRunner()
    bad = runner.invoke(app, ["--engine", "fast", "simulate", "--out", str(tmp_path / "x")])
    assert bad.exit_code == 2 and "'fast' is not one of auto, c, numba" in bad.output
    assert not (tmp_path / "x").exists()
    good = runner.invoke(app, ["--engine", "numba", "simulate", "--t-end", "2",
                               "--out", str(tmp_path / "run")])
    assert good.exit_code == 0, good.output
    assert (tmp_path / "run" / "simulation.csv").is_file()
    assert os.environ["PNEUMACT_ENGINE"] == "numba"


@pytest.mark.numba
@needs_compiler
def test_a_model_the_back_end_cannot_translate_runs_on_numba_naming_the_construct(
        monkeypatch, tmp_path):
    """'auto' falls back to numba with the construct the C back end refused; 'c' raises it."""
    from pneumact.core import c_source
    from pneumact.core.c_source import CSourceError

    def refuse(roots, share=None):
        raise CSourceError("kernel.rhs: the C back end does not translate a call of <gamma>")

    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path))  # nothing built yet
    monkeypatch.setattr(c_source, "translate", refuse)
    # GMS: the command line's models' C is shipped (core.c_shipped), never translated;
    # GMS's is not (the default set lacks its parameters: tools/ship_c.py skips it)
    model, experiment = _models()["gms"]
    with pytest.warns(EngineWarning, match=r"does not translate a call of <gamma>"):
        run = pa.simulate(model, experiment, engine="auto")
    assert run.meta["engine"] == "numba"
    with pytest.raises(CSourceError, match="<gamma>"):
        pa.simulate(_models()["gms"][0], experiment, engine="c")


def _output_signal(model, experiment) -> str:
    """A signal of ``model`` that is a derived output, not a state."""
    from pneumact.simulation.batch import signal_names

    states = assemble(model).state_names
    return next(n for n in signal_names(model, experiment) if n not in states)


@pytest.mark.parametrize(("name", "engine", "solver"), [
    pytest.param("command", "c", pa.Rodas4(), marks=needs_compiler),
    pytest.param("command", "numba", pa.Rodas4(), marks=pytest.mark.numba),
    pytest.param("loop", "c", pa.Rodas4(), marks=needs_compiler),
    pytest.param("rig", "numba", pa.DormandPrince(), marks=pytest.mark.numba)])
def test_a_batch_that_keeps_states_only_skips_the_outputs_bit_for_bit(name, engine, solver,
                                                                      monkeypatch):
    """Features that read states only (the command valve's position, velocity and
    pressure; the closed loop's rig) run the integrator that writes no derived output
    (``Solver.states_function``); every feature is the one the full integrator gives (a
    kept output signal makes the batch run it) and the one ``simulate`` and the feature
    functions give, bit for bit; with either method."""
    from pneumact.core.features import FEATURES, N_FEATURES, all_features
    from pneumact.simulation.batch import simulate_batch
    from pneumact.simulation.batch.runner import ChunkRunner

    model, experiment = _models()[name]
    base = model.params
    table = pd.DataFrame({"Fc": base["Fc"] * np.array([1.0, 0.8, 1.2]),
                          "sigma0": base["sigma0"] * np.array([1.0, 1.3, 0.7])})
    chosen: list[bool] = []
    reads_states_only = ChunkRunner.reads_states_only
    monkeypatch.setattr(ChunkRunner, "reads_states_only",
                        lambda self: chosen.append(reads_states_only(self)) or chosen[-1])
    states = simulate_batch(model, experiment, table, executor=1, engine=engine,
                            solver=solver)
    assert chosen and all(chosen)  # each chunk's choice
    chosen.clear()
    names = [f for f in FEATURES if f in states.table.columns]
    full = simulate_batch(model, experiment, table, features=names, executor=1,
                          engine=engine, solver=solver,
                          signals=[_output_signal(model, experiment)])
    assert chosen and not any(chosen)
    np.testing.assert_array_equal(states.table[names].to_numpy(), full.table[names].to_numpy())
    run = pa.simulate(model, experiment, solver, engine=engine)  # the table's first row
    expected, none = np.empty(N_FEATURES), np.empty(0)
    x, v = run["position"], run["velocity"]
    has_pressure = "pressure" in run.signals
    all_features(run.time, x, v, run["pressure"] if has_pressure else x, has_pressure, none,
                 none, False, expected)
    np.testing.assert_array_equal(states.table[names].iloc[0].to_numpy(),
                                  expected[[FEATURES.index(f) for f in names]])


@needs_compiler
def test_a_call_on_c_leaves_nothing_for_the_garbage_collector():
    """An array goes to the library as plain numbers (its address, shape and strides): a
    call makes no reference cycle, so the arguments of a batch's rows (about 25 a row)
    leave the garbage collector nothing to find."""
    import gc

    from pneumact.core.c_common import common_functions

    stroke = common_functions()["stroke"]
    x = np.linspace(0.0, 1.0, 11)
    enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        for _ in range(100):
            assert stroke(x) == 1.0
        assert gc.collect() == 0
    finally:
        if enabled:
            gc.enable()
