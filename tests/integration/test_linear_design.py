"""The linear PID design (python-control) and designs side by side on the nonlinear loop
(issue 23, items 4 and 5):

- without friction (a mass-damper) the python-control design's predicted step metrics
  are the nonlinear model's, and tuning the nonlinear loop from it keeps meeting the
  specs with metrics python-control predicts for the tuned gains too;
- on the Canudas (1995) rig the linear design meets the specs on the linear model but
  friction breaks it on the nonlinear one: the small step sticks short and the step
  creeps into the band (or stops past it); tuning on the nonlinear loop meets them;
- bad input is refused by name.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import pneumact as pa
from pneumact.control import (
    PID,
    Cascade,
    ClosedLoop,
    Move,
    Specs,
    canudas_hunting,
    load_gains,
    tune,
)
from pneumact.control.comparison import compare_designs, friction_designs
from pneumact.control.linear_design import linear_design
from pneumact.errors import ParameterError
from pneumact.parameters import ParameterSet
from reference import (
    CANUDAS_DESIGN_SPECS,
    LINEAR_DESIGN_OVERSHOOT_POINTS,
    LINEAR_DESIGN_SETTLING_RTOL,
    LINEAR_DESIGN_SPECS,
    LINEAR_LOOP_MASS_DAMPER,
    LINEAR_TUNED_GAIN_FACTOR,
)

pytest.importorskip("control")

STEP = 0.1  # m
MOVES = (Move("step", 0.0, STEP, 4.0),)


@pytest.fixture(scope="module")
def frictionless():
    """A mass-damper (CoulombViscous with Fc = 0: σ2·v exactly) under a PID."""
    m, c = LINEAR_LOOP_MASS_DAMPER
    params = ParameterSet.from_dict({"m": m, "Fc": 0.0, "sigma2": c}, name="mass-damper")
    rig = pa.FrictionRig(params, pa.CoulombViscous(), drive="force")
    loop = ClosedLoop(rig, PID(kp=1.0, ki=1.0, kd=1.0, filter_time=0.01))
    return loop, linear_design(loop, LINEAR_DESIGN_SPECS, velocity=0.1)


def _linear_metrics(design, loop):
    """python-control's step metrics of ``loop``'s gains on ``design``'s linear plant."""
    import control

    again = dataclasses.replace(design, loop=loop)
    t = np.linspace(0.0, 4.0 - MOVES[0].t_ref, 8001)
    step = np.asarray(control.step_response(again.closed_loop(), T=t).outputs).ravel()
    info = control.step_info(step, T=t, yfinal=1.0,
                             SettlingTimeThreshold=Specs.parse(LINEAR_DESIGN_SPECS).band)
    return info["Overshoot"], info["SettlingTime"]


def _nonlinear_metrics(loop):
    row = compare_designs(loop, LINEAR_DESIGN_SPECS, {"design": loop}, moves=MOVES).table.iloc[0]
    return row["overshoot"], row["settling_time"], bool(row["meets_specs"])


def test_without_friction_the_model_does_what_python_control_predicts(frictionless):
    _, design = frictionless
    assert design.meets_specs, design.predicted_table()
    assert design.predicted["phase_margin"] > 30.0
    overshoot, settling, meets = _nonlinear_metrics(design.loop)
    assert meets
    assert overshoot == pytest.approx(design.predicted["overshoot"],
                                      abs=LINEAR_DESIGN_OVERSHOOT_POINTS)
    assert settling == pytest.approx(design.predicted["settling_time"],
                                     rel=LINEAR_DESIGN_SETTLING_RTOL)


def test_tuning_without_friction_agrees_with_python_control(frictionless):
    """Tuned on the nonlinear (here linear) loop from the python-control design, the
    gains still meet the specs, and python-control predicts the tuned loop's metrics."""
    _, design = frictionless
    tuned = tune(design.loop, LINEAR_DESIGN_SPECS, moves=MOVES, gains=("kp", "ki", "kd"),
                 n_global=8, max_evaluations=12, spread=3.0, seed=1)
    assert tuned.meets_specs
    for name in ("kp", "kd"):  # the same design, refined (ki: the PD's 0 may grow)
        ratio = tuned.gains[name] / design.gains[name]
        assert 1 / LINEAR_TUNED_GAIN_FACTOR <= ratio <= LINEAR_TUNED_GAIN_FACTOR, (name, ratio)
    overshoot, settling, _ = _nonlinear_metrics(tuned.loop)
    predicted = _linear_metrics(design, tuned.loop)
    assert overshoot == pytest.approx(predicted[0], abs=LINEAR_DESIGN_OVERSHOOT_POINTS)
    assert settling == pytest.approx(predicted[1], rel=LINEAR_DESIGN_SETTLING_RTOL)


def test_friction_breaks_the_linear_design_on_the_canudas_rig():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)
        loop, _ = canudas_hunting()
    moves = (Move("step", 0.0, 1.0, 20.0), Move("small step", 0.0, 0.05, 20.0))
    design = linear_design(loop, CANUDAS_DESIGN_SPECS, velocity=0.25)
    assert design.meets_specs  # on the linear model
    designs = friction_designs(design)
    assert set(designs) == {"linear (python-control)", "linear + static compensation",
                            "linear + dither", "linear + LuGre observer"}
    comparison = compare_designs(loop, CANUDAS_DESIGN_SPECS, designs, moves=moves)
    table = comparison.to_pandas().set_index(["design", "move"])
    linear = table.loc["linear (python-control)"]
    assert "sticks short" in linear.loc["small step", "failure"]
    assert "creeps" in linear.loc["step", "failure"]
    assert linear.loc["step", "settling_time"] > 2 * design.predicted["settling_time"] or (
        not np.isfinite(linear.loc["step", "settling_time"]))
    summary = comparison.to_pandas("summary").set_index("design")
    assert summary.loc["linear (python-control)", "moves met"] == 0
    tuned = tune(loop, CANUDAS_DESIGN_SPECS, moves=moves, n_global=16, max_evaluations=24,
                 spread=300.0, seed=2)  # what tuning on the nonlinear loop recovers
    both = compare_designs(loop, CANUDAS_DESIGN_SPECS, {"tuned": tuned.loop}, moves=moves)
    assert both.meets("tuned"), both.to_pandas()


def test_the_command_line_compares_the_designs_with_a_tuned_gains_file(tmp_path):
    """``pneumact control compare``: the linear design and its compensations beside a
    tuned gains file on the rig; the tables name every design, the linear gains file
    runs in ``control step``; a bad --regime is refused by name (exit 2)."""
    import pandas as pd
    from typer.testing import CliRunner

    from pneumact.cli import app
    from pneumact.control import write_gains

    runner = CliRunner()
    gains = write_gains(PID(kp=10.0, ki=1.0, kd=10.0, filter_time=0.02), tmp_path / "t.toml")
    rig = ["--plant", "rig", "--params", "canudas1995", "--at", "0", "--velocity", "250"]
    done = runner.invoke(app, ["control", "compare", *rig, "--spec", CANUDAS_DESIGN_SPECS,
                               "--tuned", str(gains), "--out", str(tmp_path / "cmp")])
    assert done.exit_code == 0, done.output
    summary = pd.read_csv(tmp_path / "cmp" / "summary.csv")
    assert list(summary["design"]) == ["linear (python-control)",
                                       "linear + static compensation", "linear + dither",
                                       "linear + LuGre observer", "tuned (t.toml)"]
    linear = load_gains(tmp_path / "cmp" / "linear_gains.toml")
    table = pd.read_csv(tmp_path / "cmp" / "linear_gains.csv").set_index("gain")
    assert linear.kp == pytest.approx(table.loc["kp", "value"], rel=1e-12)
    step = runner.invoke(app, ["control", "step", "--plant", "rig", "--params",
                               "canudas1995", "--start", "0", "--stop", "100", "--t-end", "5",
                               "--gains-file", str(tmp_path / "cmp" / "linear_gains.toml"),
                               "--out", str(tmp_path / "step")])
    assert step.exit_code == 0, step.output
    bad = runner.invoke(app, ["control", "compare", *rig, "--regime", "gliding",
                              "--out", str(tmp_path / "bad")])
    assert bad.exit_code == 2 and "regime" in bad.output, bad.output
    assert not (tmp_path / "bad").exists()


def test_bad_input_is_refused_by_name(frictionless):
    loop, _ = frictionless
    cascade = dataclasses.replace(loop, controller=Cascade(kx=1.0, kv=1.0))
    with pytest.raises(ParameterError, match=r"loop = .*PID"):
        linear_design(cascade, LINEAR_DESIGN_SPECS)
    sampled = dataclasses.replace(
        loop, controller=dataclasses.replace(loop.controller, sample_time=0.01))
    with pytest.raises(ParameterError, match="sample_time"):
        linear_design(sampled, LINEAR_DESIGN_SPECS)
    with pytest.raises(ParameterError, match=r"designs = \{\}"):
        compare_designs(loop, LINEAR_DESIGN_SPECS, {})
    with pytest.raises(ParameterError, match=r"designs\['x'\]"):
        compare_designs(loop, LINEAR_DESIGN_SPECS, {"x": 3.0})


def test_results_write_their_tables_and_figures(frictionless, tmp_path):
    loop, design = frictionless
    written = {p.name for p in design.write(tmp_path / "design")}
    assert {"gains.csv", "predicted.csv", "candidates.csv", "linear_design.png",
            "report.html"} <= written
    comparison = compare_designs(loop, LINEAR_DESIGN_SPECS,
                                 {"linear": design.loop, "start": loop}, moves=MOVES)
    written = {p.name for p in comparison.write(tmp_path / "compare")}
    assert {"metrics.csv", "summary.csv", "designs.png", "report.html"} <= written
    assert "linear_gains.toml" not in written  # no linear design given
    with_linear = compare_designs(loop, LINEAR_DESIGN_SPECS, {"linear": design.loop},
                                  moves=MOVES, linear=design)
    written = {p.name for p in with_linear.write(tmp_path / "with-linear")}
    assert {"linear_gains.toml", "linear_gains.csv", "linear_predicted.csv",
            "linear_design.png"} <= written
    again = load_gains(tmp_path / "with-linear" / "linear_gains.toml")
    assert again.parameters() == pytest.approx(design.controller.parameters(), rel=1e-15)
