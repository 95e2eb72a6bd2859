"""Benchmark: the whole paper, ``pneumact reproduce`` (and ``--quick``), with warm kernels.

Each run is the real command line in a fresh subprocess (interpreter start, imports and
writing the folder included), using the user's kernel cache: a first run fills it if it
is cold (reported separately, not counted), then ``--repeats`` runs are timed and the
best and median are printed. The quick mode runs inside the test suite; the full mode is
the one the README quotes.

Run (after ``pip install -e .``, or with ``PYTHONPATH=src`` from the repository root):
    python benchmarks/bench_reproduce.py [--repeats 3] [--quick-only]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run(args: list[str], out: Path) -> tuple[float, float]:
    """(wall time, CPU time) of one ``pneumact reproduce`` in a fresh process."""
    cpu, started = _cpu(), time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pneumact", "reproduce", *args, "--out",
                           str(out)], capture_output=True, text=True, check=False)
    wall = time.perf_counter() - started
    if proc.returncode != 0:
        raise RuntimeError(f"reproduce {args} failed: {proc.stderr[-2000:]}")
    return wall, _cpu() - cpu


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per mode")
    parser.add_argument("--quick-only", action="store_true", help="time --quick only")
    args = parser.parse_args(argv)
    print(f"pneumact reproduce benchmark; {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.2f}")
    modes = {"pneumact reproduce --quick": ["--quick"]}
    if not args.quick_only:
        modes["pneumact reproduce"] = []
    with tempfile.TemporaryDirectory(prefix="pneumact-reproduce-") as tmp:
        for label, extra in modes.items():
            first, _ = run(extra, Path(tmp) / "warm-up")
            runs = [run(extra, Path(tmp) / f"run{i}") for i in range(args.repeats)]
            walls = [wall for wall, _ in runs]
            best = min(runs)
            print(f"\n{label}")
            print(f"  first run (fills the kernel cache if it was cold): {first:.1f} s")
            print(f"  warm: best {best[0]:.1f} s (CPU {best[1]:.1f} s), median "
                  f"{statistics.median(walls):.1f} s of {args.repeats}; load average now "
                  f"{os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
