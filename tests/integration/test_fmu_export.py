"""The FMU export (issue 22), proved by an independent importer (FMPy).

- The FMU's equations are the kernel's: at the same state, its derivatives, outputs and
  Jacobian (directional derivatives) equal the compiled kernel's.
- FMPy's simulation of the exported FMU (CVode) agrees with ``pa.simulate`` of the same
  model and input, for the source, command-valve and regulator variants: loop width,
  position and pressure within the issue's tolerances; FMPy's model-description
  validation passes.
- GMS mode switches are the FMU's state events.
- The sources alone build with an importer's own tool chain (FMPy's CMake build).
- No C compiler: one clear error naming what to install, an existing file left intact.
"""

from __future__ import annotations

import ctypes
import shutil
import zipfile

import numpy as np
import pytest
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.cli import app
from pneumact.core.assembly import assemble
from pneumact.core.features import loop_width_pressure
from pneumact.core.signals import Constant, pack_channels
from pneumact.errors import ExportError
from pneumact.export import find_compiler
from pneumact.parameters.family import ActuatorFamily

fmpy = pytest.importorskip("fmpy", reason="FMPy (the test extra) simulates the FMUs")
from fmpy.fmi2 import FMU2Model  # noqa: E402
from fmpy.model_description import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402


def _compiler() -> str | None:
    try:
        return find_compiler()
    except ExportError:
        return None


pytestmark = pytest.mark.skipif(_compiler() is None, reason="no C compiler to build FMUs with "
                                                           "(install gcc or clang)")

VALVES = {"source": pa.PressureSource, "command": pa.CommandValve,
          "regulator": pa.PressureRegulator}


def actuator(valve: str, friction=None) -> pa.Actuator:
    params = load_quietly("vgt-paper-gms4" if isinstance(friction, pa.GMS) else "vgt-paper")
    return pa.Actuator(params, friction=friction or pa.LuGre(), valve=VALVES[valve]())


def experiment_for(valve: str) -> pa.Experiment:
    """A 10 s cycle: the loop of the paper's Fig. 5, twice as fast as the default."""
    return pa.CommandCycle(period=10.0) if valve == "command" else pa.PressureCycle(period=10.0)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """valve -> (model, ExportedFmu), each exported once."""
    folder = tmp_path_factory.mktemp("fmus")
    return {valve: (model, pa.export_fmu(model, folder / f"{valve}.fmu"))
            for valve, model in ((v, actuator(v)) for v in VALVES)}


def simulate_fmu(fmu, experiment, **kwargs):
    """FMPy's run of ``fmu`` driven by ``experiment``'s drive (exact at its corners)."""
    drive_name = fmu.names("input")[0]
    corners = experiment.drive.breakpoints()
    times = np.unique(np.concatenate([[0.0, experiment.t_end],
                                      corners[(corners > 0) & (corners < experiment.t_end)]]))
    drive = np.array([experiment.drive(t) for t in times])
    table = np.array(list(zip(times, drive, np.zeros_like(drive), strict=True)),
                     dtype=[("time", float), (drive_name, float), ("external_force", float)])
    return fmpy.simulate_fmu(str(fmu.path), stop_time=experiment.t_end, input=table,
                             start_values={drive_name: float(drive[0])},
                             relative_tolerance=ref.FMU_RTOL,
                             output_interval=experiment.t_end / 4000,
                             output=["position", "pressure"], **kwargs)


def pointer(values: np.ndarray):
    return values.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def assert_runs_agree(model, fmu, experiment):
    run = pa.simulate(model, experiment).to_pandas()
    out = simulate_fmu(fmu, experiment)
    t = run.index.to_numpy()
    x, p = run["position"].to_numpy(), run["pressure"].to_numpy()
    x_fmu = np.interp(t, out["time"], out["position"])
    p_fmu = np.interp(t, out["time"], out["pressure"])
    stroke = float(model.params["x_max"])
    assert np.sqrt(np.mean((x_fmu - x) ** 2)) <= ref.FMU_POSITION_RMS_OF_STROKE * stroke
    assert np.sqrt(np.mean((p_fmu - p) ** 2)) <= ref.FMU_PRESSURE_RMS
    width, width_fmu = loop_width_pressure(p, x), loop_width_pressure(p_fmu, x_fmu)
    assert width > 0 and abs(width_fmu - width) <= ref.FMU_LOOP_WIDTH * width


@pytest.mark.parametrize("valve", list(VALVES))
def test_fmpy_runs_the_fmu_like_pa_simulate(exported, valve):
    model, fmu = exported[valve]
    assert validate_fmu(str(fmu.path)) == []
    assert_runs_agree(model, fmu, experiment_for(valve))


def test_the_fmu_s_equations_are_the_kernel_s(exported, tmp_path):
    """Derivatives, outputs and the Jacobian at random states: the FMU's (C, through FMPy)
    against the compiled kernel's, with the same parameters and input (the regulator:
    mechanics, friction, chamber and regulator states all in one), then with every
    parameter set to another actuator of the family; the external force input against its
    known answer, d(dv/dt)/dF = −1/m."""
    model, fmu = exported["regulator"]
    description = read_model_description(str(fmu.path))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    folder = fmpy.extract(str(fmu.path), str(tmp_path / "unzipped"))
    instance = FMU2Model(guid=description.guid, unzipDirectory=folder,
                         modelIdentifier=fmu.identifier, instanceName="check")
    instance.instantiate()
    drive_name, drive = fmu.names("input")[0], 60e3
    instance.setReal([refs[drive_name]], [drive])
    instance.setupExperiment(startTime=0.0)
    instance.enterInitializationMode()
    instance.exitInitializationMode()
    instance.enterContinuousTimeMode()

    asm = assemble(model)  # the model without a load: the FMU's with no external force
    kernel, vec = asm.kernel, asm.pack()
    sig, ptr = pack_channels(model.channels(Constant(drive)))
    n = len(asm.states)
    rest, states_now = np.zeros(n), np.zeros(n)
    kernel.initial_state(0.0, 0.0, vec, sig, ptr, rest)
    instance.getContinuousStates(pointer(states_now), n)
    assert np.allclose(states_now, rest, rtol=ref.FMU_KERNEL_RTOL, atol=0)

    rng = np.random.default_rng(22)
    states = [refs[name] for name in asm.state_names]
    derivatives = [refs[f"der({name})"] for name in asm.state_names]
    outputs = [refs[name] for name in asm.output_names]
    for _ in range(4):
        y = rest * (1.0 + 0.2 * rng.standard_normal(n))
        y[asm.state_index("velocity")] = 1e-3 * rng.standard_normal()
        instance.setContinuousStates(pointer(y), n)
        rates, out, jac = np.zeros(n), np.zeros(len(outputs)), np.zeros((n, n))
        kernel.rhs(0.0, 0.0, y, vec, sig, ptr, rates)
        kernel.outputs(0.0, 0.0, y, vec, sig, ptr, out)
        kernel.jac(0.0, 0.0, y, vec, sig, ptr, jac)
        fmu_rates = np.zeros(n)
        instance.getDerivatives(pointer(fmu_rates), n)
        assert np.allclose(fmu_rates, rates, rtol=ref.FMU_KERNEL_RTOL, atol=0)
        assert np.allclose(instance.getReal(outputs), out, rtol=ref.FMU_KERNEL_RTOL, atol=0)
        for j in range(n):
            column = instance.getDirectionalDerivative(derivatives, [states[j]], [1.0])
            assert np.allclose(column, jac[:, j], rtol=ref.FMU_KERNEL_RTOL, atol=0)
    # every parameter is tunable: another actuator of the family, warmer gas of another
    # heat ratio (derived flow constants change: the FMU re-derives), set into the FMU
    drawn = ActuatorFamily().draw(2, seed=ref.FAMILY_SEED)[1]
    other = drawn.replace(T=drawn["T"] + 40.0, gamma=1.3)
    vec = asm.pack(other)
    values = asm.values(vec)
    instance.setReal([refs[name] for name in values], list(values.values()))
    for _ in range(2):
        y = rest * (1.0 + 0.2 * rng.standard_normal(n))
        instance.setContinuousStates(pointer(y), n)
        rates, fmu_rates = np.zeros(n), np.zeros(n)
        kernel.rhs(0.0, 0.0, y, vec, sig, ptr, rates)
        instance.getDerivatives(pointer(fmu_rates), n)
        assert np.allclose(fmu_rates, rates, rtol=ref.FMU_KERNEL_RTOL, atol=0)
    acceleration = refs["der(velocity)"]
    column = instance.getDirectionalDerivative([acceleration], [refs["external_force"]], [1.0])
    assert column[0] == pytest.approx(-1.0 / values["m"], rel=ref.FMU_INPUT_JACOBIAN_RTOL)
    before = instance.getReal([acceleration])[0]
    instance.setReal([refs["external_force"]], [3.0])
    after = instance.getReal([acceleration])[0]
    assert after - before == pytest.approx(-3.0 / values["m"], rel=1e-9)
    instance.terminate()
    instance.freeInstance()


def test_gms_mode_switches_are_state_events(tmp_path):
    model = actuator("source", pa.GMS(n_elements=4))
    fmu = pa.export_fmu(model, tmp_path / "gms.fmu")
    assert (fmu.event_indicators, fmu.mode_switches) == (6, 4)  # the two stops, 4 blocks
    assert read_model_description(str(fmu.path)).numberOfEventIndicators == 6
    assert validate_fmu(str(fmu.path)) == []
    assert_runs_agree(model, fmu, pa.PressureCycle(period=5.0))


@pytest.fixture(scope="module")
def sources_only(tmp_path_factory):
    """The CLI's export without a binary (the default model, whose kernel the module's
    source FMU compiled): (the command's result, the file)."""
    path = tmp_path_factory.mktemp("cli") / "vgt.fmu"
    result = CliRunner().invoke(app, ["export", "fmu", "--no-binary", "--out", str(path)])
    return result, path


@pytest.mark.filterwarnings("ignore::ResourceWarning",  # FMPy's build leaves a temporary
                            "ignore::pytest.PytestUnraisableExceptionWarning")  # folder to GC
def test_the_sources_alone_build_with_the_importer_s_tool_chain(sources_only, tmp_path):
    """Exported without a binary, the FMU holds its C sources; FMPy's own (CMake) build
    of them gives a binary that runs."""
    result, path = sources_only
    assert result.exit_code == 0, result.output
    names = zipfile.ZipFile(path).namelist()
    assert "none (sources only)" in result.output
    assert not any(n.startswith("binaries/") for n in names)
    assert {"sources/model.c", "sources/model.h", "sources/fmu.c"} <= set(names)
    if shutil.which("cmake") is None:
        pytest.skip("cmake (FMPy's build tool) is not installed")
    from fmpy.build import build_platform_binary

    folder = fmpy.extract(str(path), str(tmp_path / "unzipped"))
    build_platform_binary(folder)
    out = fmpy.simulate_fmu(folder, stop_time=1.0, output=["position"])
    assert np.isfinite(out["position"]).all()


def test_no_compiler_is_one_clear_error_and_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "actuator.fmu"
    path.write_bytes(b"previous export")
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    with pytest.raises(ExportError, match=r"no C compiler found.*install"):
        pa.export_fmu(actuator("source"), path)
    assert path.read_bytes() == b"previous export"
    with pytest.raises(ExportError, match="'no-such-cc'"):
        pa.export_fmu(actuator("source"), path, compiler="no-such-cc")
    for inputs, words in (({"pressure": 60e3}, "not inputs of this FMU"),
                          ({"pressure_input": -1.0}, "pressure_input"),
                          ({"external_force": float("nan")}, "external_force")):
        with pytest.raises(pa.ArgumentError, match=words):
            pa.export_fmu(actuator("source"), path, inputs=inputs)
    assert path.read_bytes() == b"previous export"


def test_cli_exports_a_valid_fmu(sources_only, tmp_path):
    result, path = sources_only
    assert result.exit_code == 0, result.output
    assert "pressure_input" in result.output and f"wrote {path}" in " ".join(
        result.output.split())
    assert validate_fmu(str(path)) == []
    refused = CliRunner().invoke(app, ["export", "fmu", "--compiler", "no-such-cc",
                                       "--out", str(tmp_path / "b.fmu")])
    assert refused.exit_code == 2 and "no-such-cc" in refused.output
    assert not (tmp_path / "b.fmu").exists()
