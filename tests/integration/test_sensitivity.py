"""Sensitivity studies of the actuator on the batch engine, and the command line."""

from __future__ import annotations

import numpy as np
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from pneumact.cli import app
from pneumact.sensitivity import one_at_a_time

runner = CliRunner()
EXIT_USER_ERROR = 2


def test_one_at_a_time_with_zero_variation_returns_the_nominal_run(vgt):
    model = pa.Actuator(vgt, valve=pa.CommandValve())
    study = one_at_a_time(model, pa.CommandCycle(period=20.0), {"Fc": 0.0, "sigma0": 0.0})
    assert len(study.runs) == 3  # nominal, then one run per parameter (low = high)
    deltas = study.runs.filter(like="delta_").to_numpy()
    assert np.all(deltas == 0.0)
    assert np.all(study.runs["rms_position_change"] == 0.0)
    nominal = pa.simulate(model, pa.CommandCycle(period=20.0))
    assert np.array_equal(study.signals["position"][0], nominal["position"])


def test_one_at_a_time_ranks_coulomb_friction_first_for_loop_width(vgt):
    model = pa.Actuator(vgt, valve=pa.CommandValve())
    study = one_at_a_time(model, pa.CommandCycle(period=20.0))
    assert study.ranking("loop_width_pressure").index[0] == "Fc"
    assert study.plot_loops() is not None


def test_cli_sensitivity_oat_and_sobol(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["sensitivity", "oat", "--out", "oat"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "oat" / "loops.png").exists()
    assert (tmp_path / "oat" / "friction_velocity.png").exists()
    result = runner.invoke(app, ["sensitivity", "sobol", "--n", "16", "--out", "sobol"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "sobol" / "indices.csv").exists()
    result = runner.invoke(app, ["sensitivity", "sobol", "--variations", "Fc=30%,Fs=30%",
                                 "--n", "16", "--out", "bad"])
    assert result.exit_code == EXIT_USER_ERROR
    assert "Fs" in result.output and "runs failed" in result.output
    assert not (tmp_path / "bad").exists()


def test_cli_signals_convergence_and_resume(tmp_path, monkeypatch):
    import pandas as pd

    monkeypatch.chdir(tmp_path)
    args = ["sensitivity", "sobol", "--variations", "Fc=10%,sigma2=20%", "--n", "16",
            "--features", "loop_width_pressure", "--signals", "position", "--times", "11",
            "--convergence", "--out", "study"]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    for name in ("convergence.csv", "convergence_loop_width_pressure.png", "local_position.csv",
                 "indices_position.csv", "along_time_position.png", "along_loop_position.png"):
        assert (tmp_path / "study" / name).exists(), name
    convergence = pd.read_csv(tmp_path / "study" / "convergence.csv")
    assert sorted(convergence["n"].unique()) == [1, 2, 4, 8, 16]
    along = pd.read_csv(tmp_path / "study" / "indices_position.csv")
    assert along["output"].nunique() == 11
    first = pd.read_csv(tmp_path / "study" / "indices.csv")
    result = runner.invoke(app, args)  # the runs are kept: neither mixed nor redone silently
    assert result.exit_code == EXIT_USER_ERROR
    assert "--resume" in result.output
    result = runner.invoke(app, [*args, "--resume"])
    assert result.exit_code == 0, result.output
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "study" / "indices.csv"), first)


def test_position_indices_along_the_cycle(vgt):
    from pneumact import sensitivity as sa

    model = pa.Actuator(vgt, valve=pa.CommandValve())
    experiment = pa.CommandCycle(period=20.0)
    problem = sa.Problem.around(vgt, {"Fc": "10%", "sigma2": "20%"})
    times = np.linspace(6.0, 16.0, 5)  # while the diaphragm moves
    study = sa.src(problem, sa.model_signal(model, experiment, problem, "position", times),
                   n=64)
    curves = sa.along_time(study, "SRC2")
    assert curves.shape == (5, 2)
    assert curves.index.tolist() == times.tolist()
    assert np.all(curves["Fc"] > curves["sigma2"])  # Coulomb friction moves the loop


def test_sobol_on_dask_equals_local(vgt, dask_client):
    from pneumact import sensitivity as sa

    model = pa.Actuator(vgt, valve=pa.CommandValve())
    experiment = pa.CommandCycle(period=20.0)
    problem = sa.Problem.around(vgt, {"Fc": "10%", "Fs": "10%"})
    features = ["loop_width_pressure"]
    local = sa.sobol(problem, sa.model_outputs(model, experiment, problem, features), n=8)
    remote = sa.sobol(problem, sa.model_outputs(model, experiment, problem, features,
                                                executor=pa.Executor(scheduler=dask_client)), n=8)
    np.testing.assert_array_equal(remote.outputs.to_numpy(), local.outputs.to_numpy())


def test_dgsm_of_the_actuator_from_forward_sensitivities(vgt):
    from pneumact import sensitivity as sa

    model = pa.Actuator(vgt, valve=pa.CommandValve())
    problem = sa.Problem.around(vgt, {"Fc": "10%", "sigma1": "20%"})
    gradient = sa.model_gradient(model, pa.CommandCycle(period=20.0), problem, "position",
                                 [8.0, 12.0])
    study = sa.dgsm(problem, gradient, n=8)
    table = study.to_pandas(output="8.0")
    assert table.loc["Fc", "nu_scaled"] > 100 * table.loc["sigma1", "nu_scaled"]


def test_friction_velocity_curves_follow_the_varied_parameter(vgt):
    """Fig. 3: at |v| ≫ vs the friction is Fc + σ2·v, so ±15.36 % on Fc shifts the
    plateau by exactly 0.1536·Fc."""
    from pneumact.sensitivity import friction_velocity

    curves = friction_velocity(vgt, {"Fc": 0.1536, "sigma0": 0.0})
    (_, v0, f0), (_, _, f_low), (_, _, f_high) = curves.curves["Fc"]
    fast = v0 > 0.9 * v0.max()
    shift = 0.1536 * vgt["Fc"]
    assert np.allclose(f_high[fast] - f0[fast], shift, rtol=1e-3)
    assert np.allclose(f0[fast] - f_low[fast], shift, rtol=1e-3)
    (_, _, same), (_, _, low), (_, _, high) = curves.curves["sigma0"]
    assert np.array_equal(low, same) and np.array_equal(high, same)
    assert curves.plot() is not None


def test_local_sensitivities_along_time_match_differences(vgt):
    from pneumact import sensitivity as sa

    model = pa.Actuator(vgt, valve=pa.CommandValve())
    experiment = pa.CommandCycle(period=20.0)
    times = np.linspace(2.0, 18.0, 9)
    curves = sa.local_along_time(model, experiment, ["Fc", "k"], "position", times)
    scale = np.max(np.abs(pa.simulate(model, experiment, t_eval=times)["position"]))
    for name in ("Fc", "k"):
        step = 1e-2 * vgt[name]  # smaller steps drown in the solver tolerance
        up, down = (pa.simulate(model, experiment, t_eval=times,
                                values={name: vgt[name] + s * step})["position"]
                    for s in (1.0, -1.0))
        differences = vgt[name] * (up - down) / (2 * step) / scale
        error = np.max(np.abs(curves[name].to_numpy() - differences))
        assert error <= ref.LOCAL_FD_RTOL * np.max(np.abs(differences))
    assert sa.plot_along_time(curves) is not None
    assert sa.plot_along_loop(curves, np.arange(9.0), "pressure [kPa]") is not None


def test_indices_across_conditions_follow_the_sliding_speed(vgt):
    """Slow enough that the loop slides below vs, static friction matters as much as
    Coulomb friction; well above vs it does not (g(v) → Fc)."""
    from pneumact import sensitivity as sa

    model = pa.Actuator(vgt)
    study = sa.across_conditions(model, sa.conditions(periods=[20.0, 320.0]), "oat")
    speeds = study.conditions.set_index("condition")["speed_vs"]
    assert speeds["command, 20 s"] > 5 > 1 > speeds["command, 320 s"]
    width = study.index("loop_width_pressure")
    assert width.loc["command, 20 s", "Fs"] < 0.01 * width.loc["command, 20 s", "Fc"]
    assert width.loc["command, 320 s", "Fs"] > 0.5 * width.loc["command, 320 s", "Fc"]
    ranking = study.ranking("loop_width_pressure")
    assert ranking.loc["command, 320 s", "rank 1"] in ("Fc", "Fs")
    assert set(study.indices["condition"]) == set(speeds.index)
    assert study.plot("loop_width_pressure") is not None


def test_conditions_at_wanted_sliding_speeds(vgt):
    from pneumact import sensitivity as sa

    model = pa.Actuator(vgt)
    targets = [2 * vgt["vs"], 10 * vgt["vs"]]
    found = sa.at_speeds(model, targets, valve="regulator")
    for condition, target in zip(found, targets, strict=True):
        run = pa.simulate(condition.model(model), condition.experiment(vgt))
        speed = run.summary()["sliding_speed"]
        assert abs(speed / target - 1) <= 0.02
    assert found[0].period > found[1].period


def test_cli_sensitivity_across_conditions(tmp_path, monkeypatch):
    import pandas as pd

    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["sensitivity", "oat", "--conditions", "period=20,5min",
                                 "--conditions", "valve=command", "--out", "study"])
    assert result.exit_code == 0, result.output
    conditions = pd.read_csv(tmp_path / "study" / "conditions.csv")
    assert conditions["period"].tolist() == [20.0, 300.0]
    assert conditions["speed_vs"].is_monotonic_decreasing
    indices = pd.read_csv(tmp_path / "study" / "indices.csv")
    assert {"speed_vs", "output", "parameter", "relative_change"} <= set(indices.columns)
    for name in ("indices_loop_width_pressure_by_speed.png", "report.html"):
        assert (tmp_path / "study" / name).exists(), name
    for bad, message in ((["--conditions", "pace=20"], "AXIS"),
                         (["--conditions", "speed=3"], "has no unit"),
                         (["--conditions", "valve=pump"], "allowed"),
                         (["--conditions", "amplitude=2"], "amplitude = 2.0"),
                         (["--conditions", "period=20", "--t-end", "10"], "--t-end")):
        result = runner.invoke(app, ["sensitivity", "oat", *bad, "--out", "bad"])
        assert result.exit_code == EXIT_USER_ERROR, (bad, result.output)
        assert message in result.output, (bad, result.output)
        assert not (tmp_path / "bad").exists()


def test_zoomed_figures_keep_coinciding_curves_flat_and_show_the_loop_width(vgt):
    """Issue #40, item 6: Fig. 3's sliding-level zoom spans at least 10 % of the friction
    level (σ0's curves coincide there: no 1e-4 N axis), and Fig. 5 has a mid-stroke zoom
    whose position axis is a few loop widths, not the 17.7 mm stroke."""
    import matplotlib

    from pneumact.sensitivity import friction_velocity

    matplotlib.use("Agg")
    curves = friction_velocity(vgt, {"sigma0": 0.5}, amplitude=10 * vgt["vs"])
    fastest = curves.plot(zoom=True).axes[2]
    low, high = fastest.get_ylim()
    assert high - low >= 0.1 * vgt["Fc"]
    model = pa.Actuator(vgt, valve=pa.CommandValve())
    study = one_at_a_time(model, pa.CommandCycle(period=20.0), {"sigma0": 0.5})
    panels = {ax.get_title(): ax for ax in study.plot_loops(zoom=True).axes}
    low, high = panels["sigma0: mid-stroke"].get_ylim()
    width = 1e3 * study.runs["loop_width_position"].iloc[0]  # mm
    assert width < high - low < 8 * width
