"""The real EMPS drive replayed in its closed loop (pneumact.control.drives): the drive
identified on DATA_EMPS.mat, under its own sampled cascade, follows the recorded
reference of both records; position, velocity and motor force against the measurements.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import reference as ref
from pneumact.control.drives import control_law_check, drive_plant, replay_drive
from pneumact.errors import DataError, ParameterError
from pneumact.identification import inverse_friction
from pneumact.identification.estimates import Estimates
from pneumact.io.datasets import read_emps
from pneumact.models.friction import StribeckMap

EMPS = Path(__file__).resolve().parents[3] / "shared" / "data" / "emps"
pytestmark = pytest.mark.skipif(not EMPS.is_dir(),
                                reason="shared/data/emps is not beside the repo")


@pytest.fixture(scope="module")
def estimation():
    return read_emps(EMPS / "DATA_EMPS.mat")


@pytest.fixture(scope="module")
def pulses():
    return read_emps(EMPS / "DATA_EMPS_PULSES.mat")


@pytest.fixture(scope="module")
def identified(estimation):
    return inverse_friction(estimation, cutoff=ref.EMPS_CUTOFF)


@pytest.fixture(scope="module")
def replayed(estimation, identified):
    return replay_drive(estimation, identified)


@pytest.fixture(scope="module")
def replayed_pulses(pulses, identified):
    return replay_drive(pulses, identified)


def _lag(replay) -> float:
    """‖r − x̂‖: the simulated tracking error."""
    f = replay.frame
    return float(np.linalg.norm(f["reference"] - f["position_simulated"]))


def _measured_lag(replay) -> float:
    f = replay.frame
    return float(np.linalg.norm(f["reference"] - f["position_measured"]))


def test_replay_matches_the_estimation_record(replayed):
    e = replayed.errors
    assert e["position"] < ref.EMPS_LOOP_POSITION_ERROR
    assert e["tracking"] < ref.EMPS_LOOP_TRACKING_ERROR
    assert e["velocity"] < ref.EMPS_LOOP_VELOCITY_ERROR
    assert e["force"] < ref.EMPS_LOOP_FORCE_ERROR
    # the simulated loop lags the reference as much as the real one did
    assert _lag(replayed) / _measured_lag(replayed) == pytest.approx(
        1.0, abs=ref.EMPS_LOOP_LAG_TOL)


def test_replay_predicts_the_pulse_record(replayed_pulses):
    """Never fitted: identification on DATA_EMPS.mat, the pulses as recorded."""
    e = replayed_pulses.errors
    assert replayed_pulses.settings["pulses"] == "command"
    assert e["position"] < ref.EMPS_LOOP_POSITION_ERROR
    assert e["tracking"] < ref.EMPS_LOOP_TRACKING_ERROR
    assert e["velocity"] < ref.EMPS_LOOP_VELOCITY_ERROR
    assert e["force"] < ref.EMPS_LOOP_PULSES_FORCE_ERROR


def test_halving_kp_doubles_the_lag_and_breaks_the_match(estimation, identified, replayed):
    """P/P cascade at steady speed: kp·e = v + F/(gtau·kv), so e ∝ 1/kp."""
    kp = float(estimation.meta["kp"])
    half = replay_drive(estimation, identified, gains={"kp": ref.EMPS_LOOP_KP_FACTOR * kp})
    assert half.settings["kp"] == pytest.approx(ref.EMPS_LOOP_KP_FACTOR * kp)
    assert _lag(half) / _lag(replayed) == pytest.approx(1.0 / ref.EMPS_LOOP_KP_FACTOR,
                                                         rel=ref.EMPS_LOOP_LAG_TOL)
    assert half.errors["position"] > ref.EMPS_LOOP_POSITION_ERROR
    assert half.errors["force"] > ref.EMPS_LOOP_FORCE_ERROR


def test_the_law_explains_the_recorded_command(estimation, pulses):
    """The backward-difference cascade reproduces vir from qm and qg; on the pulse
    record the residual is the pulses themselves, in volts, with a gain of +1."""
    plain = control_law_check(estimation)
    assert plain["law_rms_V"] < ref.EMPS_LOOP_LAW_RMS
    assert "pulse_gain" not in plain
    check = control_law_check(pulses)
    low, high = ref.EMPS_LOOP_PULSE_GAIN
    assert low < check["pulse_gain"] < high
    assert check["law_rms_with_pulses_V"] < ref.EMPS_LOOP_LAW_RMS
    assert check["law_rms_V"] > 10 * ref.EMPS_LOOP_LAW_RMS  # the pulses are in vir


def test_the_pulses_are_needed_and_not_a_carriage_force(pulses, identified, replayed_pulses):
    ignored = replay_drive(pulses, identified, pulses=False)
    as_force = replay_drive(pulses, identified, pulses="force")
    for other in (ignored, as_force):
        assert other.errors["force"] > ref.EMPS_LOOP_PULSES_FORCE_ERROR
        assert other.errors["position"] > ref.EMPS_LOOP_POSITION_ERROR
    assert ignored.settings["pulses"] == "none"
    assert replayed_pulses.errors["force"] < as_force.errors["force"] / 3


def test_the_difference_estimate_fits_better_than_an_ideal_sensor(estimation, identified,
                                                                    replayed):
    ideal = replay_drive(estimation, identified, velocity_estimate="measured")
    assert replayed.errors["force"] < ideal.errors["force"]
    assert replayed.errors["position_rms_mm"] < ideal.errors["position_rms_mm"]


def test_refuses_what_the_rig_cannot_represent(estimation, identified):
    asymmetric = inverse_friction(estimation, asymmetric=True, cutoff=ref.EMPS_CUTOFF)
    with pytest.raises(ParameterError, match="asymmetric"):
        replay_drive(estimation, asymmetric)
    # EMPS has no Stribeck dip: the fitted Fs falls below Fc, which no Stribeck map holds
    stribeck = inverse_friction(estimation, "stribeck", cutoff=ref.EMPS_CUTOFF)
    assert stribeck.estimates["Fs"] < stribeck.estimates["Fc"]
    with pytest.raises(ParameterError, match="Fs"):
        replay_drive(estimation, stribeck)
    with pytest.raises(ParameterError, match="gains"):
        replay_drive(estimation, identified, gains={"ki": 1.0})
    with pytest.raises(DataError, match="no pulses"):
        replay_drive(estimation, identified, pulses="command")


def test_a_stribeck_estimate_builds_a_stribeck_rig(estimation):
    stribeck = inverse_friction(estimation, "stribeck", cutoff=ref.EMPS_CUTOFF)
    values = stribeck.estimates.as_dict() | {"Fs": 25.0, "vs": 0.01}
    names = tuple(values)
    est = Estimates(names, np.array([values[n] for n in names]), np.zeros(len(names)),
                    np.zeros((len(names), len(names))), 1)
    rig, offset = drive_plant(dataclasses.replace(stribeck, estimates=est))
    assert isinstance(rig.friction, StribeckMap)
    assert (rig.params["m"], rig.params["Fs"], rig.params["vs"], rig.params["sigma2"]) == (
        values["mass"], 25.0, 0.01, values["Fv"])
    assert offset == values["offset"]


def test_write_gives_every_file(replayed, tmp_path):
    written = replayed.write(tmp_path / "emps")
    assert sorted(p.name for p in written) == ["metrics.csv", "replay.csv", "replay.png",
                                               "report.html"]
    metrics = pd.read_csv(tmp_path / "emps" / "metrics.csv")
    assert metrics["force_relative_error"].iloc[0] == pytest.approx(replayed.errors["force"])
    frame = pd.read_csv(tmp_path / "emps" / "replay.csv")
    assert list(frame.columns) == list(replayed.to_pandas().columns)
    assert len(frame) == len(replayed.frame)
    assert "DATA_EMPS.mat" in (tmp_path / "emps" / "report.html").read_text(encoding="utf-8")
