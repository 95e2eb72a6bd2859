"""Benchmark: the whole paper, ``pneumact reproduce`` (and ``--quick``), with warm kernels.

Each run is the real command line in a fresh subprocess (interpreter start, imports and
writing the folder included), using the user's kernel cache: a first run fills it if it
is cold (reported separately, not counted), then ``--repeats`` runs are timed and the
best and median are printed. The quick mode runs inside the test suite; the full mode is
the one the README quotes.

``--sections`` instead runs ``reproduce()`` once in this process and prints, per section,
the wall and CPU time (this process's threads and its children) it took: where the time
goes (``--seal-data DIR`` adds the real seal section, ``--quick`` the quick mode). Both
modes run part of their work in a worker process beside the sections (the full mode two
jobs, the quick mode whole sections: ``reproduction.Sizes.apart``); its CPU time is
counted where the worker is let go (the section whose result is taken last) and also
shown on its own ("in the worker"): the rest is the main process's, and on two idle cores
the wall time is about the larger of the two. A section the worker makes is listed where
its result is taken, after the sections made here.

Run (after ``pip install -e .``, or with ``PYTHONPATH=src`` from the repository root):
    python benchmarks/bench_reproduce.py [--repeats 3] [--quick-only]
    python benchmarks/bench_reproduce.py --sections [--quick] [--seal-data DIR]
"""

from __future__ import annotations

import argparse
import itertools
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


def _cpu_here() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    return own.ru_utime + own.ru_stime + _cpu()


def sections(quick: bool, seal_data: str | None) -> None:
    """One ``reproduce()`` in this process, timed by section (wall and CPU)."""
    from pneumact.reproduction import reproduce

    marks: list[tuple[str, float, float, float]] = []

    def progress(report) -> None:
        if not marks or marks[-1][0] != report.stage:
            marks.append((report.stage, time.perf_counter(), _cpu_here(), _cpu()))

    print(f"reproduce(quick={quick}) by section; {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory(prefix="pneumact-reproduce-") as tmp:
        reproduce(Path(tmp) / "out", quick=quick, progress=progress, seal_data=seal_data)
    marks.append(("end", time.perf_counter(), _cpu_here(), _cpu()))
    for (name, wall, cpu, child), (_, next_wall, next_cpu, next_child) in \
            itertools.pairwise(marks):
        beside = (f" (in the worker {next_child - child:5.1f} s)" if next_child - child > 0.05
                  else "")
        print(f"  {name:28s} wall {next_wall - wall:6.1f} s  CPU {next_cpu - cpu:6.1f} s"
              f"{beside}")
    worker = marks[-1][3] - marks[0][3]
    print(f"  {'total':28s} wall {marks[-1][1] - marks[0][1]:6.1f} s  CPU "
          f"{marks[-1][2] - marks[0][2]:6.1f} s (in the worker {worker:.1f} s); load average "
          f"now {os.getloadavg()[0]:.2f}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per mode")
    parser.add_argument("--quick-only", action="store_true", help="time --quick only")
    parser.add_argument("--sections", action="store_true",
                        help="one reproduce() in this process, timed by section")
    parser.add_argument("--quick", action="store_true", help="with --sections: quick mode")
    parser.add_argument("--seal-data", default=None,
                        help="with --sections: the TU Delft seal records' folder")
    args = parser.parse_args(argv)
    if args.sections:
        sections(args.quick, args.seal_data)
        return
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
