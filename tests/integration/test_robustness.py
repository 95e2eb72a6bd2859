"""A frictionless actuator simulates; a batch row that raises fails alone; a failed run
leaves the previous results exactly as they were (and resumable); an overwrite leaves no
stale file of the run before."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import pneumact as pa
from pneumact.cli import app
from pneumact.errors import DataError, PassivityWarning, PneumactError
from pneumact.io.tables import partial_folder
from pneumact.simulation.batch import runner as batch_runner
from reference import FRICTIONLESS_FORCE_ATOL

DATA = Path(__file__).resolve().parents[1] / "data"
cli = CliRunner()


@pytest.fixture(scope="module")
def frictionless():
    """vgt-paper with Fc = Fs = 0 (tests/data/good/frictionless.toml)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        return pa.load_params(DATA / "good" / "frictionless.toml")


@pytest.mark.parametrize("law", [pa.LuGre(), pa.LuGre(decaying_damping=True), pa.Dahl(),
                                 pa.BoucWen(), pa.CoulombViscous(), pa.StribeckMap()])
def test_frictionless_law_is_viscous_only(frictionless, law):
    v = np.array([-0.3, -1e-3, 0.0, 2e-4, 0.5])
    values = law.evaluate(v, 0.0, frictionless)
    np.testing.assert_allclose(values["force"], frictionless["sigma2"] * v, atol=1e-12)
    np.testing.assert_array_equal(values["rates"], 0.0)
    assert all(np.all(np.isfinite(a)) for a in values.values())


def test_lugre_without_coulomb_level_stays_finite_far_above_vs(vgt):
    """Fc = 0: g(v) = Fs·exp(−|v|/vs) underflows to 0 at a few hundred vs; the law then
    takes its limit instead of dividing by zero."""
    params = vgt.replace(Fc=0.0)
    v = np.array([0.5, 1.0, 5.0])  # 1000 to 10000 vs
    values = pa.LuGre().evaluate(v, 0.0, params)
    assert all(np.all(np.isfinite(a)) for a in values.values())
    np.testing.assert_allclose(values["force"], params["sigma2"] * v)


@pytest.mark.parametrize("valve", [pa.PressureSource(), pa.CommandValve()])
def test_frictionless_actuator_simulates(frictionless, valve):
    actuator = pa.Actuator(frictionless, valve=valve)
    experiment = (pa.PressureCycle(period=2.0, n_points=201) if valve.drive == "pressure"
                  else pa.CommandCycle(period=2.0, n_points=201))
    result = pa.simulate(actuator, experiment)
    np.testing.assert_array_equal(result["bristle"], 0.0)
    np.testing.assert_allclose(result["friction"],
                               frictionless["sigma2"] * result["velocity"],
                               atol=FRICTIONLESS_FORCE_ATOL)
    assert np.ptp(result["position"]) > 0.01  # it moves through its stroke


def test_frictionless_row_of_a_batch_runs(vgt):
    model = pa.Actuator(vgt.replace(delta=2.0))
    table = pd.DataFrame({"Fc": [2.6, 0.0], "Fs": [3.2, 0.0]})
    batch = pa.simulate_batch(model, pa.PressureCycle(period=2.0, n_points=201), table,
                              features=["stroke", "loop_width_pressure"], executor=1)
    assert batch.table["status"].tolist() == ["ok", "ok"]
    width = batch.table["loop_width_pressure"]
    # without Coulomb friction only the viscous (and inertial) loop is left: at most a
    # fifth of the paper's (2·Fc/A_d = 1.78 kPa of it is Coulomb)
    assert width.iloc[1] < 0.2 * width.iloc[0]


def test_a_row_that_raises_is_that_row_s_error(vgt, monkeypatch):
    """Whatever a row's run raises (here a ZeroDivisionError on the row with Fc = 2.5)
    becomes its error; the rows beside it finish."""
    model = pa.Actuator(vgt.replace(delta=2.0))
    experiment = pa.PressureCycle(period=2.0, n_points=101)
    table = pd.DataFrame({"Fc": [2.4, 2.5, 2.6]})
    plain = pa.simulate_batch(model, experiment, table, features=["stroke"], executor=1)
    real = batch_runner.ChunkRunner._row

    def flaky(self, row, work, *rest):
        if row[0] == 2.5:
            raise ZeroDivisionError("division by zero")
        return real(self, row, work, *rest)

    monkeypatch.setattr(batch_runner.ChunkRunner, "_row", flaky)
    batch = pa.simulate_batch(model, experiment, table, features=["stroke"], executor=1)
    assert batch.table["status"].tolist() == ["ok", "error", "ok"]
    assert "ZeroDivisionError" in batch.table["error"].iloc[1]
    np.testing.assert_array_equal(batch.table["stroke"].iloc[[0, 2]],
                                  plain.table["stroke"].iloc[[0, 2]])
    assert np.isnan(batch.table["stroke"].iloc[1])


def _tree(folder: Path) -> dict[str, tuple[bytes, int]]:
    return {str(p.relative_to(folder)): (p.read_bytes(), p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_failed_overwrite_keeps_the_batch_exactly_and_resumable(vgt, tmp_path, monkeypatch):
    model = pa.Actuator(vgt.replace(delta=2.0))
    experiment = pa.PressureCycle(period=2.0, n_points=101)
    table = pd.DataFrame({"Fc": [2.3, 2.4, 2.5, 2.6]})
    out = tmp_path / "batch"
    first = pa.simulate_batch(model, experiment, table, checkpoint=out,
                              executor=pa.Executor(workers=1, chunk_size=1))
    before = _tree(out)
    calls = []
    real = batch_runner.ChunkRunner.run

    def fails_on_the_third_chunk(self, start, values):
        calls.append(start)
        if len(calls) == 3:
            raise DataError("the disk is full (simulated)")
        return real(self, start, values)

    monkeypatch.setattr(batch_runner.ChunkRunner, "run", fails_on_the_third_chunk)
    with pytest.raises(DataError, match="disk is full"):
        pa.simulate_batch(model, experiment, table,
                          checkpoint=pa.Checkpoint(out, overwrite=True),
                          executor=pa.Executor(workers=1, chunk_size=1))
    monkeypatch.undo()
    assert _tree(out) == before  # not one byte or time stamp changed
    assert not partial_folder(out).exists()
    again = pa.simulate_batch(model, experiment, table,
                              checkpoint=pa.Checkpoint(out, resume=True), executor=1)
    assert again.stats["computed"] == 0 and again.stats["reused_chunks"] == 4
    pd.testing.assert_frame_equal(again.table, first.table)


def test_failed_sensitivity_overwrite_keeps_the_runs_resumable(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    args = ["sensitivity", "sobol", "--n", "8", "--t-end", "2", "--variations",
            "Fc=10%,sigma2=20%", "--features", "loop_width_pressure", "--out", "study"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.invoke(app, args).exit_code == 0
        before = _tree(tmp_path / "study")
        failing = [a if a != "Fc=10%,sigma2=20%" else "Fc=30%,Fs=30%" for a in args]
        result = cli.invoke(app, [*failing, "--overwrite"])  # some runs have Fs < Fc
        assert result.exit_code == 2 and "runs failed" in result.output
        assert _tree(tmp_path / "study") == before
        resumed = cli.invoke(app, [*args, "--resume"])
    assert resumed.exit_code == 0, resumed.output
    assert "0 sims/s" in resumed.output or "32/32" in resumed.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study"]


def test_fit_without_multistart_removes_the_previous_starts(tmp_path):
    record = DATA / "good" / "record.csv"
    out = tmp_path / "fit"
    base = ["fit", str(record), "--free", "Fc", "--out", str(out)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        first = cli.invoke(app, [*base, "--multistart", "1"])
        assert first.exit_code == 0, first.output
        assert (out / "starts.csv").exists() and (out / "waterfall.png").exists()
        second = cli.invoke(app, base)
    assert second.exit_code == 0, second.output
    names = {p.name for p in out.iterdir()}
    assert "starts.csv" not in names and "waterfall.png" not in names
    assert {"estimates.csv", "report.html", "fit.png"} <= names


def test_offsets_with_multistart_fit(vgt):
    """A sensor offset has no bounds: each extra start begins it where the fit does,
    instead of refusing the multistart."""
    record = pa.read_record(DATA / "good" / "record.csv")
    result = pa.fit(pa.Actuator(vgt), record, ["Fc"], offsets=["position"], multistart=1,
                    executor=1)
    assert len(result.starts) == 2 and result.success
    assert set(result.starts["offset_position[0]_start"]) == {0.0}


def test_step_limit_follows_the_input():
    from pneumact.simulation.solvers import DEFAULT_MAX_STEPS, STEPS_PER_SEGMENT

    assert pa.Rodas4().step_limit(10) == DEFAULT_MAX_STEPS
    two_hours_at_1khz = 7_200_000
    assert pa.Rodas4().step_limit(two_hours_at_1khz) == STEPS_PER_SEGMENT * two_hours_at_1khz
    assert pa.Rodas4(max_steps=1000).step_limit(two_hours_at_1khz) == 1000


def test_friction_experiments_on_a_frictionless_rig(canudas):
    """Stick-slip runs without friction (the spring just pulls the mass); the tests that
    measure friction refuse a set that has none, saying so."""
    from pneumact.analysis.friction_tests import run_friction_test
    from pneumact.experiments.friction import Presliding, StickSlip

    params = canudas.replace(Fc=0.0, Fs=0.0)
    run = run_friction_test(StickSlip(t_end=2.0, samples_per_second=100), params)
    assert np.all(np.isfinite(run.result["position"]))
    with pytest.raises(PneumactError, match="measures friction"):
        run_friction_test(Presliding(t_end=1.0), params)


#: An interrupt that arrives while the command line is still being imported, made
#: deterministic: the import of pneumact.cli itself raises KeyboardInterrupt.
_INTERRUPTED_IMPORT = """
import sys

class Interrupt:
    @staticmethod
    def find_spec(name, path=None, target=None):
        if name == "pneumact.cli":
            raise KeyboardInterrupt
        return None

sys.meta_path.insert(0, Interrupt)
from pneumact.__main__ import main
main()
"""


def test_ctrl_c_while_the_command_line_imports_exits_130_without_a_traceback():
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _INTERRUPTED_IMPORT], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 130, done.stderr
    assert "Traceback" not in done.stderr and "interrupted" in done.stderr
