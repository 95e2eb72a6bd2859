"""The boundary helpers (``pneumact.checks``), the physical limits and their hints, and the
staged output folders (``pneumact.io.tables.staged_folder``)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from pneumact import checks
from pneumact.errors import ArgumentError, ArgumentTypeError, DataError, PneumactError
from pneumact.io.tables import (
    RUN_LISTING,
    lock_file,
    partial_folder,
    staged_folder,
    write_files,
)


# --------------------------------------------------------------------------- checks
@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_finite_refuses_nan_and_infinities(value):
    with pytest.raises(ArgumentError, match=r"x = .*: must be a finite number"):
        checks.check_finite("x", value)


@pytest.mark.parametrize("value", ["1e-6", None, [1.0], True])
def test_a_number_of_the_wrong_type_says_what_was_expected(value):
    with pytest.raises(ArgumentTypeError, match="must be a number"):
        checks.check_finite("rtol", value)
    with pytest.raises(TypeError):  # and is a TypeError for callers that catch those
        checks.check_finite("rtol", value)


def test_a_numeric_string_gets_the_fix():
    with pytest.raises(ArgumentTypeError, match=r"write rtol=1e-6 without quotes"):
        checks.check_finite("rtol", "1e-6")


def test_range_messages_name_the_bound_and_the_unit():
    assert checks.check_range("t", 2, 0.0, 5.0) == 2.0
    with pytest.raises(ArgumentError, match=r"t = -1 s: must be > 0 s"):
        checks.check_range("t", -1, 0.0, unit="s", low_open=True)
    with pytest.raises(ArgumentError, match=r"u = 5: must be in \[0, 1\]"):
        checks.check_range("u", 5, 0.0, 1.0)
    with pytest.raises(DataError):  # the caller's error class
        checks.check_positive("dt", 0, error=DataError)


@pytest.mark.parametrize(("value", "message"), [
    (8.5, "whole number"), (-1, ">= 0"), (True, "whole number"), ("3", "whole number")])
def test_integers(value, message):
    with pytest.raises(PneumactError, match=message):
        checks.check_int("n", value, minimum=0)
    assert checks.check_int("n", 8.0, minimum=0) == 8


def test_seed_range_is_numpy_s():
    assert checks.check_seed("seed", 2**32 - 1) == 2**32 - 1
    for bad in (-1, 2**32):
        with pytest.raises(ArgumentError):
            checks.check_seed("seed", bad)


def test_choices_and_names_guess_a_near_miss():
    with pytest.raises(ArgumentError, match="did you mean 'huber'"):
        checks.check_choice("loss", "hubber", ["linear", "huber"])
    with pytest.raises(ArgumentError, match="sigma0 more than once"):
        checks.check_names("free", ["sigma0", "sigma0"])
    with pytest.raises(ArgumentError, match="did you mean 'position'"):
        checks.check_names("signals", ["positon"], known=["position", "pressure"])
    assert checks.check_names("free", "Fc") == ["Fc"]


def test_paths_and_output_folders(tmp_path):
    with pytest.raises(ArgumentTypeError, match="must be a file path"):
        checks.check_path("path", 5)
    a_file = tmp_path / "f.txt"
    a_file.write_text("x")
    with pytest.raises(ArgumentError, match="is a file; give a folder"):
        checks.check_out_dir("out_dir", a_file)
    with pytest.raises(ArgumentError, match="cannot be created there"):
        checks.check_out_dir("out_dir", a_file / "sub")
    assert checks.check_out_dir("out_dir", tmp_path / "new") == tmp_path / "new"


def test_strategy_class_is_instantiated_and_a_name_refused():
    class Base:
        pass

    class Thing(Base):
        pass

    assert isinstance(checks.as_instance("valve", Thing, Base, examples="Thing()"), Thing)
    with pytest.raises(ArgumentTypeError, match=r"such as Thing\(\), not str"):
        checks.as_instance("valve", "thing", Base, examples="Thing()")


# --------------------------------------------------------------------------- physics
@pytest.mark.parametrize(("value", "mistake"), [
    (100.0, "kPa typed as Pa"), (1.01325, "bar typed as Pa"), (0.0, "gauge pressure"),
    (-50e3, "gauge pressure"), (1013.25, "hPa or mbar")])
def test_pressure_hints_name_the_likely_mistake(value, mistake):
    assert mistake in checks.pressure_hint(value)


def test_absolute_pressure_and_atmosphere_limits():
    assert checks.check_absolute_pressure("p", 20e3) == 20e3
    for bad in (0.0, -1.0, 1e12, 100.0):
        with pytest.raises(ArgumentError, match="absolute pressure"):
            checks.check_absolute_pressure("p", bad)
    assert checks.check_atmosphere("p_atm", 101325.0) == 101325.0
    assert checks.check_atmosphere("p_atm", 30e3) == 30e3  # odd, not impossible
    with pytest.raises(ArgumentError, match="kPa typed as Pa"):
        checks.check_atmosphere("p_atm", 101.325)


# --------------------------------------------------------------------------- staging
def _tree(folder: Path) -> dict[str, tuple[bytes, int]]:
    return {str(p.relative_to(folder)): (p.read_bytes(), p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_a_failed_write_leaves_the_previous_run_exactly(tmp_path):
    out = tmp_path / "run"
    write_files(out, {"a.csv": lambda p: p.write_text("1"), "b.png": lambda p: p.write_text("2")})
    before = _tree(out)

    def fail(path):
        path.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        write_files(out, {"a.csv": lambda p: p.write_text("new"), "c.csv": fail})
    assert _tree(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["run"]  # no staging left beside


def test_an_overwrite_removes_the_previous_run_s_files_only(tmp_path):
    out = tmp_path / "fit"
    write_files(out, {"estimates.csv": lambda p: p.write_text("1"),
                      "starts.csv": lambda p: p.write_text("multistart")})
    (out / "notes.txt").write_text("mine")  # not written by a run: kept
    write_files(out, {"estimates.csv": lambda p: p.write_text("2")})
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [RUN_LISTING, "estimates.csv", "notes.txt"])
    assert (out / "estimates.csv").read_text() == "2"
    assert json.loads((out / RUN_LISTING).read_text())["files"] == ["estimates.csv"]


def test_parts_written_inside_a_stage_are_added_not_swapped(tmp_path):
    out = tmp_path / "study"
    with staged_folder(out) as stage:
        write_files(stage, {"indices.csv": lambda p: p.write_text("i")})
        write_files(stage, {"report.html": lambda p: p.write_text("r")})
    assert sorted(p.name for p in out.iterdir()) == [RUN_LISTING, "indices.csv",
                                                     "report.html"]


def test_a_resumable_run_is_kept_when_interrupted_and_dropped_on_a_mistake(tmp_path):
    out = tmp_path / "batch"
    with pytest.raises(KeyboardInterrupt), staged_folder(out, resumable=True) as stage:
        (stage / "chunk-0").write_text("done")
        raise KeyboardInterrupt
    kept = partial_folder(out)
    assert (kept / "chunk-0").exists() and not out.exists()
    with pytest.raises(ArgumentError, match="would be lost"):
        with staged_folder(out, resumable=True):
            pass
    with staged_folder(out, resumable=True, resume=True) as stage:
        assert (stage / "chunk-0").read_text() == "done"
        (stage / "results").write_text("all")
    assert sorted(p.name for p in out.iterdir()) == [RUN_LISTING, "chunk-0", "results"]
    assert not kept.exists()
    with pytest.raises(ArgumentError, match="kept runs"):  # neither resume nor overwrite
        with staged_folder(out, resumable=True):
            pass
    before = _tree(out)
    with pytest.raises(DataError):
        with staged_folder(out, resumable=True, overwrite=True) as stage:
            (stage / "results").write_text("new")
            raise DataError("a mistake")
    assert _tree(out) == before and not kept.exists()


def test_resume_seeds_the_stage_with_hard_links(tmp_path):
    out = tmp_path / "b"
    with staged_folder(out, resumable=True) as stage:
        (stage / "chunks").mkdir()
        (stage / "chunks" / "c0").write_text("x")
    inode = (out / "chunks" / "c0").stat().st_ino
    with staged_folder(out, resumable=True, resume=True) as stage:
        assert (stage / "chunks" / "c0").stat().st_ino == inode  # linked, not copied
        assert not (stage / RUN_LISTING).exists()
    assert (out / "chunks" / "c0").read_text() == "x"


def test_the_current_folder_can_be_an_output(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write_files(".", {"a.txt": lambda p: p.write_text("a")})
    assert (tmp_path / "a.txt").read_text() == "a"
    assert not [p for p in tmp_path.parent.iterdir() if "pneumact-stage" in p.name]


def test_listing_cannot_point_outside_the_folder(tmp_path):
    out = tmp_path / "run"
    write_files(out, {"a.txt": lambda p: p.write_text("a")})
    (tmp_path / "precious").write_text("keep")
    (out / RUN_LISTING).write_text(json.dumps({"files": ["../precious", "a.txt"]}))
    write_files(out, {"b.txt": lambda p: p.write_text("b")})
    assert (tmp_path / "precious").read_text() == "keep"
    assert not (out / "a.txt").exists()
    assert sorted(os.listdir(out)) == sorted([RUN_LISTING, "b.txt"])


# --------------------------------------------------------------------------- memory
def test_memory_estimate_refuses_with_the_figure(monkeypatch):
    from pneumact.errors import ResourceError
    from pneumact.simulation import memory

    monkeypatch.setattr(memory, "available_memory", lambda: 1 << 30)  # 1 GiB
    memory.check_memory(memory.simulate_bytes(1000, 3, 10), "small")
    with pytest.raises(ResourceError, match=r"about .* GiB of memory, above the limit of "
                                            r".*; 1 GiB are available"):
        memory.check_memory(memory.simulate_bytes(10**9, 3, 10), "a run of 1e9 points")


def test_a_stated_memory_limit_refuses_above_it_and_can_be_raised(monkeypatch,
                                                                 estimates_log):
    """Big work says its memory estimate first and is refused above a stated limit
    (issue 42), whatever the machine has; PNEUMACT_MEMORY_LIMIT raises or lowers it."""
    from pneumact.errors import ResourceError
    from pneumact.simulation import memory

    monkeypatch.setattr(memory, "available_memory", lambda: 1 << 40)  # 1 TiB free
    monkeypatch.delenv(memory.MEMORY_LIMIT_ENV, raising=False)
    three_gib, six_gib = 3 * 1024**3, 6 * 1024**3
    memory.check_memory(three_gib, "oat: 7 runs x 10000000 times")
    assert any("about 3 GiB of memory (limit 4 GiB)" in n for n in estimates_log), \
        estimates_log
    with pytest.raises(ResourceError, match=r"6 GiB of memory, above the limit of 4 GiB "
                                            r"\(the default; raise it") as refused:
        memory.check_memory(six_gib, "oat: 14 runs x 10000000 times")
    assert "PNEUMACT_MEMORY_LIMIT=16GiB" in refused.value.for_cli()
    monkeypatch.setenv(memory.MEMORY_LIMIT_ENV, "8GiB")
    memory.check_memory(six_gib, "oat: 14 runs x 10000000 times")  # raised: runs
    monkeypatch.setenv(memory.MEMORY_LIMIT_ENV, "lots")
    with pytest.raises(ResourceError, match="PNEUMACT_MEMORY_LIMIT = 'lots'"):
        memory.check_memory(six_gib, "a run")


def test_signal_extremes_see_both_sides_of_a_jump():
    from pneumact.experiments import PiecewiseLinear, Sine, Step

    assert Step(1.0, 0.2, 0.8).extremes(0.0, 2.0) == (0.2, 0.8)
    assert PiecewiseLinear([0, 1, 2], [0.0, 5.0, 0.0]).extremes(0.0, 0.5) == (0.0, 2.5)
    low, high = (Sine(1.0, 1.0) + 2.0).extremes(0.0, 1.0)
    assert low == pytest.approx(1.0, abs=1e-6) and high == pytest.approx(3.0, abs=1e-6)
    assert np.isfinite(low)


def test_a_folder_another_live_run_writes_is_refused_naming_that_run(tmp_path):
    """Two runs into one folder (issue 42): the second is told which run holds it, not
    advised to --overwrite (which would wipe the running one); the lock goes with the
    run, and a stale lock (its process gone) is taken over."""
    import socket
    import subprocess
    import sys

    out = tmp_path / "batch"
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lock_file(out).write_text(json.dumps({"pid": other.pid, "host": socket.gethostname(),
                                              "started": "now"}), encoding="utf-8")
        with pytest.raises(ArgumentError, match=f"another run \\(pid {other.pid}") as held:
            with staged_folder(out, resumable=True):
                pass
        assert "--overwrite" not in held.value.for_cli() and "--out" in held.value.for_cli()
        assert not out.exists() and not partial_folder(out).exists()
    finally:
        other.kill()
        other.wait()
    # the holder is gone: its lock is stale and taken over
    with staged_folder(out, resumable=True) as stage:
        assert json.loads(lock_file(out).read_text(encoding="utf-8"))["pid"] == os.getpid()
        (stage / "chunk-0").write_text("done")
    assert not lock_file(out).exists() and (out / "chunk-0").exists()


def test_an_output_folder_name_too_long_to_stage_beside_is_refused_naming_its_length(
        tmp_path):
    """A 250-character --out (issue 42, finding 9) is refused for its name, not with an
    error about the hidden staging folder that would not fit beside it."""
    with pytest.raises(ArgumentError, match="folder name is 250 characters") as refused:
        checks.check_out_dir("--out", tmp_path / ("a" * 250))
    assert "pneumact-stage" not in str(refused.value)
    assert checks.check_out_dir("--out", tmp_path / ("a" * checks.MAX_OUT_NAME_BYTES))
    written = write_files(tmp_path / ("b" * checks.MAX_OUT_NAME_BYTES),
                          {"x.csv": lambda p: p.write_text("1")})
    assert written[0].read_text() == "1"  # the longest allowed name stages and writes
