"""Benchmark: how long the test suite takes, warm (kernel caches filled) or cold (empty
kernel and numba caches, as on a fresh clone: every kernel compiles once).

Runs ``python -m pytest -x -q -p no:cacheprovider`` from the repository root in a
subprocess and prints its wall time and pytest's summary line. Cold uses temporary
``PNEUMACT_CACHE_DIR`` and ``NUMBA_CACHE_DIR``, so the user's caches are left alone.
The suite's target (2 cores): under 6 minutes cold.

Run (after ``pip install -e ".[test]"``):
    python benchmarks/bench_suite.py [--cold] [-- extra pytest arguments]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_COLD_S = 360.0


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", action="store_true", help="empty kernel and numba caches")
    parser.add_argument("pytest_args", nargs="*", help="more pytest arguments (after --)")
    args = parser.parse_args(argv)
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
               *args.pytest_args]
    print(f"pneumact test suite benchmark ({'cold' if args.cold else 'warm'}); "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory(prefix="pneumact-suite-") as tmp:
        env = dict(os.environ)
        if args.cold:
            env.update(PNEUMACT_CACHE_DIR=str(Path(tmp) / "kernels"),
                       NUMBA_CACHE_DIR=str(Path(tmp) / "numba"))
        started = time.perf_counter()
        proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True,
                              check=False)
        wall = time.perf_counter() - started
    lines = [line for line in proc.stdout.splitlines() if line.strip()]
    print(f"  {' '.join(command[1:])}: exit {proc.returncode}, {wall:.0f} s "
          f"({wall / 60:.1f} min); load average now {os.getloadavg()[0]:.2f}")
    print(f"  pytest: {lines[-1] if lines else proc.stderr[-500:]}")
    if args.cold:
        print(f"  target (cold, 2 cores): under {TARGET_COLD_S / 60:g} min: "
              f"{'met' if wall <= TARGET_COLD_S else 'NOT met'}")
    if proc.returncode != 0:
        print(proc.stdout[-4000:])
    sys.exit(proc.returncode)


if __name__ == "__main__":
    main()
