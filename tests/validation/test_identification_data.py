"""Identification validated: honest standard errors over many noise seeds, and the
inverse friction model on the two real data sets in shared/data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from pneumact.identification import Noise, fit, inverse_friction, paper_campaign, stages
from pneumact.identification.campaign import add_noise, synthetic_campaign
from pneumact.io.datasets import read_emps, read_tudelft_cylinder

DATA = Path(__file__).resolve().parents[3] / "shared" / "data"
EMPS = DATA / "emps"
TUDELFT = DATA / "pneumatic_cylinder_friction_tudelft"
needs_data = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data is not beside the repo")


def test_staged_intervals_cover_the_truth(vgt):
    """Stages (a)-(c) on COVERAGE_SEEDS noise realisations of one simulated campaign
    (the paper's fixed speeds and its 5 mm/s threshold of eq. 13)."""
    clean = synthetic_campaign(vgt, paper_campaign(vgt), noise=Noise(0.0, 0.0, 0.0))
    start = vgt.replace({n: vgt[n] * f for n, f in ref.IDENT_START_FACTORS.items()})
    hits = dict.fromkeys(ref.IDENT_WITHIN_CI, 0)
    for seed in range(ref.COVERAGE_SEEDS):
        records = add_noise(clean, Noise(), seed)
        sweeps = [r for r in records if r.meta["kind"] == "sweep"]
        spring = stages.stage_spring(sweeps, start)
        current = start.replace(F0=spring.estimates["F0"], k=spring.estimates["k"])
        segments = stages.segments_of([r for r in records if r.meta["kind"] != "presliding"],
                                      current, stages.presliding_range(start))
        sliding = stages.stage_sliding(segments, 5e-3)
        stribeck = stages.stage_stribeck(segments, sliding, current, 5e-3)
        for stage in (spring, sliding, stribeck):
            ci = stage.estimates.interval(0.95)
            for j, name in enumerate(stage.estimates.names):
                if name in hits:
                    hits[name] += bool(ci[j, 0] <= vgt[name] <= ci[j, 1])
    coverage = {n: h / ref.COVERAGE_SEEDS for n, h in hits.items()}
    low, high = ref.COVERAGE_RANGE
    assert all(low <= c <= high for c in coverage.values()), coverage


def test_fit_intervals_cover_the_truth(vgt):
    """Output-error fit of σ0, σ1 (presliding test, clean input, noisy position)."""
    tests = [t for t in paper_campaign(vgt) if t.kind == "presliding"]
    clean = synthetic_campaign(vgt, tests, noise=Noise(0.0, 0.0, 0.0))
    model = pa.Actuator(vgt, valve=pa.PressureSource())
    truth = np.array([vgt["sigma0"], vgt["sigma1"]])
    hits = np.zeros(2)
    for seed in range(ref.FIT_COVERAGE_SEEDS):
        record = add_noise(clean, Noise(0.0, 1e-6, 1e-6), seed)[0]
        result = fit(model, record, ["sigma0", "sigma1"],
                     start={"sigma0": 1.3e5, "sigma1": 150.0})
        ci = result.estimates.interval(0.95)
        hits += (ci[:, 0] <= truth) & (truth <= ci[:, 1])
    coverage = hits / ref.FIT_COVERAGE_SEEDS
    low, high = ref.COVERAGE_RANGE
    assert np.all((coverage >= low) & (coverage <= high)), coverage


@needs_data
def test_emps_inverse_model_predicts_the_pulse_record():
    estimation = read_emps(EMPS / "DATA_EMPS.mat")
    validation = read_emps(EMPS / "DATA_EMPS_PULSES.mat")
    result = inverse_friction(estimation, cutoff=ref.EMPS_CUTOFF)
    values = result.estimates.as_dict()
    for name, (low, high) in ref.EMPS_RANGES.items():
        assert low <= values[name] <= high, (name, values[name])
    assert result.relative_force_error < ref.EMPS_FORCE_ERROR
    assert result.validate(validation) < ref.EMPS_PULSES_FORCE_ERROR
    assert result.condition_number < ref.EMPS_CONDITION


@needs_data
def test_tudelft_seal_friction_grows_with_supply_pressure():
    levels = {}
    for bar in (1, 3, 5, 7):
        record = read_tudelft_cylinder(TUDELFT / f"O-ring_{bar}bar.csv")
        result = inverse_friction(record, force="friction", mass=False,
                                  cutoff=ref.TUDELFT_CUTOFF)
        assert result.relative_force_error < ref.TUDELFT_FORCE_ERROR, bar
        speed = np.median(np.abs(result.data["velocity"]))
        levels[bar] = result.estimates["Fc"] + result.estimates["Fv"] * speed
    assert levels[7] > levels[1], levels


@needs_data
def test_real_data_examples_write_their_reports(tmp_path):
    import importlib.util

    import pandas as pd

    path = Path(__file__).resolve().parents[2] / "examples" / "real_data_validation.py"
    spec = importlib.util.spec_from_file_location("real_data_validation", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    example.main(DATA, tmp_path)
    emps = pd.read_csv(tmp_path / "emps" / "metrics.csv").set_index("role")
    assert emps.loc["identification", "relative_force_error"] < ref.EMPS_FORCE_ERROR
    assert emps.loc["validation", "relative_force_error"] < ref.EMPS_PULSES_FORCE_ERROR
    tudelft = pd.read_csv(tmp_path / "tudelft" / "metrics.csv")
    predicted = tudelft[tudelft["role"] == "validation"]
    assert len(predicted) == 2
    assert (predicted["relative_force_error"] < ref.TUDELFT_ACROSS_FORCE_ERROR).all()
    for name in ("emps", "tudelft"):
        html = (tmp_path / name / "report.html").read_text(encoding="utf-8")
        assert "data:image/png;base64," in html
