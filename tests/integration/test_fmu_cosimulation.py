"""The Co-Simulation FMU (issue 39): pneumact's own integrator, translated to C.

- FMPy runs the CS FMU at communication steps of 1 ms, 10 ms, 0.1 s and 1 s; each run equals
  ``pa.simulate`` of the same model driven by the same zero-order-hold (staircase) input,
  for the three valves and GMS-4; FMPy's validation passes.
- The C integrator in the FMU is the compiled one: on a whole cycle its states, outputs
  and step counts equal the numba kernel's (a change to the C side's step control fails
  here).
- A step the integrator cannot finish is fmi2Error with the reason, the state kept.
- Translating a kernel to C compiles none of its functions with numba (they are typed).
- ``pneumact export fmu --kind --fmi``; a wrong kind or version is refused.
- FMI 3.0 from the same C: FMPy's validation passes, its CS run is the FMI 2.0 one's, its
  ME run agrees with pa.simulate; the sources alone build from the FMI 3.0 build
  description.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from conftest import load_quietly
from fmu_support import VALVES, needs_compiler
from pneumact.cli import app
from pneumact.core.c_source import Arena, c_array
from pneumact.core.signals import PiecewiseLinear
from pneumact.export import find_compiler
from pneumact.export.compiler import FLAGS
from pneumact.simulation.simulate import prepare
from pneumact.simulation.solvers import Rodas4

fmpy = pytest.importorskip("fmpy", reason="FMPy (the test extra) simulates the FMUs")
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (  # noqa: E402
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.model_description import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

pytestmark = needs_compiler
CASES = (*VALVES, "gms4")


def actuator(case: str) -> pa.Actuator:
    if case == "gms4":
        return pa.Actuator(load_quietly("vgt-paper-gms4"), friction=pa.GMS(n_elements=4),
                           valve=pa.PressureSource())
    return pa.Actuator(load_quietly("vgt-paper"), valve=VALVES[case]())


def experiment_for(case: str) -> pa.Experiment:
    """A 10 s cycle (5 s for GMS-4): the loop of the paper's Fig. 5, faster."""
    if case == "command":
        return pa.CommandCycle(period=10.0)
    return pa.PressureCycle(period=5.0 if case == "gms4" else 10.0)


@pytest.fixture(scope="module")
def cosimulation(tmp_path_factory):
    """case -> (model, ExportedFmu): one Co-Simulation FMU per case, exported once."""
    folder = tmp_path_factory.mktemp("cs")
    return {case: (model, pa.export_fmu(model, folder / f"{case}.fmu", kind="cs"))
            for case, model in ((c, actuator(c)) for c in CASES)}


def held(experiment: pa.Experiment, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The communication points and the drive held over each step from its value there."""
    grid = np.linspace(0.0, experiment.t_end, round(experiment.t_end / step) + 1)
    return grid, np.array([experiment.drive(t) for t in grid])


def staircase(experiment: pa.Experiment, grid: np.ndarray, values: np.ndarray
              ) -> pa.Experiment:
    """The same zero-order-hold input for pa.simulate: a jump at every communication point."""
    times = np.concatenate([[grid[0]], np.repeat(grid[1:-1], 2), [grid[-1]]])
    return pa.Experiment(PiecewiseLinear(times, np.repeat(values[:-1], 2)), experiment.quantity,
                         experiment.t_end, n_points=grid.size, name="held drive")


@pytest.mark.parametrize("step", ref.CS_STEPS)
@pytest.mark.parametrize("case", CASES)
def test_the_cs_fmu_steps_like_pa_simulate_with_held_inputs(cosimulation, case, step):
    _steps_like_pa_simulate(cosimulation, case, step, experiment_for(case))


@pytest.mark.parametrize("case", ["source", "command"])
def test_a_tenth_of_a_millisecond_step_too(cosimulation, case):
    """The shortest communication step the issue names (0.1 ms, a HIL task's), on a 1 s
    cycle (10 000 steps: FMPy's own loop is most of the time)."""
    experiment = (pa.CommandCycle(period=1.0) if case == "command"
                  else pa.PressureCycle(period=1.0))
    _steps_like_pa_simulate(cosimulation, case, ref.CS_SHORTEST_STEP, experiment)


def test_the_iso_6358_valve_exports_too(tmp_path):
    """A valve added after the export was written (issue 41's ISO 6358 valve, with a
    datasheet's b and m) needs nothing of the export: its CS FMU steps like pa.simulate."""
    params = load_quietly("vgt-paper").replace({"iso_b": 0.3, "iso_m": 0.6})
    model = pa.Actuator(params, valve=pa.Iso6358Valve())
    fmu = pa.export_fmu(model, tmp_path / "iso.fmu", kind="cs")
    _steps_like_pa_simulate({"iso": (model, fmu)}, "iso", ref.CS_STEPS[0],
                            pa.CommandCycle(period=10.0))


@pytest.fixture(scope="module")
def cylinder_fmu(tmp_path_factory):
    """The ISO 15552 cylinder (issue 41, item 5) and its FMU with both interfaces, once."""
    model = pa.Cylinder(load_quietly("iso15552-32"))
    fmu = pa.export_fmu(model, tmp_path_factory.mktemp("cylinder") / "cylinder.fmu",
                        kind="both")
    return model, fmu


@pytest.mark.parametrize("step", ref.CS_STEPS[:3])
def test_the_cylinder_exports_and_its_cs_fmu_steps_like_pa_simulate(cylinder_fmu, step):
    """The exporter asks the model (its fmu_interface): the spool command in [-1, 1] is
    the drive input, and a held spool step runs as pa.simulate runs it."""
    _, fmu = cylinder_fmu
    spool = next(v for v in fmu.variables if v.name == "spool_command")
    assert (spool.causality, spool.minimum, spool.maximum) == ("input", -1.0, 1.0)
    experiment = pa.experiments.SpoolStep(before=-1.0, after=0.5, t_step=0.1, t_end=1.0)
    _steps_like_pa_simulate({"cylinder": cylinder_fmu}, "cylinder", step, experiment)


def test_the_heat_transfer_cylinder_s_cs_fmu_steps_like_pa_simulate(tmp_path):
    """Chambers with heat transfer (their gas temperatures as states, issue 41): the
    exporter needs nothing of its own for them; a held spool step runs as pa.simulate
    runs it, the chambers' gas temperatures (which move by kelvins) with it."""
    model = pa.Cylinder(load_quietly("iso15552-32"), chamber=pa.HeatTransfer())
    fmu = pa.export_fmu(model, tmp_path / "heat.fmu", kind="cs")
    assert {"temperature_a", "temperature_b"} <= set(fmu.names("output"))
    experiment = pa.experiments.SpoolStep(before=-1.0, after=0.5, t_step=0.1, t_end=1.0)
    temperatures = ("temperature_a", "temperature_b")
    run = pa.simulate(model, experiment)
    assert all(np.ptp(run[name]) > 1.0 for name in temperatures)  # K: they do move
    _steps_like_pa_simulate({"heat": (model, fmu)}, "heat", ref.CS_STEPS[0], experiment,
                            also=temperatures)


def test_the_cylinder_cs_fmu_runs_into_its_end_stop_as_pa_simulate_does(cylinder_fmu):
    """Spool fully open: the rod runs out to the rod-end stop (x_max), bounces on its
    spring and damper and rests there, in the FMU as in pa.simulate (the stop force is
    the kernel's own, stiff: the FMU's integrator must take it too)."""
    model, _ = cylinder_fmu
    experiment = pa.experiments.SpoolStep(before=-1.0, after=1.0, t_step=0.1, t_end=1.0)
    run = pa.simulate(model, experiment)
    x_max = float(model.params["x_max"])
    assert run["position"][-1] == pytest.approx(x_max, abs=ref.END_STOP_REST_ATOL)
    assert float(run["position"].max()) > x_max  # on the stop's spring
    _steps_like_pa_simulate({"cylinder": cylinder_fmu}, "cylinder", ref.CS_STEPS[0],
                            experiment)


@pytest.mark.parametrize("values", [{}, {"chamber_a.V_dead": ref.FMU_LARGE_DEAD_VOLUME}],
                         ids=["set", "chamber_a.V_dead set in the FMU"])
def test_the_cylinder_me_fmu_follows_pa_simulate(cylinder_fmu, values):
    """Model Exchange: FMPy's CVode on the same spool step (its corner in the input
    table) against pa.simulate, within what the actuator's ME FMU is held to; with chamber
    A's dead volume set by its structured name, as pa.simulate runs with that value (and
    unlike the set's run)."""
    model, fmu = cylinder_fmu
    experiment = pa.experiments.SpoolStep(before=-1.0, after=0.5, t_step=0.1, t_end=1.0)
    table = np.array([(0.0, -1.0, 0.0), (0.1, -1.0, 0.0), (0.1, 0.5, 0.0), (1.0, 0.5, 0.0)],
                     dtype=[("time", float), ("spool_command", float),
                            ("external_force", float)])
    out = fmpy.simulate_fmu(str(fmu.path), fmi_type="ModelExchange", stop_time=1.0,
                            input=table, start_values={"spool_command": -1.0, **values},
                            relative_tolerance=ref.FMU_RTOL, output_interval=1e-3,
                            output=["position"])
    run = pa.simulate(model, experiment, values=values)
    position = np.interp(run.time, out["time"], out["position"])
    travel = float(np.ptp(run["position"]))
    assert travel > 0.2 * float(model.params["x_max"])
    rms = np.sqrt(np.mean((position - run["position"]) ** 2))
    allowed = ref.FMU_POSITION_RMS_OF_STROKE * travel
    assert rms <= allowed
    if values:
        nominal = pa.simulate(model, experiment)["position"]
        changed = np.sqrt(np.mean((nominal - run["position"]) ** 2))
        assert changed > ref.FMU_PARAMETER_EFFECT_FACTOR * allowed, changed


def test_the_cylinder_fmu_s_external_force_is_its_load_input(cylinder_fmu):
    """The FMU's input ``external_force`` is the cylinder's declared input ``load``
    (issue 41, item 2): a load step in the FMU's input table runs as pa.simulate runs the
    same step driven by name, within what the ME FMU is held to, and far from the run
    without it."""
    from pneumact.core.signals import Step

    model, fmu = cylinder_fmu
    spool = pa.experiments.SpoolStep(before=-1.0, after=0.5, t_step=0.1, t_end=1.0)
    push = Step(0.15, 0.0, 250.0)  # while the rod extends
    loaded = pa.Experiment(spool.drive, spool.quantity, spool.t_end, n_points=spool.n_points,
                           drives={"load": push})
    table = np.array([(0.0, -1.0, 0.0), (0.1, -1.0, 0.0), (0.1, 0.5, 0.0), (0.15, 0.5, 0.0),
                      (0.15, 0.5, 250.0), (1.0, 0.5, 250.0)],
                     dtype=[("time", float), ("spool_command", float),
                            ("external_force", float)])
    out = fmpy.simulate_fmu(str(fmu.path), fmi_type="ModelExchange", stop_time=1.0,
                            input=table, start_values={"spool_command": -1.0},
                            relative_tolerance=ref.FMU_RTOL, output_interval=1e-3,
                            output=["position"])
    run = pa.simulate(model, loaded)
    position = np.interp(run.time, out["time"], out["position"])
    allowed = ref.FMU_POSITION_RMS_OF_STROKE * float(np.ptp(run["position"]))
    assert np.sqrt(np.mean((position - run["position"]) ** 2)) <= allowed
    free = pa.simulate(model, spool)["position"]
    changed = np.sqrt(np.mean((free - run["position"]) ** 2))
    assert changed > ref.FMU_PARAMETER_EFFECT_FACTOR * allowed, changed


def test_the_cylinder_fmu_s_supply_input_is_its_supply_pressure(cylinder_fmu):
    """The cylinder declares its supply pressure as an input on a channel of its own
    (issue 41, item 2): its FMU has the input ``supply`` [Pa] starting at p_supply, from
    p_atm up, and a supply step in the FMU's input table runs as pa.simulate runs the same
    step driven by name, within what the ME FMU is held to, and far from the run without
    it."""
    from pneumact.core.signals import Step

    model, fmu = cylinder_fmu
    supply = next(v for v in fmu.variables if v.name == "supply")
    assert (supply.causality, supply.unit, supply.start, supply.minimum) == (
        "input", "Pa", model.params["p_supply"], model.params["p_atm"])
    spool = pa.experiments.SpoolStep(before=-1.0, after=0.5, t_step=0.1, t_end=1.0)
    high, low = model.params["p_supply"], 3e5
    lowered = pa.Experiment(spool.drive, spool.quantity, spool.t_end, n_points=spool.n_points,
                            drives={"supply": Step(0.15, high, low)})
    table = np.array([(0.0, -1.0, high), (0.1, -1.0, high), (0.1, 0.5, high),
                      (0.15, 0.5, high), (0.15, 0.5, low), (1.0, 0.5, low)],
                     dtype=[("time", float), ("spool_command", float), ("supply", float)])
    out = fmpy.simulate_fmu(str(fmu.path), fmi_type="ModelExchange", stop_time=1.0,
                            input=table, start_values={"spool_command": -1.0},
                            relative_tolerance=ref.FMU_RTOL, output_interval=1e-3,
                            output=["position"])
    run = pa.simulate(model, lowered)
    position = np.interp(run.time, out["time"], out["position"])
    allowed = ref.FMU_POSITION_RMS_OF_STROKE * float(np.ptp(run["position"]))
    assert np.sqrt(np.mean((position - run["position"]) ** 2)) <= allowed
    free = pa.simulate(model, spool)["position"]
    changed = np.sqrt(np.mean((free - run["position"]) ** 2))
    assert changed > ref.FMU_PARAMETER_EFFECT_FACTOR * allowed, changed
    with pytest.raises(pa.ArgumentError,
                       match=r"supply = 50000: must be in \[100000, 1e\+07\]"):
        pa.export_fmu(model, fmu.path.with_name("low.fmu"), inputs={"supply": 5e4},
                      binary=False)


def _steps_like_pa_simulate(cosimulation, case: str, step: float,
                            experiment: pa.Experiment, also: tuple[str, ...] = ()) -> None:
    """The CS FMU's position (and the outputs ``also``) on a held input against
    pa.simulate of the same staircase, within ``ref.CS_POSITION_RMS_OF_TRAVEL`` of
    each one's span."""
    model, fmu = cosimulation[case]
    grid, drive = held(experiment, step)
    name = fmu.names("input")[0]
    table = np.array(list(zip(grid, drive, np.zeros_like(drive), strict=True)),
                     dtype=[("time", float), (name, float), ("external_force", float)])
    out = fmpy.simulate_fmu(str(fmu.path), fmi_type="CoSimulation", stop_time=experiment.t_end,
                            input=table, start_values={name: float(drive[0])},
                            step_size=step, output_interval=step,
                            output=["position", *also])
    assert np.allclose(out["time"], grid, rtol=0, atol=1e-9 * experiment.t_end)
    run = pa.simulate(model, staircase(experiment, grid, drive), t_eval=grid)
    x = run["position"]
    travel = float(np.max(x) - np.min(x))
    assert travel > 0.2 * float(model.params["x_max"])  # the actuator does move
    rms = np.sqrt(np.mean((out["position"] - x) ** 2))
    assert rms <= ref.CS_POSITION_RMS_OF_TRAVEL * travel
    for name in also:
        rms = np.sqrt(np.mean((out[name] - run[name]) ** 2))
        assert rms <= ref.CS_POSITION_RMS_OF_TRAVEL * float(np.ptp(run[name])), name
    if step == ref.CS_STEPS[0]:
        assert validate_fmu(str(fmu.path)) == []


class _State(ctypes.Structure):
    _fields_ = [("data", ctypes.POINTER(ctypes.c_double)), ("shape", ctypes.c_int64 * 1),
                ("strides", ctypes.c_int64 * 1)]


@pytest.mark.numba
def test_the_c_integrator_is_the_compiled_one(cosimulation, tmp_path):
    """The FMU's model.c (its integrator translated from core/integrators.py), built here
    and called on a whole regulator cycle, gives the numba kernel's run: the same step
    counts, states and outputs (bit-equal on x86-64 with gcc -O3 -fno-tree-vectorize, the FMU's
    flags)."""
    model, fmu = cosimulation["regulator"]
    source = zipfile.ZipFile(fmu.path).read("sources/model.c")
    (tmp_path / "model.c").write_bytes(source)
    library = tmp_path / "model.so"
    flags = [f for f in FLAGS if f != "-fvisibility=hidden"]  # the FMU's build, exported
    subprocess.run([find_compiler(), *flags, "-o", str(library), str(tmp_path / "model.c"), "-lm"],
                   check=True)
    lib = ctypes.CDLL(str(library))
    lib.pa_integrate.restype = _State
    solver = Rodas4()
    prep = prepare(model, experiment_for("regulator"), solver)
    kernel = prep.kernel
    runs = []
    for language in ("C", "numba"):
        y_out = np.zeros((prep.t_out.size, kernel.NSTATE))
        out = np.zeros((prep.t_out.size, kernel.NOUT))
        info = np.zeros(kernel.INFO_LENGTH)
        vector = prep.vector.copy()
        if language == "C":
            arena = Arena()
            state = lib.pa_integrate(
                ctypes.byref(arena), c_array(prep.y0), c_array(vector), c_array(prep.sig),
                c_array(prep.ptr), c_array(prep.breakpoints), c_array(prep.t_out),
                ctypes.c_double(solver.rtol), c_array(prep.atol),
                ctypes.c_double(solver.h_init), ctypes.c_double(solver.h_max),
                ctypes.c_int64(prep.max_steps), c_array(y_out), c_array(out), c_array(info))
            end = np.array(state.data[:kernel.NSTATE])
            lib.pa_arena_free(ctypes.byref(arena))
        else:
            end = kernel.integrate_rodas4(prep.y0, vector, prep.sig, prep.ptr,
                                          prep.breakpoints, prep.t_out, solver.rtol, prep.atol,
                                          solver.h_init, solver.h_max, prep.max_steps, y_out,
                                          out, info)
        runs.append((end, y_out, out, info))
    (c_end, c_states, c_outputs, c_info), (end, states, outputs, info) = runs
    assert c_info[kernel.INFO_STATUS] == 0 and info[kernel.INFO_STATUS] == 0
    counters = [kernel.INFO_STEPS, kernel.INFO_REJECTED, kernel.INFO_RHS, kernel.INFO_JAC]
    assert c_info[counters].tolist() == info[counters].tolist()
    assert info[kernel.INFO_STEPS] > 100
    for c_values, values in ((c_end, end), (c_states, states), (c_outputs, outputs)):
        assert np.allclose(c_values, values, rtol=ref.FMU_KERNEL_RTOL, atol=0)


TRANSLATE_FRESH = """
import sys, warnings
warnings.simplefilter("ignore")
import pneumact as pa
from numba.core.registry import CPUDispatcher
from pneumact.core.assembly import assemble
from pneumact.core.jit import LazyDispatcher
from pneumact.core.c_source import translate
from pneumact.export.fmu import kernel_roots
actuator = pa.Actuator(pa.load_params("vgt-paper"), valve=pa.PressureRegulator())
kernel = assemble(actuator).numba_kernel
unit = translate(kernel_roots(kernel, False, cosimulation=True))
compiled = sorted(f"{m.__name__}.{n}" for m in list(sys.modules.values())
                  if getattr(m, "__name__", "").startswith("pneumact")
                  for n, v in vars(m).items()
                  if isinstance(v, LazyDispatcher) and v.made and v.dispatcher().signatures
                  or isinstance(v, CPUDispatcher) and v.signatures)
print(len(unit.source), compiled)
"""


def test_translating_a_kernel_compiles_none_of_its_functions():
    """A fresh process translates the regulator's kernel and its integrator to C: no
    function of the kernel, of its templates or of the component modules has a compiled
    overload afterwards (numba's disk cache is not even read: nothing is compiled), so
    a first translation costs numba's typing, not its code generation."""
    run = subprocess.run([sys.executable, "-c", TRANSLATE_FRESH], capture_output=True,
                         text=True, check=True, timeout=600)
    size, compiled = run.stdout.strip().split(" ", 1)
    assert int(size) > 100_000 and compiled == "[]"


def test_a_failed_step_is_an_error_with_the_reason(cosimulation, tmp_path):
    """A mass made NaN after initialisation: the step fails; fmi2DoStep says why and where,
    and the FMU keeps its state (no NaN); a variable step size is taken as it comes."""
    _, fmu = cosimulation["source"]
    description = read_model_description(str(fmu.path))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    messages: list[str] = []

    def logger(environment, instance, status, category, message):
        messages.append(message.decode())

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
    from fmpy.logging import addLoggerProxy

    addLoggerProxy(ctypes.byref(callbacks))
    folder = fmpy.extract(str(fmu.path), str(tmp_path / "unzipped"))
    instance = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                         modelIdentifier=fmu.identifier, instanceName="failing")
    instance.instantiate(callbacks=callbacks)
    instance.setupExperiment(startTime=0.0)
    instance.enterInitializationMode()
    instance.exitInitializationMode()
    instance.setReal([refs["pressure_input"]], [60e3])
    t = 0.0
    for step in (1e-3, 0.05, 0.2):  # canHandleVariableCommunicationStepSize
        instance.doStep(t, step)
        t += step
    moved = instance.getReal([refs["position"]])[0]
    assert moved > 0.0
    instance.setReal([refs["m"]], [float("nan")])
    with pytest.raises(FMICallException):
        instance.doStep(t, 0.01)
    assert any("failed at t" in m and "non-finite" in m for m in messages), messages
    assert instance.getReal([refs["position"]])[0] == moved
    instance.terminate()
    instance.freeInstance()


@pytest.mark.filterwarnings("ignore::ResourceWarning",  # FMPy's build leaves a temporary
                            "ignore::pytest.PytestUnraisableExceptionWarning")  # folder to GC
def test_cli_exports_a_sources_only_fmi3_fmu_that_builds(tmp_path):
    """``--kind both --fmi 3 --no-binary``: an FMI 3.0 FMU with both interfaces whose
    sources FMPy builds from their FMI 3.0 build description (CMake); the build runs."""
    path = tmp_path / "cs3.fmu"
    result = CliRunner().invoke(app, ["export", "fmu", "--kind", "both", "--fmi", "3",
                                      "--no-binary", "--out", str(path)])
    assert result.exit_code == 0, result.output
    assert "FMI 3" in result.output
    names = zipfile.ZipFile(path).namelist()
    assert "sources/buildDescription.xml" in names
    assert not any(n.startswith("binaries/") for n in names)
    description = read_model_description(str(path))
    assert description.fmiVersion == "3.0"
    assert description.coSimulation is not None and description.modelExchange is not None
    assert description.coSimulation.canHandleVariableCommunicationStepSize
    assert validate_fmu(str(path)) == []
    refused = CliRunner().invoke(app, ["export", "fmu", "--kind", "hybrid",
                                       "--out", str(tmp_path / "b.fmu")])
    assert refused.exit_code == 2 and "hybrid" in refused.output
    for wrong, words in (({"kind": "hybrid"}, "kind = 'hybrid'"), ({"fmi": 1}, "fmi = 1")):
        with pytest.raises(pa.ArgumentError, match=words):
            pa.export_fmu(actuator("source"), tmp_path / "c.fmu", **wrong)
    if shutil.which("cmake") is None:
        pytest.skip("cmake (FMPy's build tool) is not installed")
    from fmpy.build import build_platform_binary

    folder = fmpy.extract(str(path), str(tmp_path / "unzipped"))
    build_platform_binary(folder)
    out = fmpy.simulate_fmu(folder, fmi_type="CoSimulation", stop_time=1.0, step_size=0.01,
                            start_values={"pressure_input": 60e3}, output=["position"])
    assert np.isfinite(out["position"]).all() and out["position"][-1] > 0.0


def test_fmi3_runs_like_fmi2(cosimulation, tmp_path):
    """The FMI 3.0 FMU (both interfaces, from the same model.c): FMPy's validation passes;
    its Co-Simulation run is the FMI 2.0 one's, its Model Exchange run (FMPy's CVode)
    agrees with pa.simulate as the FMI 2.0 Model Exchange FMU does."""
    model, fmu2 = cosimulation["source"]
    fmu3 = pa.export_fmu(model, tmp_path / "source3.fmu", kind="both", fmi=3)
    assert validate_fmu(str(fmu3.path)) == []
    assert read_model_description(str(fmu3.path)).numberOfEventIndicators == 2
    experiment = experiment_for("source")
    grid, drive = held(experiment, 0.01)
    table = np.array(list(zip(grid, drive, np.zeros_like(drive), strict=True)),
                     dtype=[("time", float), ("pressure_input", float), ("external_force", float)])
    runs = [fmpy.simulate_fmu(str(fmu.path), fmi_type="CoSimulation", stop_time=experiment.t_end,
                              input=table, start_values={"pressure_input": float(drive[0])},
                              step_size=0.01, output_interval=0.01, output=["position"])
            for fmu in (fmu2, fmu3)]
    np.testing.assert_array_equal(runs[0]["position"], runs[1]["position"])
    down = experiment.with_duration(experiment.t_end / 2)  # the ramp down, to keep it short
    ramp = np.array([(t, down.drive(t), 0.0) for t in (0.0, down.t_end)], dtype=table.dtype)
    me = fmpy.simulate_fmu(str(fmu3.path), fmi_type="ModelExchange", stop_time=down.t_end,
                           input=ramp, start_values={"pressure_input": float(ramp[0][1])},
                           relative_tolerance=ref.FMU_RTOL,
                           output_interval=down.t_end / 1000, output=["position"])
    run = pa.simulate(model, down, t_eval=me["time"])
    rms = np.sqrt(np.mean((me["position"] - run["position"]) ** 2))
    assert rms <= ref.FMU_POSITION_RMS_OF_STROKE * float(model.params["x_max"])


def test_the_two_valve_cylinder_fmu_has_both_commands_as_inputs(tmp_path):
    """Cylinder(valves="two-3/2"): its FMU has the inputs valve_a_command and
    valve_b_command in [-1, 1] (command_a and command_b, each on its valve's channel; the
    outputs command_a, command_b keep their names), starting closed; valve A stepped open to the
    supply and valve B to the exhaust (command_b mirrored) runs as pa.simulate runs the
    same commands, within what the ME FMU is held to, and far from the run with valve B
    left closed."""
    from pneumact.core.signals import Step

    model = pa.Cylinder(load_quietly("iso15552-32"), valves="two-3/2")
    fmu = pa.export_fmu(model, tmp_path / "two.fmu", kind="me")
    for name in ("valve_a_command", "valve_b_command"):
        variable = next(v for v in fmu.variables if v.name == name)
        assert (variable.causality, variable.minimum, variable.maximum, variable.start) == (
            "input", -1.0, 1.0, 0.0), name
    table = np.array([(0.0, -1.0, 1.0), (0.1, -1.0, 1.0), (0.1, 0.5, -0.5), (1.0, 0.5, -0.5)],
                     dtype=[("time", float), ("valve_a_command", float),
                            ("valve_b_command", float)])
    out = fmpy.simulate_fmu(str(fmu.path), fmi_type="ModelExchange", stop_time=1.0,
                            input=table, start_values={"valve_a_command": -1.0,
                                          "valve_b_command": 1.0},
                            relative_tolerance=ref.FMU_RTOL, output_interval=1e-3,
                            output=["position"])
    mirrored = pa.Experiment(Step(0.1, -1.0, 0.5), "command_a", 1.0,
                             drives={"command_b": Step(0.1, 1.0, -0.5)})
    run = pa.simulate(model, mirrored)
    position = np.interp(run.time, out["time"], out["position"])
    allowed = ref.FMU_POSITION_RMS_OF_STROKE * float(np.ptp(run["position"]))
    assert np.sqrt(np.mean((position - run["position"]) ** 2)) <= allowed
    closed_b = pa.simulate(model, pa.Experiment(Step(0.1, -1.0, 0.5), "command_a", 1.0,
                                                drives={"command_b": Step(0.1, 1.0, 0.0)}))
    changed = np.sqrt(np.mean((closed_b["position"] - run["position"]) ** 2))
    assert changed > ref.FMU_PARAMETER_EFFECT_FACTOR * allowed, changed


def test_the_two_valve_cylinder_s_cs_fmu_steps_like_pa_simulate(tmp_path):
    """``pneumact export fmu --model cylinder --valves two-3/2 --kind cs``: FMPy steps its
    Co-Simulation FMU at 1 ms on valve A stepped open to the supply and valve B to the
    exhaust (command_b mirrored), each held over the step, as pa.simulate runs the same
    two staircases (command_a the drive, command_b by name), within what the CS FMUs are
    held to; FMPy's validation passes."""
    from pneumact.core.signals import Step

    result = CliRunner().invoke(app, ["export", "fmu", "--model", "cylinder", "--valves",
                                      "two-3/2", "--kind", "cs", "--out",
                                      str(tmp_path / "two.fmu")])
    assert result.exit_code == 0, result.output
    path = tmp_path / "two.fmu"
    assert [v.name for v in read_model_description(str(path)).modelVariables
            if v.causality == "input"][:2] == ["valve_a_command", "valve_b_command"]
    step, t_end = ref.CS_STEPS[0], 0.5
    grid = np.linspace(0.0, t_end, round(t_end / step) + 1)
    command_a = Step(0.1, -1.0, 0.5)(grid)
    command_b = Step(0.1, 1.0, -0.5)(grid)
    table = np.array(list(zip(grid, command_a, command_b, strict=True)),
                     dtype=[("time", float), ("valve_a_command", float),
                            ("valve_b_command", float)])
    out = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=t_end, input=table,
                            start_values={"valve_a_command": -1.0, "valve_b_command": 1.0},
                            step_size=step, output_interval=step, output=["position"])
    assert np.allclose(out["time"], grid, rtol=0, atol=1e-9 * t_end)
    held_a = staircase(pa.Experiment(Step(0.1, -1.0, 0.5), "command_a", t_end), grid,
                       command_a)
    held_b = staircase(held_a, grid, command_b).drive
    model = pa.Cylinder(load_quietly("iso15552-32"), valves="two-3/2")
    run = pa.simulate(model, pa.Experiment(held_a.drive, "command_a", t_end,
                                           n_points=grid.size,
                                           drives={"command_b": held_b}), t_eval=grid)
    travel = float(np.ptp(run["position"]))
    assert travel > 0.2 * float(model.params["x_max"])  # the piston does move
    rms = np.sqrt(np.mean((out["position"] - run["position"]) ** 2))
    assert rms <= ref.CS_POSITION_RMS_OF_TRAVEL * travel, rms
    assert validate_fmu(str(path)) == []
