"""Controller tuning: a PID with a filtered derivative on the regulator-driven vgt-paper
actuator, robust over 50 uncertainty samples (Fc, Fs, σ0 ±15 %) and 4 reference moves
(issue 23 asks < 2 min on 2 cores). Against the alternative a user would write: a
Python loop of ``pa.simulate`` + ``loop_metrics`` for the same runs.

    python benchmarks/bench_tuning.py [--workers N]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--samples", type=int, default=50)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    import pneumact as pa
    from pneumact.control import PID, ClosedLoop, Specs, default_moves, loop_metrics, tune
    from pneumact.identification import Estimates

    params = pa.load_params("vgt-paper")
    plant = pa.Actuator(params, pa.LuGre(), valve=pa.PressureRegulator())
    loop = ClosedLoop(plant, PID(kp=5e6, ki=5e7, kd=1e4, filter_time=2e-3, u_min=10e3,
                                 u_max=float(params["p_atm"])))
    names = ("Fc", "Fs", "sigma0")
    values = np.array([float(params[n]) for n in names])
    estimates = Estimates(names, values, 0.15 * values, np.diag((0.15 * values) ** 2), 100)
    specs = Specs.parse("settling=0.3,overshoot=5%,error=20um,no-hunting")
    tune(loop, specs, n_global=2, max_evaluations=2, rounds=0)  # compile (not timed)
    start = time.perf_counter()
    result = tune(loop, specs, uncertainty=estimates, samples=args.samples,
                  executor=args.workers)
    wall = time.perf_counter() - start
    print(f"tune: {args.samples} samples x {len(result.moves)} moves, {result.runs} closed-"
          f"loop runs on {args.workers} workers: {wall:.1f} s ({result.runs / wall:.0f} "
          f"runs/s); specs met on {100 * result.met:.0f} % of the samples")
    print(result.gains_table()[["gain", "value", "unit", "datasheet value",
                                "datasheet unit"]].to_string(index=False))
    moves = default_moves(result.loop, specs)
    n_user = 40
    start = time.perf_counter()
    for i in range(n_user):
        move = moves[i % len(moves)]
        own = dataclasses.replace(result.loop, bias=result.biases[0, i % len(moves)])
        run = pa.simulate(own, move.experiment())
        loop_metrics(run, t_step=move.t_ref, start=move.start, target=move.stop)
    per_run = (time.perf_counter() - start) / n_user
    print(f"a Python loop of pa.simulate + loop_metrics: {1e3 * per_run:.1f} ms per run -> "
          f"{per_run * result.runs:.0f} s for the same runs ({per_run * result.runs / wall:.1f}"
          f"x the tuner)")


if __name__ == "__main__":
    main()
