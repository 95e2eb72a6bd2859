"""Controller synthesis: gains as parameters (batches, sensitivities through the
controller and its jumps), the tuner's metrics against loop_metrics, the Canudas (1995)
known answer and a robust design on samples it was not tuned on."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from pneumact.control import (
    PID,
    Cascade,
    ClosedLoop,
    Move,
    Specs,
    canudas_hunting,
    evaluate_design,
    load_gains,
    loop_metrics,
    step_metrics,
    tune,
)
from pneumact.errors import ParameterError
from pneumact.identification import Estimates

pytestmark = pytest.mark.integration


def test_gains_are_parameters_in_the_plant_s_units(canudas, vgt):
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    loop = ClosedLoop(rig, PID(kp=3.0, ki=4.0, kd=6.0, derivative="velocity"))
    assert loop.gains == {"kp": 3.0, "ki": 4.0, "kd": 6.0, "tracking_time": 1.5 ** 0.5,
                          "velocity_ff": 0.0}
    assert loop.gain_units["kp"] == "N/m" and loop.gain_units["kd"] == "N*s/m"
    regulator = ClosedLoop(pa.Actuator(vgt, valve=pa.PressureRegulator()), PID(kp=5e6))
    assert regulator.gain_units["kp"] == "Pa/m"
    command = ClosedLoop(pa.Actuator(vgt, valve=pa.CommandValve()), PID(kp=200.0, ki=1.0))
    assert command.gain_units["ki"] == "1/(m*s)"
    cascade = ClosedLoop(rig, Cascade(kx=5.0, kv=2.0, ki=1.0))
    assert {"kx", "kv", "ki"} <= set(cascade.gains) and "kp" not in cascade.gains
    assert cascade.controller.with_parameters(kv=3.0).kv == 3.0
    # a filtered derivative's filter is a parameter; PID(kd=0) has no derivative
    assert "filter_time" in PID(kp=1.0, kd=1.0).parameters()
    assert "kd" not in PID(kp=1.0).parameters()


@pytest.mark.parametrize("sample_time", [None, 0.01], ids=["continuous", "sampled"])
def test_sensitivities_pass_through_the_controller(canudas, sample_time):
    """∂x/∂(kp, ki, kd, Fc) of the Canudas loop against central differences; sampled: the
    sensitivities jump with the controller (s⁺ = ∂jump/∂y·s⁻ + ∂jump/∂θ)."""
    loop, _ = canudas_hunting(canudas, sample_time=sample_time)
    experiment = pa.experiments.SetpointStep(0.0, 1.0, 0.1, 3.0, n_points=301)
    names = ["kp", "ki", "kd", "Fc"]
    sens = pa.simulate_sensitivities(loop, experiment, names, pa.Rodas4(rtol=1e-9))
    assert sens.units["kp"] == "N/m"
    for k, name in enumerate(names):
        value = sens.values[k]
        h = 1e-4 * abs(value)
        up, down = (pa.simulate(loop, experiment, pa.Rodas4(rtol=1e-10),
                                values={name: value + sign * h})["position"]
                    for sign in (1.0, -1.0))
        fd = (up - down) / (2 * h)
        err = np.max(np.abs(sens["position"][:, k] - fd)) / np.max(np.abs(fd))
        assert err < ref.LOOP_SENSITIVITY_RTOL, (name, err)


def test_step_metric_gradients_are_the_metrics_central_differences(canudas):
    """∂(rise, settling, overshoot, steady-state error, IAE)/∂(kp, ki, kd) of a Canudas
    step from the position's sensitivities, against central differences of the metrics
    of whole runs; the tuner's cost and its gradient from them against its batch cost."""
    from pneumact.control import step_metric_gradients
    from pneumact.control.tuning import _Evaluator, _holding

    loop, _ = canudas_hunting(canudas)
    loop = dataclasses.replace(loop, controller=PID(kp=100.0, ki=50.0, kd=20.0,
                                                    filter_time=0.02))
    move = Move("step", 0.0, 0.1, 8.0)
    specs = Specs.parse("settling=2,overshoot=0.3%,error=1mm")
    experiment = move.experiment()
    kw = {"t_step": move.t_ref, "start": move.start, "target": move.stop,
          "tol": move.tolerance(specs), "window": move.window()}
    names = ["kp", "ki", "kd"]
    solver = pa.Rodas4(rtol=1e-9)
    sens = pa.simulate_sensitivities(loop, experiment, names, solver)
    run = sens.result
    slopes = step_metric_gradients(run.time, run["position"], run["position_setpoint"],
                                   sens["position"], **kw)
    for k, name in enumerate(names):
        h = 1e-4 * sens.values[k]
        up, down = (pa.simulate(loop, experiment, solver, values={name: sens.values[k] + d})
                    for d in (h, -h))
        metrics = [step_metrics(r.time, r["position"], r["position_setpoint"], **kw)
                   for r in (up, down)]
        for key in ("rise_time", "settling_time", "overshoot", "steady_state_error", "iae"):
            fd = float(metrics[0][key][0] - metrics[1][key][0]) / (2 * h)
            assert slopes[key][k] == pytest.approx(fd, rel=ref.METRIC_GRADIENT_RTOL,
                                                   abs=1e-12), (key, name)
    samples = pd.DataFrame({"Fs": [1.5, 1.8]})
    moves = (move,)
    evaluator = _Evaluator(loop, specs, moves, tuple(names), samples,
                           _holding(loop, samples, moves), None, None, 0.05)
    gains = np.array([100.0, 50.0, 20.0])
    cost, gradient = evaluator.cost_and_gradient(gains, np.arange(2))
    assert cost == pytest.approx(evaluator.cost(gains[None, :], np.arange(2))[0], rel=1e-9)
    violated = evaluator.violations(evaluator.metrics(gains[None, :], np.arange(2)), 0.05)
    assert violated[:, 0, 1].min() > 0  # the overshoot spec is missed: a slope to follow
    for k in range(3):
        h = np.zeros(3)
        h[k] = 1e-4 * gains[k]
        up, down = evaluator.cost(np.vstack([gains + h, gains - h]), np.arange(2))
        assert gradient[k] == pytest.approx((up - down) / (2 * h[k]),
                                            rel=ref.METRIC_GRADIENT_RTOL), names[k]


def test_a_batch_row_of_gains_is_the_controller_with_those_gains(canudas):
    loop, _ = canudas_hunting(canudas)
    experiment = pa.experiments.SetpointStep(0.0, 1.0, 0.1, 5.0, n_points=201)
    table = pd.DataFrame({"kp": [2.0, 6.0], "ki": [1.0, 4.0]})
    batch = pa.simulate_batch(loop, experiment, table, signals=["position"], features=())
    for i, row in table.iterrows():
        own = dataclasses.replace(loop, controller=loop.controller.with_parameters(
            kp=row["kp"], ki=row["ki"]))
        single = pa.simulate(own, experiment)["position"]
        np.testing.assert_allclose(batch.signals["position"][i], single, rtol=1e-12,
                                   atol=1e-15)
    assert batch.units["kp"] == "N/m"


def test_the_tuner_s_metrics_are_loop_metrics(canudas):
    """step_metrics (all rows at once) equals loop_metrics run by run."""
    loop, _ = canudas_hunting(canudas)
    move = Move("step", 0.0, 1.0, 20.0)
    table = pd.DataFrame({"kp": [3.0, 10.0, 40.0], "ki": [4.0, 1.0, 2.0]})
    batch = pa.simulate_batch(loop, move.experiment(), table, features=(),
                              signals=["position", "command", "position_setpoint"])
    found = step_metrics(batch.time, batch.signals["position"],
                         batch.signals["position_setpoint"][0], batch.signals["command"],
                         t_step=move.t_ref, start=0.0, target=1.0, tol=0.05,
                         window=move.window())
    for i in range(len(table)):
        frame = pd.DataFrame({"time": batch.time, **{s: batch.signals[s][i] for s in (
            "position", "command", "position_setpoint")}})
        expected = loop_metrics(frame, t_step=move.t_ref, start=0.0, target=1.0, band=0.05,
                                window=move.window())
        for name, values in found.items():
            np.testing.assert_allclose(values[i], getattr(expected, name), rtol=1e-12,
                                       err_msg=name)


def test_the_tuned_canudas_pid_does_not_hunt_where_the_published_gains_do(canudas):
    """Canudas de Wit et al. (1995): Kp = 3, Ki = 4, Kv = 6 hunt around xd = 1 m; the
    PID tuned for no hunting from those gains does not (loop_metrics over 100 s)."""
    loop, experiment = canudas_hunting(canudas)
    published = loop_metrics(pa.simulate(loop, experiment))
    assert published.hunting
    specs = Specs.parse("settling=10,error=5mm,no-hunting")
    result = tune(loop, specs, moves=(Move("Canudas step", 0.0, 1.0, 60.0),),
                  n_global=16, max_evaluations=20, seed=1)
    assert result.meets_specs
    tuned = loop_metrics(pa.simulate(result.loop, experiment))
    assert not tuned.hunting
    assert tuned.limit_cycle_amplitude < 0.02 * published.limit_cycle_amplitude


def test_a_robust_design_meets_its_specs_on_fresh_samples(canudas, tmp_path):
    """Tuned over 20 draws of an identification's uncertainty (Fc, Fs, σ0: 15 %), the
    design meets the specs on ≥ 95 % of them and on most of 40 draws it never saw."""
    loop, _ = canudas_hunting(canudas)
    names = ("Fc", "Fs", "sigma0")
    values = np.array([float(canudas[n]) for n in names])
    stderr = 0.15 * values
    estimates = Estimates(names, values, stderr, np.diag(stderr ** 2), 100)
    specs = Specs.parse("settling=4,overshoot=10%,error=5mm,no-hunting,fraction=95%")
    moves = (Move("step", 0.0, 1.0, 20.0), Move("small step", 0.0, 0.05, 20.0))
    result = tune(loop, specs, moves=moves, uncertainty=estimates, samples=20,
                  n_global=16, max_evaluations=24, seed=2, spread=300.0)
    assert result.meets_specs, result.spread_table()
    fresh = evaluate_design(result.loop, specs, moves=moves, uncertainty=estimates,
                            samples=40, seed=99)
    assert fresh.met >= ref.FRESH_SAMPLES_MET, fresh.spread_table()
    published = evaluate_design(loop, specs, moves=moves, uncertainty=estimates,
                                samples=40, seed=99)
    assert published.met < 0.5  # the hunting gains fail: the check can fail
    # the gains file gives the tuned controller back
    written = result.write(tmp_path / "tuned")
    assert {p.name for p in written} >= {"gains.toml", "report.html", "spread.csv",
                                         "tuning.png"}
    assert load_gains(tmp_path / "tuned" / "gains.toml").parameters() == pytest.approx(
        result.controller.parameters(), rel=1e-15)


def test_uncertainty_samples_are_plants_that_can_exist(canudas):
    """Fc and Fs drawn 25 % wide overlap: a tenth of the normal's draws have Fs < Fc, a
    plant that cannot exist (the batch refuses it, and a robust design counted it as a
    failure). The draws are truncated to valid sets; a table with such a row is refused
    by row; a distribution almost all outside is refused."""
    from pneumact.control import draw_samples

    loop, _ = canudas_hunting(canudas)
    values = np.array([canudas["Fc"], canudas["Fs"]])
    cov = np.diag((0.25 * values) ** 2)
    estimates = Estimates(("Fc", "Fs"), values, np.sqrt(np.diag(cov)), cov, 100)
    raw = np.random.default_rng(0).multivariate_normal(values, cov, size=200)
    assert np.mean(raw[:, 1] < raw[:, 0]) > 0.05  # the untruncated draws break Fs >= Fc
    drawn = draw_samples(estimates, 200, seed=0, base=canudas.values)
    assert len(drawn) == 200 and (drawn["Fs"] >= drawn["Fc"]).all()
    table = drawn.head(3).copy()
    table.loc[1, "Fs"] = 0.5 * table.loc[1, "Fc"]
    with pytest.raises(ParameterError, match=r"1 of 3 uncertainty samples .*row 1: Fs ="):
        tune(loop, "settling=10", uncertainty=table)
    far = Estimates(("Fc", "Fs"), np.array([2.0, 0.2]), np.array([0.01, 0.01]),
                    np.diag([1e-4, 1e-4]), 100)
    with pytest.raises(ParameterError, match="valid parameter sets"):
        draw_samples(far, 10)


def test_a_design_that_misses_says_where_and_on_which_plants(canudas):
    """The published (hunting) Canudas gains over Fs samples: the result does not meet
    the specs and says so, with the failing samples, what they miss in words, and which
    parameter they share; the tuned design's statement is that it meets them."""
    loop, _ = canudas_hunting(canudas)
    samples = pd.DataFrame({"Fs": np.linspace(1.0, 2.0, 11)})
    specs = Specs.parse("settling=10,error=5mm,no-hunting,fraction=90%")
    moves = (Move("step", 0.0, 1.0, 60.0),)
    published = evaluate_design(loop, specs, moves=moves, uncertainty=samples)
    assert not published.meets_specs
    failing = published.failing_table()
    assert len(failing) == round((1 - published.met) * len(published.samples)) > 0
    hunting = published.metrics_table["violates_hunting"] > 0
    assert failing["misses"].str.contains("step: hunts").sum() == hunting.sum() > 0
    assert failing["misses"].str.contains("step: error").all()
    text = published.feasibility()
    assert text.startswith("Does NOT meet the specs on 90 % of the 12 samples")
    assert f"step hunting on {hunting.sum()}" in text
    assert "90 % of the samples hold step settling at no limit" in text
    met = pd.DataFrame({"Fs": [1.5]})
    tuned = tune(loop, specs, moves=moves, uncertainty=met, n_global=16,
                 max_evaluations=20, seed=1)
    assert tuned.meets_specs and tuned.feasibility().startswith("Meets every spec")
    assert tuned.failing_table().empty


def test_bad_tuning_input_is_one_clear_message(canudas):
    loop, _ = canudas_hunting(canudas)
    with pytest.raises(ParameterError, match="'speed' is not a specification"):
        Specs.parse("speed=3")
    with pytest.raises(ParameterError, match="overshoot = 'five'"):
        Specs.parse("overshoot=five")
    with pytest.raises(ParameterError, match="nothing to meet"):
        Specs()
    with pytest.raises(ParameterError, match=r"gains \['kx'\] are not parameters"):
        tune(loop, "settling=1", gains=["kx"])
    with pytest.raises(ParameterError, match="samples = 0"):
        tune(loop, "settling=1", samples=0)
    assert Specs.parse("settling=300ms,error=20um,no-hunting") == Specs(
        settling=0.3, error=20e-6, no_hunting=True)


def test_the_command_line_tunes_and_control_step_runs_the_gains_file(tmp_path):
    from typer.testing import CliRunner

    from pneumact.cli import app

    runner = CliRunner()
    rig = ["--plant", "rig", "--params", "canudas1995"]
    tuned = runner.invoke(app, ["control", "tune", *rig, "--kp", "3", "--ki", "4",
                                "--spec", "settling=10,no-hunting", "--n-global", "4",
                                "--max-evaluations", "6", "--at", "0",
                                "--out", str(tmp_path / "tune")])
    assert tuned.exit_code == 0, tuned.output
    assert (tmp_path / "tune" / "gains.toml").is_file()
    step = runner.invoke(app, ["control", "step", *rig, "--start", "0", "--stop", "100",
                               "--t-end", "20", "--gains-file",
                               str(tmp_path / "tune" / "gains.toml"),
                               "--out", str(tmp_path / "step")])
    assert step.exit_code == 0, step.output
    frame = pd.read_csv(tmp_path / "step" / "metrics.csv")
    assert set(frame["metric"]) >= {"settling_time", "overshoot"}
