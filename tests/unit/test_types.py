"""The package passes mypy (issue 20, item 6: "typed and tested for real").

mypy checks ``src/pneumact`` with the configuration in ``pyproject.toml`` (``[tool.mypy]``:
the bodies of unannotated functions too, third-party libraries without types listed by
name, the kernel templates' placeholder codes switched off). Its incremental cache is kept
in pytest's cache folder: a fresh clone checks cold (about 8 s on one core), a later run
only what changed.
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).parents[2]
PACKAGE = ROOT / "src" / "pneumact"


def _cache_dir(pytestconfig, tmp_path_factory) -> Path:
    cache = getattr(pytestconfig, "cache", None)  # None under -p no:cacheprovider
    return cache.mkdir("mypy") if cache is not None else tmp_path_factory.mktemp("mypy")


def test_the_package_passes_mypy(pytestconfig, tmp_path_factory):
    from mypy import api

    stdout, stderr, status = api.run([
        "--config-file", str(ROOT / "pyproject.toml"),
        "--cache-dir", str(_cache_dir(pytestconfig, tmp_path_factory)),
        str(PACKAGE),
    ])
    assert status == 0, (f"mypy finds errors in the package (run `mypy` in the repository "
                         f"root):\n{stdout}{stderr}")
