"""The package passes mypy (issue 20, item 6: "typed and tested for real").

mypy checks ``src/pneumact`` with the configuration in ``pyproject.toml`` (``[tool.mypy]``:
the bodies of unannotated functions too, third-party libraries without types listed by
name, the kernel templates' placeholder codes switched off). Its incremental cache is kept
in pytest's cache folder: a fresh clone checks cold (about 8 s on one core), a later run
only what changed (well under a second).

mypy runs in a process of its own (``python -m mypy``), not through ``mypy.api.run`` in
the test process: in process it keeps about 450 MB alive in the test worker until the
worker exits, freeing them then costs another 5 s or so, and it leaves the worker's
garbage-collector thresholds changed for the tests after it; its command line ends
without freeing anything.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[2]
PACKAGE = ROOT / "src" / "pneumact"


def _cache_dir(pytestconfig, tmp_path_factory) -> Path:
    cache = getattr(pytestconfig, "cache", None)  # None under -p no:cacheprovider
    return cache.mkdir("mypy") if cache is not None else tmp_path_factory.mktemp("mypy")


def test_the_package_passes_mypy(pytestconfig, tmp_path_factory):
    run = subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", str(ROOT / "pyproject.toml"),
         "--cache-dir", str(_cache_dir(pytestconfig, tmp_path_factory)), str(PACKAGE)],
        capture_output=True, text=True, cwd=ROOT, check=False)
    assert run.returncode == 0, (f"mypy finds errors in the package (run `mypy` in the "
                                 f"repository root):\n{run.stdout}{run.stderr}")
