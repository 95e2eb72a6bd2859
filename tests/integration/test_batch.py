"""Batch engine: equals one-by-one simulation, isolates failures, Dask equality, resume, CLI."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
from pneumact.core import features as ft
from pneumact.errors import DataError, ParameterError, PassivityWarning
from pneumact.io.tables import partial_folder
from pneumact.simulation.batch import BatchResult, simulate_batch
from reference import BATCH_FEATURE_RTOL as FEATURE_RTOL

# --- tolerances and sizes (one block) --------------------------------------------------
N_SETS = 50  # sets compared with one-by-one simulation
N_DASK = 20  # sets run on the LocalCluster
N_RESUME = 24  # sets of the interrupted batch
RESUME_CHUNK = 4  # rows per chunk of the interrupted batch
SPREAD = 0.2  # ±20 % uniform around the vgt-paper values
KILL_TIMEOUT_S = 120.0  # wait this long at most for the first chunk file of the subprocess
FAIL_MAX_STEPS = 5000  # a normal 2 s cycle needs ~900 steps; sigma0 = 1e12 needs far more

# The set-up shared by the test process and the subprocess of the resume test.
SETUP = """
import warnings
import numpy as np, pandas as pd
import pneumact as pa
warnings.simplefilter("ignore", pa.PassivityWarning)
params = pa.load_params("vgt-paper").replace(delta=2.0)
model = pa.Actuator(params)
experiment = pa.PressureCycle(high=100e3, low=20e3, period=2.0, n_points=1001)

def random_table(n, seed, spread=0.2):
    rng = np.random.default_rng(seed)
    names = ["sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs", "F0", "k"]
    table = pd.DataFrame({k: params[k] * rng.uniform(1 - spread, 1 + spread, n)
                          for k in names})
    table["Fs"] = np.maximum(table["Fs"], table["Fc"])
    return table
"""
NS: dict = {}
exec(SETUP, NS)
PARAMS, MODEL, EXPERIMENT, random_table = (NS["params"], NS["model"], NS["experiment"],
                                           NS["random_table"])
SRC = str(Path(pa.__file__).resolve().parents[1])


def one_by_one_features(row: pd.Series) -> dict[str, float]:
    """The same features from a plain simulate() of one set."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        model = pa.Actuator(PARAMS.replace(**row.to_dict()))
    r = pa.simulate(model, EXPERIMENT)
    out = {"final_position": float(r["position"][-1]),
           "max_velocity": float(np.max(np.abs(r["velocity"])))}
    out.update(ft.hysteresis_summary(r.time, r["pressure"], r["position"]))
    return out


def assert_close(a: float, b: float, rtol: float, what: str) -> None:
    if np.isnan(a) and np.isnan(b):
        return
    assert abs(a - b) <= rtol * max(abs(a), abs(b), 1e-300), f"{what}: {a!r} != {b!r}"


def test_batch_equals_simulate_one_by_one():
    table = random_table(N_SETS, seed=1, spread=SPREAD)
    seen = []
    batch = simulate_batch(MODEL, EXPERIMENT, table,
                           progress=lambda p: seen.append((p.done, p.failed, p.total)))
    assert isinstance(batch, BatchResult)
    assert (batch.table["status"] == "ok").all(), batch.failed
    assert batch.failed.empty
    assert seen[-1] == (N_SETS, 0, N_SETS)
    assert batch.stats["computed"] == N_SETS and batch.stats["sims_per_s"] > 0
    pd.testing.assert_frame_equal(batch.table[table.columns], table)
    for i in range(N_SETS):
        expected = one_by_one_features(table.iloc[i])
        for name, value in expected.items():
            assert_close(batch.table[name].iloc[i], value, FEATURE_RTOL, f"set {i} {name}")
    # physics sanity: the loop is there and widens with Coulomb friction
    width = batch.table["loop_width_pressure"].to_numpy()
    assert np.all(width > 0)
    assert np.corrcoef(table["Fc"], width)[0, 1] > 0.5


def test_signals_on_requested_grid_match_simulate():
    table = random_table(3, seed=2)
    t_eval = np.linspace(0.0, 2.0, 201)
    batch = simulate_batch(MODEL, EXPERIMENT, table, signals=["position", "pressure"],
                           features=["stroke"], t_eval=t_eval, executor=1)
    assert batch.signals["position"].shape == (3, t_eval.size)
    np.testing.assert_array_equal(batch.time, t_eval)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        r = pa.simulate(pa.Actuator(PARAMS.replace(**table.iloc[1].to_dict())), EXPERIMENT,
                        t_eval=t_eval)
    np.testing.assert_array_equal(batch.signals["position"][1], r["position"])
    np.testing.assert_array_equal(batch.signals["pressure"][1], r["pressure"])


@pytest.mark.numba
def test_a_read_only_time_grid_runs_the_integrator_already_compiled():
    """numba types a read-only array apart from a writeable one: a Record's time (read
    only) as t_eval must run the kernel's integrator compiled for writeable times, not
    compile it a second time (~3-6 s per kernel)."""
    from pneumact.simulation import assemble

    t_eval = np.linspace(0.0, 2.0, 201)
    frozen = t_eval.copy()
    frozen.setflags(write=False)
    runs = [pa.simulate(MODEL, EXPERIMENT, t_eval=t, engine="numba") for t in (t_eval, frozen)]
    np.testing.assert_array_equal(runs[0]["position"], runs[1]["position"])
    integrate = getattr(assemble(MODEL).numba_kernel, pa.Rodas4().kernel_function)
    assert len(integrate.signatures) == 1, integrate.signatures


def test_invalid_and_failing_sets_fail_alone():
    table = random_table(6, seed=3)
    table.loc[1, "F0"] = np.nan
    table.loc[2, "Fs"] = 0.5 * table.loc[2, "Fc"]  # Fs < Fc
    table.loc[3, "sigma0"] = 1e12  # valid but absurd: far too many steps
    table["m"] = PARAMS["m"]
    table.loc[4, "m"] = -1.0  # negative mass
    batch = simulate_batch(MODEL, EXPERIMENT, table,
                           solver=pa.Rodas4(max_steps=FAIL_MAX_STEPS))
    status = batch.table["status"].tolist()
    assert status == ["ok", "invalid", "invalid", "solver", "invalid", "ok"]
    errors = batch.table["error"]
    assert "F0" in errors[1] and "finite" in errors[1]
    assert "Fs" in errors[2] and ">= Fc" in errors[2]
    assert "maximum number of steps" in errors[3]
    assert "m = -1 kg" in errors[4] and ">= 1e-09" in errors[4]
    assert list(batch.failed.index) == [1, 2, 3, 4]
    assert batch.table.loc[[1, 2, 3, 4], "stroke"].isna().all()
    good = one_by_one_features(table.drop(columns="m").iloc[5])
    assert_close(batch.table["stroke"].iloc[5], good["stroke"], FEATURE_RTOL, "stroke")


def test_bad_table_and_names_are_refused():
    with pytest.raises(ParameterError, match="did you mean 'sigma0'"):
        simulate_batch(MODEL, EXPERIMENT, pd.DataFrame({"sigma_0": [1e5]}))
    with pytest.raises(ParameterError, match=r"unknown feature 'strok'.*'stroke'"):
        simulate_batch(MODEL, EXPERIMENT, pd.DataFrame({"Fc": [2.0]}), features=["strok"])
    with pytest.raises(ParameterError, match="reference"):
        simulate_batch(MODEL, EXPERIMENT, pd.DataFrame({"Fc": [2.0]}), features=["rms_error"])


def test_reference_enables_rms_error():
    table = pd.DataFrame({"Fc": [PARAMS["Fc"], 1.2 * PARAMS["Fc"]]})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        ref = pa.simulate(MODEL, EXPERIMENT)
    batch = simulate_batch(MODEL, EXPERIMENT, table, reference=(ref.time, ref["position"]),
                           executor=1)
    assert batch.table["rms_error"].iloc[0] == 0.0  # the reference itself
    assert batch.table["rms_error"].iloc[1] > 0.0


def test_dask_local_cluster_gives_identical_results(dask_client):
    table = random_table(N_DASK, seed=4)
    local = simulate_batch(MODEL, EXPERIMENT, table, signals=["position"],
                           features=["stroke", "loop_area", "breakaway_pressure"])
    remote = simulate_batch(MODEL, EXPERIMENT, table, signals=["position"],
                            features=["stroke", "loop_area", "breakaway_pressure"],
                            executor=pa.Executor(scheduler=dask_client))
    assert remote.stats["workers"] == 2 and remote.stats["chunks"] > 1
    pd.testing.assert_frame_equal(remote.table, local.table, check_exact=True)
    np.testing.assert_array_equal(remote.signals["position"], local.signals["position"])


def _chunk_files(out: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in sorted((out / "chunks").glob("chunk-*"))}


def test_killed_batch_resumes_and_matches(tmp_path):
    out = tmp_path / "run"
    script = SETUP + f"""
import time
from pneumact.options import Executor
from pneumact.simulation.batch import simulate_batch
simulate_batch(model, experiment, random_table({N_RESUME}, seed=5), checkpoint={str(out)!r},
               executor=Executor(workers=1, chunk_size={RESUME_CHUNK}),
               progress=lambda *a: time.sleep(0.5))
"""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [
        SRC, os.environ.get("PYTHONPATH")]))}
    proc = subprocess.Popen([sys.executable, "-c", script], env=env)
    try:
        deadline = time.monotonic() + KILL_TIMEOUT_S
        kept = partial_folder(out)  # an unfinished batch is built beside its folder
        while not list((kept / "chunks").glob("chunk-*.parquet")):
            assert proc.poll() is None, "the batch subprocess ended before writing a chunk"
            assert time.monotonic() < deadline, "no chunk file appeared"
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait()
    before = _chunk_files(kept)
    n_chunks = N_RESUME // RESUME_CHUNK
    assert 1 <= len(before) < n_chunks
    assert not out.exists()  # only a complete batch takes the folder

    table = random_table(N_RESUME, seed=5)
    resumed = simulate_batch(MODEL, EXPERIMENT, table,
                             checkpoint=pa.Checkpoint(out, resume=True), executor=1)
    assert resumed.stats["reused_chunks"] == len(before)
    assert resumed.stats["computed_chunks"] == n_chunks - len(before)
    assert resumed.stats["computed"] == N_RESUME - RESUME_CHUNK * len(before)
    after = _chunk_files(out)
    assert len(after) == n_chunks and not kept.exists()
    assert all(after[name] == mtime for name, mtime in before.items())  # not rewritten

    fresh = simulate_batch(MODEL, EXPERIMENT, table)
    pd.testing.assert_frame_equal(resumed.table, fresh.table, check_exact=True)
    on_disk = pd.read_parquet(out / "results.parquet")
    np.testing.assert_array_equal(on_disk["stroke"], fresh.table["stroke"])
    summary = pd.read_csv(out / "summary.csv")
    assert len(summary) == N_RESUME and "status" in summary.columns

    again = simulate_batch(MODEL, EXPERIMENT, table,  # all reused
                           checkpoint=pa.Checkpoint(out, resume=True))
    assert again.stats["computed"] == 0
    pd.testing.assert_frame_equal(again.table, fresh.table, check_exact=True)


def test_existing_batch_is_not_reused_without_resume(tmp_path):
    table = random_table(4, seed=7)
    first = simulate_batch(MODEL, EXPERIMENT, table, checkpoint=tmp_path, executor=1)
    with pytest.raises(DataError, match=r"already holds this batch.*resume.*overwrite"):
        simulate_batch(MODEL, EXPERIMENT, table, checkpoint=tmp_path, executor=1)
    again = simulate_batch(MODEL, EXPERIMENT, table,
                           checkpoint=pa.Checkpoint(tmp_path, overwrite=True), executor=1)
    assert again.stats["computed"] == 4 and again.stats["reused_chunks"] == 0
    pd.testing.assert_frame_equal(again.table, first.table, check_exact=True)


def test_gamma_column_with_adiabatic_chamber_equals_one_by_one(vgt):
    """The polytropic index is derived from γ in the kernel for every row (it used to be
    fixed in Python when the vector was built)."""
    model = pa.Actuator(vgt, valve=pa.CommandValve(), chamber=pa.Adiabatic())
    experiment = pa.CommandCycle(period=2.0, n_points=501)
    table = pd.DataFrame({"gamma": [1.2, 1.4, 1.6]})
    batch = simulate_batch(model, experiment, table, signals=["pressure"], executor=1)
    for i, gamma in enumerate(table["gamma"]):
        one = pa.simulate(pa.Actuator(vgt.replace(gamma=gamma), valve=pa.CommandValve(),
                                      chamber=pa.Adiabatic()), experiment)
        np.testing.assert_array_equal(batch.signals["pressure"][i], one["pressure"])
    assert np.ptp(batch.signals["pressure"][0] - batch.signals["pressure"][2]) > 100.0


def test_manifest_mismatch_is_refused(tmp_path):
    table = random_table(4, seed=6)
    simulate_batch(MODEL, EXPERIMENT, table, checkpoint=tmp_path, executor=1)
    changed = table.copy()
    changed.loc[0, "Fc"] *= 1.01
    with pytest.raises(DataError, match=r"different batch.*table"):
        simulate_batch(MODEL, EXPERIMENT, changed,
                       checkpoint=pa.Checkpoint(tmp_path, resume=True))
    with pytest.raises(DataError, match=r"different batch.*features"):
        simulate_batch(MODEL, EXPERIMENT, table, checkpoint=tmp_path, features=["stroke"])


def test_cli_end_to_end(tmp_path):
    from typer.testing import CliRunner

    from pneumact.cli import app

    csv = tmp_path / "sets.csv"
    csv.write_text("Fc [N],Fs [N],sigma1\n2.6,3.2,214\n2.0,3.0,100\n3.0,2.0,214\n")
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["simulate-batch", str(csv), "--out", str(out), "--t-end", "2",
                                      "--features", "stroke,loop_width_pressure",
                                      "--signals", "position", "--workers", "2"])
    assert result.exit_code == 0, result.output
    summary = pd.read_csv(out / "summary.csv")
    assert summary["status"].tolist() == ["ok", "ok", "invalid"]
    assert summary["stroke [m]"].iloc[0] > 5e-3
    signals = pd.read_parquet(out / "signals.parquet")
    assert set(signals.columns) == {"row", "time", "position"}
    assert len(signals) == 3 * 4001
    assert (out / "results.parquet").exists()

    bad = tmp_path / "bad.csv"
    bad.write_text("Fcc\n2.0\n")
    result = CliRunner().invoke(app, ["simulate-batch", str(bad), "--out", str(tmp_path / "o2")])
    assert result.exit_code == 2
    assert "did you mean 'Fc'" in result.output
