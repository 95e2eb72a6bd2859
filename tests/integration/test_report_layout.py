"""Reports a person can read (issue #19): one report of each kind, rendered by a real
headless browser at 1280 px, keeps every table in its own scroll box and every figure
inside the page. Skipped, with the reason, where no browser is installed (the reproduce
report is checked in test_reproduce.py, on the reproduction that test makes anyway)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import pneumact as pa
from browser import assert_fits_the_page, needs_browser
from pneumact.cli import app
from pneumact.identification import fit, identify_paper, paper_campaign, synthetic_campaign
from pneumact.validation import validate

pytestmark = needs_browser
runner = CliRunner()


@pytest.fixture(scope="module")
def records(vgt):
    tests = paper_campaign(vgt, speeds=(2e-4, 1e-3, 5e-3, 2e-2), sweep_period=30.0)
    return synthetic_campaign(vgt, tests, seed=4)


def test_identification_report_fits_the_page(vgt, records, tmp_path):
    identify_paper(records, vgt).write(tmp_path / "ident", truth=vgt)
    assert_fits_the_page(tmp_path / "ident" / "report.html")


def test_fit_report_fits_the_page(vgt, records, tmp_path):
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    result = fit(model, records[:1], ["Fc", "F0"])
    result.report("pa.fit(...)").write(tmp_path / "fit.html")
    assert_fits_the_page(tmp_path / "fit.html")


def test_validation_report_fits_the_page(vgt, records, tmp_path):
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    validate(model, records[:2], signals=("position", "pressure")).write(tmp_path / "val")
    assert_fits_the_page(tmp_path / "val" / "report.html")


@pytest.mark.parametrize("args", [
    ["sensitivity", "oat", "--conditions", "period=20,80", "--conditions",
     "valve=command,regulator"],
    # the loop of test_cli_control.py's step test: its closed-loop kernel serves both
    ["control", "step", "--plant", "command", "--start", "4", "--stop", "8", "--t-end",
     "0.6", "--sample-time", "1e-3"]], ids=["sensitivity", "control"])
def test_command_reports_fit_the_page(args, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, [*args, "--out", "out"])
    assert result.exit_code == 0, result.output
    assert_fits_the_page(tmp_path / "out" / "report.html")
