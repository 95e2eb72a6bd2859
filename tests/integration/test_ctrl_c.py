"""Ctrl-C ends long work within seconds (issue 42): the command line exits 130 with one
line and no traceback, in the middle of a multistart, a batch, a study or a comparison.

Each command runs in its own process; the test sends SIGINT once the long stage has
reported its first finished item (a hook on ``pneumact.progress.notify`` says so), so the
compilation and start-up before it never count.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pneumact.io.tables import partial_folder
from reference import INTERRUPT_EXIT_S

DATA = Path(__file__).resolve().parents[1] / "data" / "good"
SRC = Path(__file__).resolve().parents[2] / "src"

#: the command line, with a hook that prints STAGE-STARTED once the stage has done something
_HOOKED = """
import os
import sys
import pneumact.progress as progress

stage, real = sys.argv[1], progress.notify

def notify(callback, name, done=0, *args, **kwargs):
    if name == stage and done > 0 and not getattr(notify, "said", False):
        notify.said = True
        sys.stderr.write("STAGE-STARTED\\n")
        sys.stderr.flush()
    return real(callback, name, done, *args, **kwargs)

progress.notify = notify

if os.environ.get("HOOK_CALL"):  # "module:function": say CALL-STARTED when it is first called
    import importlib

    where, name = os.environ["HOOK_CALL"].split(":")
    module = importlib.import_module(where)
    real_call = getattr(module, name)

    def called(*args, **kwargs):
        sys.stderr.write("CALL-STARTED\\n")
        sys.stderr.flush()
        return real_call(*args, **kwargs)

    setattr(module, name, called)
sys.argv = ["pneumact", *sys.argv[2:]]
from pneumact.__main__ import main
main()
"""


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupt(stage: str, args: list[str], cwd: Path, *, marker: str = "STAGE-STARTED",
               extra_env: dict[str, str] | None = None, delay: float = 0.3,
               ) -> tuple[int, float, str]:
    """(exit code, seconds from SIGINT to exit, stderr) of ``pneumact ARGS`` interrupted
    ``delay`` seconds after ``stage`` has reported progress (or ``marker`` was printed)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get(
        "PYTHONPATH", "")]), COLUMNS="200", **(extra_env or {}))
    # a pytest-xdist worker ignores SIGINT, and an ignored signal stays ignored across
    # exec: the child must start with the default handler, as in a terminal
    proc = subprocess.Popen([sys.executable, "-c", _HOOKED, stage, *args], cwd=cwd, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_default_sigint)
    lines = []
    try:
        for line in proc.stderr:  # type: ignore[union-attr]
            lines.append(line)
            if marker in line:
                break
        else:
            pytest.fail(f"the stage {stage!r} never started ({marker!r}): {''.join(lines)[-2000:]}")
        time.sleep(delay)  # well inside the stage
        sent = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        rest = proc.communicate(timeout=120)[1]
        return proc.returncode, time.perf_counter() - sent, "".join(lines) + rest
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        if proc.stderr is not None:
            proc.stderr.close()


def _assert_stopped(code: int, seconds: float, stderr: str) -> None:
    assert code == 130, stderr[-2000:]
    assert "Traceback" not in stderr and "interrupted" in stderr
    assert seconds < INTERRUPT_EXIT_S, f"{seconds:.1f} s from Ctrl-C to exit"


def test_ctrl_c_stops_a_multistart_fit(tmp_path):
    code, seconds, stderr = _interrupt("multistart", [
        "fit", str(DATA / "record.csv"), "--free", "Fc,Fs", "--multistart", "2000",
        "--workers", "2", "--out", "OUT"], tmp_path)
    _assert_stopped(code, seconds, stderr)
    assert not (tmp_path / "OUT").exists()
    # a fit resumes nothing: the line says what is kept instead of advising --resume
    assert "--resume" not in stderr and "kept as it was" in stderr


def test_ctrl_c_stops_a_batch_and_keeps_its_chunks(tmp_path):
    rows = "\n".join(f"{2.0 + 0.001 * k},{3.0 + 0.001 * k}" for k in range(4000))
    (tmp_path / "table.csv").write_text(f"Fc [N],Fs [N]\n{rows}\n", encoding="utf-8")
    code, seconds, stderr = _interrupt("batch", [
        "simulate-batch", "table.csv", "--t-end", "2", "--workers", "2", "--chunk-size",
        "20", "--out", "OUT"], tmp_path)
    _assert_stopped(code, seconds, stderr)
    assert "--resume" in stderr
    kept = partial_folder(tmp_path / "OUT")  # the finished chunks, for --resume
    assert kept.is_dir() and any(p.is_file() for p in kept.rglob("*"))


def test_ctrl_c_stops_a_sensitivity_study_and_keeps_its_runs(tmp_path):
    code, seconds, stderr = _interrupt("batch", [
        "sensitivity", "sobol", "--n", "4096", "--t-end", "2", "--workers", "2",
        "--chunk-size", "16", "--out", "STUDY"], tmp_path)
    _assert_stopped(code, seconds, stderr)
    assert "--resume" in stderr
    kept = partial_folder(tmp_path / "STUDY")  # for --resume
    assert kept.is_dir() and any(p.is_file() for p in kept.rglob("*"))


def test_ctrl_c_stops_a_comparison_of_friction_laws(tmp_path):
    code, seconds, stderr = _interrupt("compare", [
        "compare", str(DATA / "record.csv"), "--workers", "2", "--out", "OUT"], tmp_path)
    _assert_stopped(code, seconds, stderr)
    assert not (tmp_path / "OUT").exists()


def test_ctrl_c_stops_a_comparison_while_its_kernel_compiles(tmp_path):
    """A kernel compiling in a worker thread cannot be interrupted from Python: the command
    leaves it and exits (before: 112 s from Ctrl-C to exit, the rest of the compilation)."""
    code, seconds, stderr = _interrupt("compare", [
        "compare", str(DATA / "record.csv"), "--workers", "2", "--out", "OUT"], tmp_path,
        marker="CALL-STARTED", delay=3.0, extra_env={  # 3 s into a law's fit: compiling
            "NUMBA_CACHE_DIR": str(tmp_path / "kernels"),  # empty: every kernel compiles
            "HOOK_CALL": "pneumact.validation.compare:fit"})  # a law's fit, in a thread
    assert "compiling the model" in stderr
    _assert_stopped(code, seconds, stderr)
    assert not (tmp_path / "OUT").exists()
    assert "--resume" not in stderr
