"""CPU time per row of the batch benchmark's case, robust to other load.

The case of ``bench_batch.py`` (vgt-paper, CommandValve, CommandCycle(0, 1, period=20),
Rodas4 rtol = 1e-6, the default features only; rows from ``random_sets(params, N,
seed=1)``), run with ``executor=1`` so that every row runs in this thread, timed with
``time.thread_time`` (this thread's CPU, not the wall clock, which other processes on a
shared machine distort). Prints the best and every repeat in ms per row; ``--save`` keeps
the feature table (``.npy``) for comparing two versions bit for bit.

Run (from the repository root; point PYTHONPATH at another checkout's ``src`` for the
version before a change, and alternate the two):
    PYTHONPATH=src python benchmarks/bench_row_cpu.py --engine c --rows 200 --repeats 3
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_batch import random_sets

import pneumact as pa
from pneumact.simulation.batch import simulate_batch


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="c", choices=["c", "numba"])
    parser.add_argument("--rows", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--save", type=Path, default=None, help="the features, as .npy")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", pa.PassivityWarning)
    params = pa.load_params("vgt-paper")
    model = pa.Actuator(params, valve=pa.CommandValve())
    experiment = pa.CommandCycle(0.0, 1.0, period=20.0)
    solver = pa.Rodas4(rtol=1e-6)

    def batch(table):
        return simulate_batch(model, experiment, table, executor=1, engine=args.engine,
                              solver=solver)

    batch(random_sets(params, 4, seed=0))  # warm-up: kernels loaded or built
    table = random_sets(params, args.rows, seed=1)
    cpu = []
    for _ in range(args.repeats):
        start = time.thread_time()
        result = batch(table)
        cpu.append((time.thread_time() - start) / args.rows * 1e3)
    print(f"{pa.__file__}: engine {args.engine}, CPU per row best {min(cpu):.3f} ms "
          f"(repeats {' '.join(f'{c:.3f}' for c in cpu)}), "
          f"{result.stats['steps'] / args.rows:.0f} steps per row, "
          f"{result.stats['failed']} failed")
    if args.save is not None:
        numeric = result.table.drop(columns=["status", "error"]).to_numpy(float)
        np.save(args.save, numeric)


if __name__ == "__main__":
    main()
