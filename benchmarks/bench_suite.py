"""Benchmark: how long the test suite takes, warm (kernel caches filled) or cold (empty
kernel and numba caches, as on a fresh clone: every kernel compiles once).

Runs ``python -m pytest -x -q -p no:cacheprovider`` from the repository root in a
subprocess (one test process per core, pyproject's ``addopts``) and prints its wall time
and pytest's summary line; ``--serial`` also runs it in one process (``-n 0``, what a
plain pytest did before) and prints the ratio. Cold uses temporary ``PNEUMACT_CACHE_DIR``
and ``NUMBA_CACHE_DIR`` (fresh ones per run), so the user's caches are left alone.
The suite's target (2 cores): under 6 minutes cold.

``--census`` (with ``--cold``) also records every numba compilation with the test that
caused it (``compile_census.py``) and prints the compile time per kernel module, largest
first, with the tests that needed it: a kernel that one test alone needs is where a cold
suite's minutes can be won.

Run (after ``pip install -e ".[test]"``):
    python benchmarks/bench_suite.py [--cold] [--serial] [--census] [-- extra pytest arguments]
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_COLD_S = 360.0


def run_suite(command: list[str], cold: bool,
              census: Path | None = None) -> tuple[subprocess.CompletedProcess, float]:
    """One run of ``command``: (the finished process, wall seconds); with ``census`` a
    folder that receives the compile census."""
    with tempfile.TemporaryDirectory(prefix="pneumact-suite-") as tmp:
        env = dict(os.environ)
        if cold:
            env.update(PNEUMACT_CACHE_DIR=str(Path(tmp) / "kernels"),
                       NUMBA_CACHE_DIR=str(Path(tmp) / "numba"))
        if census is not None:
            here = str(Path(__file__).resolve().parent)
            env.update(PNEUMACT_CENSUS_DIR=str(census), PYTHONPATH=os.pathsep.join(
                filter(None, [here, env.get("PYTHONPATH")])))
            command = [*command, "-p", "compile_census"]
        started = time.perf_counter()
        proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True,
                              check=False)
        return proc, time.perf_counter() - started


def print_census(folder: Path, rows_shown: int = 30) -> None:
    """Compile seconds per module (a generated kernel, or a package module), largest first,
    with the number of tests that compiled it and the test when it is one alone."""
    seconds: dict[str, float] = collections.defaultdict(float)
    tests: dict[str, set[str]] = collections.defaultdict(set)
    for path in folder.glob("*.jsonl"):
        for line in path.read_text(encoding="utf-8").splitlines():
            row = json.loads(line)
            seconds[row["module"]] += row["seconds"]
            tests[row["module"]].add(row["test"])
    total = sum(seconds.values())
    print(f"  compile census: {total:.0f} s of numba compilation over {len(seconds)} modules")
    for module in sorted(seconds, key=seconds.get, reverse=True)[:rows_shown]:
        alone = next(iter(tests[module])) if len(tests[module]) == 1 else ""
        print(f"  {seconds[module]:6.1f} s  {len(tests[module]):3d} tests  {module[:60]}  {alone}")


def report(command: list[str], proc: subprocess.CompletedProcess, wall: float) -> None:
    lines = [line for line in proc.stdout.splitlines() if line.strip()]
    print(f"  {' '.join(command[1:])}: exit {proc.returncode}, {wall:.0f} s "
          f"({wall / 60:.1f} min); load average now {os.getloadavg()[0]:.2f}")
    print(f"  pytest: {lines[-1] if lines else proc.stderr[-500:]}")
    if proc.returncode != 0:
        print(proc.stdout[-4000:])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", action="store_true", help="empty kernel and numba caches")
    parser.add_argument("--serial", action="store_true",
                        help="also run in one process (-n 0) and print the ratio")
    parser.add_argument("--census", action="store_true",
                        help="record numba compilations per test and print them per kernel")
    parser.add_argument("pytest_args", nargs="*", help="more pytest arguments (after --)")
    args = parser.parse_args(argv)
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
               *args.pytest_args]
    print(f"pneumact test suite benchmark ({'cold' if args.cold else 'warm'}); "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory(prefix="pneumact-census-") as census:
        proc, wall = run_suite(command, args.cold, Path(census) if args.census else None)
        report(command, proc, wall)
        if args.census:
            print_census(Path(census))
    if args.cold:
        print(f"  target (cold, 2 cores): under {TARGET_COLD_S / 60:g} min: "
              f"{'met' if wall <= TARGET_COLD_S else 'NOT met'}")
    if args.serial:
        serial = [*command, "-n", "0"]
        serial_proc, serial_wall = run_suite(serial, args.cold)
        report(serial, serial_proc, serial_wall)
        print(f"  one process per core: {serial_wall / wall:.2f}x faster than one process")
    sys.exit(proc.returncode)


if __name__ == "__main__":
    main()
