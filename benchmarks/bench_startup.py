"""Benchmark: how long a user waits before results, cold and warm.

Measured, each in a fresh subprocess running the real command line (``pneumact
simulate``, the quick start's main job, and ``--valve command``):

- cold: empty kernel cache (``PNEUMACT_CACHE_DIR``) and empty numba cache
  (``NUMBA_CACHE_DIR``), as on a fresh install: the whole command, and the time from the
  first kernel generation (compilation starts) to the end of the command;
- warm: the same command again, caches filled: the overhead from the launch of the
  process (interpreter start included) to the moment the integrator is entered, and the
  whole command (with the interpreter's exit).

Targets (issue #7, this 2-core machine): a cold ``pneumact simulate`` done within 15 s of
starting to compile; under 1 s of overhead before the simulation when warm.

Run (after ``pip install -e .``, or with ``PYTHONPATH=src`` from the repository root):
    python benchmarks/bench_startup.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_COLD_S = 15.0
TARGET_OVERHEAD_S = 1.0

# The command line, with two timestamps taken on the way: when the first kernel is
# generated or loaded, and when the integrator is entered.
CHILD = r"""
import time
start = time.perf_counter()
launched = time.time() - float(__import__("os").environ["PNEUMACT_BENCH_LAUNCH"])
import importlib, json, sys
marks = {"interpreter": launched}
codegen = importlib.import_module("pneumact.core.codegen")
simulate = importlib.import_module("pneumact.simulation.simulate")
load, run_kernel = codegen.load, simulate.run_kernel

def timed_load(*a, **k):
    marks.setdefault("kernel", time.perf_counter() - start)
    return load(*a, **k)

def timed_run(*a, **k):
    marks.setdefault("integrator", time.perf_counter() - start)
    return run_kernel(*a, **k)

codegen.load, simulate.run_kernel = timed_load, timed_run
from pneumact.cli import app
try:
    app(sys.argv[1:])
except SystemExit as exc:
    marks["exit"] = exc.code
marks["total"] = time.perf_counter() - start
print("MARKS " + json.dumps(marks))
"""


def run(args: list[str], env: dict, out: Path) -> dict:
    started = time.perf_counter()
    env = dict(env, PNEUMACT_BENCH_LAUNCH=repr(time.time()))
    proc = subprocess.run([sys.executable, "-c", CHILD, *args, "--out", str(out)], env=env,
                          capture_output=True, text=True, check=False)
    wall = time.perf_counter() - started
    marks = [line for line in proc.stdout.splitlines() if line.startswith("MARKS ")]
    if proc.returncode != 0 or not marks:
        raise RuntimeError(f"{args} failed: {proc.stderr[-2000:]}")
    result = json.loads(marks[-1][len("MARKS "):])
    result["wall"] = wall  # includes the interpreter's start and its exit
    return result


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="warm runs per command")
    args = parser.parse_args(argv)
    src = Path(__file__).resolve().parents[1] / "src"
    print(f"pneumact start-up benchmark; {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.2f}")
    commands = {"pneumact simulate": ["simulate"],
                "pneumact simulate --valve command": ["simulate", "--valve", "command"]}
    for label, command in commands.items():
        with tempfile.TemporaryDirectory(prefix="pneumact-startup-") as tmp:
            env = dict(os.environ, PNEUMACT_CACHE_DIR=str(Path(tmp) / "kernels"),
                       NUMBA_CACHE_DIR=str(Path(tmp) / "numba"),
                       PYTHONPATH=os.pathsep.join([str(src), *filter(None, [
                           os.environ.get("PYTHONPATH")])]))
            cold = run(command, env, Path(tmp) / "out")
            warm = [run(command, env, Path(tmp) / "out") for _ in range(args.repeats)]
        since_compile = cold["total"] - cold["kernel"]
        overhead = statistics.median(w["integrator"] for w in warm)
        startup = statistics.median(w["interpreter"] for w in warm)
        print(f"\n{label}")
        print(f"  cold: whole command {cold['wall']:.1f} s; from the first kernel generation "
              f"to the end {since_compile:.1f} s (target <= {TARGET_COLD_S:g} s: "
              f"{'met' if since_compile <= TARGET_COLD_S else 'NOT met'})")
        print(f"  warm: before the integrator {overhead:.2f} s + interpreter start "
              f"{startup:.2f} s = {overhead + startup:.2f} s (target < {TARGET_OVERHEAD_S:g} s: "
              f"{'met' if overhead + startup < TARGET_OVERHEAD_S else 'NOT met'}); whole "
              f"command {statistics.median(w['wall'] for w in warm):.2f} s "
              f"(median of {args.repeats})")


if __name__ == "__main__":
    main()
