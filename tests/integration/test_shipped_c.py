"""The C shipped with the package (issue 43, cold start): current, and what a first run uses.

A fresh install's first ``pneumact simulate`` builds the default model's run library and
the common library of signals and features; a first ``pneumact simulate --valve X
--friction Y`` (or ``--model cylinder``) the run library of its model. Their C is shipped
(``core.c_shipped``, written by ``tools/ship_c.py``), so those runs compile it and type
nothing (numba's typing was ~7 s of CPU of the ~9 s). The first run's two must be exactly
what a fresh translation of the current code gives; every other shipped library must
have a file for its current key (a digest of every source its translation depends on and
of the versions: a stale file is seen without translating, a few seconds each). A change
to a kernel, the back end or numba without regenerating fails here, saying how to
regenerate; so does a file no library ships.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

import pneumact
from pneumact.core.c_build import compiler_path, shared_library_suffix
from pneumact.core.c_shipped import SHIPPED_DIR, read_shipped, shipped_path

pytestmark = pytest.mark.integration

TOOL = Path(__file__).resolve().parents[2] / "tools" / "ship_c.py"
REGENERATE = "regenerate it: PYTHONPATH=src python tools/ship_c.py"


def _tool():
    spec = importlib.util.spec_from_file_location("ship_c", TOOL)
    assert spec is not None and spec.loader is not None, TOOL
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _versions() -> str:
    from importlib.metadata import version

    return (f"numba {version('numba')}, numpy {version('numpy')}, Python "
            f"{sys.version_info[0]}.{sys.version_info[1]}")


def _missing(name: str, library) -> str:
    return (f"no shipped C of {name} ({library.command}) for the current code (key "
            f"{library.key[:24]}; {_versions()}): a kernel source, the C back end, numba, "
            f"numpy (major.minor) or Python changed since it was shipped; {REGENERATE}")


def test_the_first_runs_shipped_c_is_a_fresh_translation_of_the_current_code():
    for name, library in _tool().first_run_libraries().items():
        shipped = read_shipped(name, library.key)
        assert shipped is not None, _missing(name, library)
        assert shipped == library.translate(), (
            f"the shipped C of {name} differs from a fresh translation of the same code "
            f"(a source the key does not cover changed); {REGENERATE}")


def test_every_model_the_command_builds_has_shipped_c_for_its_current_key():
    """Every ``--valve`` with every ``--friction`` the command accepts with its default
    set, and ``--model cylinder``: a shipped file under the current key (not translated
    here: ``tools/ship_c.py --check`` compares them all); no file is no library's."""
    tool = _tool()
    libraries = tool.shipped_libraries()
    models, refused = tool.command_models()
    assert len(libraries) == len(models) + 1  # one run library each, and the common one
    assert {"pneumact simulate --valve command", "pneumact simulate --valve regulator",
            "pneumact simulate --friction dahl", "pneumact simulate --model cylinder"} <= \
        {library.command for library in libraries.values()}
    assert all("gms" in command for command in refused), refused  # its own parameters
    for name, library in libraries.items():
        assert shipped_path(name, library.key).is_file(), _missing(name, library)
        assert read_shipped(name, library.key) is not None, _missing(name, library)
    orphans = [path.name for path in tool.orphans(libraries)]
    assert not orphans, (f"files in {SHIPPED_DIR} that no shipped library has (a library "
                         f"no longer shipped, or an older key): {orphans}; {REGENERATE} "
                         f"(it removes them)")


COLD_SIMULATE = """
import sys
from pneumact.cli import app
try:
    app(["simulate", *{extra!r}, "--out", {out!r}])
except SystemExit as exit:
    assert not exit.code, exit.code
print("TRANSLATED", "pneumact.core.c_source" in sys.modules, "NUMBA", "numba" in sys.modules,
      "PYPLOT", "matplotlib.pyplot" in sys.modules)
"""


def _cold_simulate(tmp_path: Path, extra: list[str]) -> list[str]:
    """``pneumact simulate *extra`` with empty caches, in a process of its own: asserts
    that it neither translated C (the back end, which types through numba, never
    imported) nor imported numba or pyplot; the libraries it built."""
    script = COLD_SIMULATE.format(extra=extra, out=str(tmp_path / "out"))
    src = str(Path(pneumact.__file__).resolve().parents[1])
    env = {**os.environ, "PNEUMACT_ENGINE": "c", "PNEUMACT_CACHE_DIR": str(tmp_path / "k"),
           "NUMBA_CACHE_DIR": str(tmp_path / "n"),
           "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")]))}
    run = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                         text=True, timeout=600, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "TRANSLATED False NUMBA False" in run.stdout, (
        f"a cold pneumact simulate {' '.join(extra)} translated C instead of compiling the "
        f"shipped C; {REGENERATE}\n{run.stdout[-2000:]}")
    assert "PYPLOT False" in run.stdout  # the figure is only written (plotting.off_screen)
    return sorted(p.name for p in (tmp_path / "k").glob(f"*{shared_library_suffix()}"))


@pytest.mark.skipif(compiler_path() is None, reason="no C compiler: the C engine cannot run")
def test_a_cold_first_simulate_compiles_the_shipped_c_and_types_nothing(tmp_path):
    """A fresh install's first ``pneumact simulate``: both libraries are built from
    shipped C, and the C back end is never imported, nor numba itself, nor pyplot (the
    figure is drawn on its own Agg canvas)."""
    libraries = _cold_simulate(tmp_path, [])
    assert len(libraries) == 2, libraries  # what the first run builds: both shipped
    assert libraries[0].startswith("pneumact_common-"), libraries
    assert libraries[1].startswith("pneumact_kernel_actuator_lugre_source_"), libraries
    assert (tmp_path / "out" / "hysteresis.png").is_file()


@pytest.mark.skipif(compiler_path() is None, reason="no C compiler: the C engine cannot run")
@pytest.mark.parametrize(("extra", "kernel", "figure"), [
    (["--valve", "command"], "actuator_lugre_command", "hysteresis.png"),
    (["--model", "cylinder"], "cylinder_lugre_spool_direct_chambers_polytropic",
     "response.png")])
def test_a_cold_new_combination_compiles_its_shipped_c_and_types_nothing(tmp_path, extra,
                                                                       kernel, figure):
    """A combination other than the default, first on a fresh install: its run library
    (and the common one) is compiled from shipped C; neither the back end nor numba is
    imported."""
    libraries = _cold_simulate(tmp_path, extra)
    assert len(libraries) == 2, libraries
    assert libraries[0].startswith("pneumact_common-"), libraries
    assert libraries[1].startswith(f"pneumact_kernel_{kernel}_"), libraries
    assert (tmp_path / "out" / figure).is_file()


def _spec(valve, **model):
    from conftest import load_quietly
    from pneumact.core.assembly import assemble

    return assemble(pneumact.Actuator(load_quietly("vgt-paper"), valve=valve,
                                      **model)).kernel_spec()


@pytest.mark.skipif(compiler_path() is None, reason="no C compiler: the C engine cannot run")
def test_the_kernel_is_built_ahead_in_a_thread_only_from_shipped_c(tmp_path, monkeypatch):
    """``build_ahead``: the default model's library (shipped) is built by a thread while
    the block runs; a model whose C is not shipped (the regulator with LuGre's decaying
    damping: ``tools/ship_c.py`` ships the default laws' options) is left to the run (its
    translation imports numba, which two threads must not import at once); nothing on
    numba."""
    import threading

    from pneumact.core.c_engine import build_ahead, engine_scope, library_path

    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path))
    shipped = _spec(pneumact.PressureSource())
    other = _spec(pneumact.PressureRegulator(), friction=pneumact.LuGre(decaying_damping=True))
    compiler = compiler_path()
    assert compiler is not None
    with engine_scope("numba"), build_ahead(shipped):
        assert "pneumact-build-ahead" not in {t.name for t in threading.enumerate()}
    with engine_scope("c"), build_ahead(other):
        assert "pneumact-build-ahead" not in {t.name for t in threading.enumerate()}
    with engine_scope("c"), build_ahead(shipped):
        assert "pneumact-build-ahead" in {t.name for t in threading.enumerate()}
    assert library_path(shipped, compiler).exists()  # built, and joined at the block's end
    assert not library_path(other, compiler).exists()


@pytest.mark.skipif(compiler_path() is None, reason="no C compiler: the C engine cannot run")
def test_a_build_ahead_that_fails_is_raised_by_the_run_and_not_tried_twice(tmp_path,
                                                                          monkeypatch):
    from pneumact.core import c_engine
    from pneumact.core.c_build import CBuildError
    from pneumact.core.c_engine import build_ahead, c_kernel, engine_scope

    calls = []

    def failing(compiler, sources, output, flags):
        calls.append(output)
        raise CBuildError("cc: out of disk space")

    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(c_engine, "compile_library", failing)
    spec = _spec(pneumact.PressureSource())
    with engine_scope("c"), build_ahead(spec):
        pass
    assert len(calls) == 1
    with pytest.raises(CBuildError, match="out of disk space"):
        c_kernel(spec)
    assert len(calls) == 1  # the thread's error, not a second build
    with pytest.raises(CBuildError, match="out of disk space"):
        c_kernel(spec)  # a later call builds again
    assert len(calls) == 2


@pytest.mark.skipif(compiler_path() is None, reason="no C compiler: the C engine cannot run")
def test_an_assembly_holding_its_kernel_builds_nothing_ahead(tmp_path, monkeypatch):
    """``Assembly.building_kernel`` is a null block once the assembly holds the kernel of
    the engine in force (every run checks its drive inside it: a warm run pays nothing),
    even where the disk cache has gone."""
    import threading

    from conftest import load_quietly
    from pneumact.core.assembly import assemble
    from pneumact.core.c_engine import engine_scope

    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path / "first"))
    assembly = assemble(pneumact.Actuator(load_quietly("vgt-paper")))
    with engine_scope("c"):
        assert assembly.kernel.engine == "c"
        monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path / "second"))  # empty
        with assembly.building_kernel():
            assert "pneumact-build-ahead" not in {t.name for t in threading.enumerate()}
        assert not (tmp_path / "second").exists()
