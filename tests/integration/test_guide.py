"""docs/guide.md runs as written: its Python blocks, in order, in an empty folder."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "guide.md"


def test_the_guide_runs(tmp_path, monkeypatch):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    blocks = re.findall(r"```python\n(.*?)```", GUIDE.read_text(encoding="utf-8"), re.S)
    assert len(blocks) >= 4
    namespace: dict = {}
    for i, block in enumerate(blocks):
        exec(compile(block, f"{GUIDE.name}, block {i + 1}", "exec"), namespace)
    assert (tmp_path / "identification" / "report.html").exists()
    assert (tmp_path / "validation" / "report.html").exists()
    assert namespace["validation"].metrics()["fit_percent"].min() > 90.0
