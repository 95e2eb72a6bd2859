"""README.md's Python API, identification and validation snippets run as written, in
order, in a folder holding the bench campaign that `pneumact campaign --out bench` writes
(a sweep, ramps from 0.083 to 56 mm/s, a presliding test), made by that command: the
identification and the validation choose their records by the names it writes, and the
validation drives each record the way it was made."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import matplotlib
from typer.testing import CliRunner

import pneumact as pa
from pneumact.cli import app

README = Path(__file__).resolve().parents[2] / "README.md"


def _blocks(*first_lines: str) -> list[str]:
    """The README's Python blocks that contain each of ``first_lines``, in page order."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)
    chosen = [b for b in blocks if any(line in b for line in first_lines)]
    assert len(chosen) == len(first_lines), "a README snippet this test runs has moved"
    return chosen


def test_the_readme_api_and_validation_snippets_run(tmp_path, monkeypatch):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)
        made = CliRunner().invoke(app, ["campaign", "--out", "bench"])
    assert made.exit_code == 0, made.output
    namespace: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)  # Table I's σ1, as published
        for i, block in enumerate(_blocks("import pneumact as pa",
                                          "ident = pa.identify_paper(records, prior)",
                                          "from pneumact.validation import validate")):
            exec(compile(block, f"README.md, snippet {i + 1}", "exec"), namespace)
    assert namespace["fitted"].records[0].name.startswith("presliding")
    assert (tmp_path / "ident" / "report.html").exists()
    verdicts = namespace["validation"].verdicts().set_index("record")
    assert verdicts.loc["presliding.csv", "valve"] == "PressureSource"
    assert verdicts.loc["sweep.csv", "valve"] == "PressureRegulator"
    assert (tmp_path / "val" / "report.html").exists()
    assert set(namespace["split"].metrics()["set"]) == {"training", "test"}
    assert [r.name for r in namespace["fast"]] == ["ramp_13mm_s", "ramp_27mm_s",
                                                   "ramp_56mm_s"]


def test_the_readme_batch_sensitivity_and_closed_loop_snippets_run(tmp_path, monkeypatch):
    """README.md's batch/sensitivities, sensitivity-analysis and closed-loop snippets,
    after its first one (they use its actuators): a batch row per parameter set, ∂x/∂θ per
    parameter, Sobol indices of the three parameters and a study per operating condition,
    the regulator loop's step metrics and files, the linearised plant as a python-control
    system."""
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    found: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)  # Table I's σ1, as published
        for i, block in enumerate(_blocks("import pneumact as pa",
                                          "batch = pa.simulate_batch(",
                                          "from pneumact import sensitivity as sa",
                                          "from pneumact.control import PID, ClosedLoop")):
            exec(compile(block, f"README.md, snippet {i + 1}", "exec"), namespace)
            found[i] = dict(namespace)
    assert (found[1]["batch"].to_pandas()["status"] == "ok").all()
    assert found[1]["sens"]["position"].shape[1] == 4
    indices = found[2]["study"].to_pandas(output="loop_width_pressure")
    assert {"sigma0", "Fc", "Fs"} <= set(indices.to_string().split())
    assert len(found[2]["across"].conditions) == 6
    metrics = found[3]["study"].metrics.to_pandas()
    assert "settling_time" in set(metrics["metric"])
    assert (tmp_path / "step" / "report.html").exists()
    assert found[3]["linear"].to_control().nstates >= 2
