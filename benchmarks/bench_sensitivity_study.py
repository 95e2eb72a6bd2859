"""Speed of a global sensitivity study on the batch engine.

Run: python benchmarks/bench_sensitivity_study.py   (installed package or PYTHONPATH=src)

A Sobol study of the six LuGre parameters of the valve-driven vgt-paper cycle
(CommandValve, CommandCycle 20 s, Rodas4 rtol 1e-6) on the loop width and break-away
pressure: N = 1024 base samples without second order (8 192 runs) and with it
(14 336 runs), all local cores, kernels warm. σ0, σ1, σ2 and vs vary ±20 %; Fc and Fs
±10 % (at ±20 % a run can have Fs < Fc, which the model refuses). For comparison, the
per-run cost of the alternative a user would pick (SALib's sample through scipy
solve_ivp LSODA on the same compiled model, from bench_batch.lsoda_run) on a few runs,
and the features-only speed-up of the batch from 1 to 2 workers. Targets (issue #9, 2
cores): 14 336 runs in under 30 s; at least 1.9x from 1 to 2 workers.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import pneumact as pa
from pneumact import sensitivity as sa

VARY = {"sigma0": "20%", "sigma1": "20%", "sigma2": "20%", "vs": "20%", "Fc": "10%",
        "Fs": "10%"}
FEATURES = ["loop_width_pressure", "breakaway_pressure"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=1024)
    parser.add_argument("--lsoda-runs", type=int, default=5)
    parser.add_argument("--scaling-runs", type=int, default=2000)
    args = parser.parse_args()
    warnings.simplefilter("ignore", pa.PassivityWarning)
    from bench_batch import lsoda_run

    params = pa.load_params("vgt-paper")
    model = pa.Actuator(params, valve=pa.CommandValve())
    experiment = pa.CommandCycle(period=20.0)
    problem = sa.Problem.around(params, VARY)
    with warnings.catch_warnings():  # warm-up: compile or load the kernel
        warnings.simplefilter("ignore", sa.SensitivityWarning)
        sa.sobol(problem, sa.model_outputs(model, experiment, problem, FEATURES), n=8)
    for second_order in (False, True):
        start = time.perf_counter()
        study = sa.sobol(problem, sa.model_outputs(model, experiment, problem, FEATURES),
                         n=args.n, second_order=second_order)
        wall = time.perf_counter() - start
        runs = len(study.sample)
        print(f"Sobol N = {args.n}, second order {second_order!s:5s}: {runs} runs in "
              f"{wall:.1f} s ({runs / wall:.0f} runs/s, analysis included)")
        if second_order:
            print(f"  -> target 14 336 runs < 30 s: {'MET' if wall < 30 else 'NOT MET'}")
    for feature in FEATURES:
        table = study.to_pandas(output=feature)["ST"].sort_values(ascending=False)
        print(f"  ST of {feature}: " + ", ".join(f"{n} {v:.3f}" for n, v in table.items()))

    rates = {1: 0.0, 2: 0.0}
    x = study.sample.to_numpy()[: args.scaling_runs]
    for _ in range(3):  # alternate 1 and 2 workers so that drifts of the VM hit both
        for workers in (1, 2):
            evaluate = sa.model_outputs(model, experiment, problem, FEATURES, executor=workers)
            start = time.perf_counter()
            evaluate(x)
            rates[workers] = max(rates[workers], len(x) / (time.perf_counter() - start))
    for workers, rate in rates.items():
        print(f"features-only batch of {len(x)} runs, {workers} worker(s): {rate:.0f} runs/s "
              "(best of 3)")
    speedup = rates[2] / rates[1]
    print(f"  -> speed-up 1 -> 2 workers {speedup:.2f}x (target >= 1.9x: "
          f"{'MET' if speedup >= 1.9 else 'NOT MET'})")

    solver = pa.Rodas4(rtol=1e-6)
    rows = study.sample.iloc[: args.lsoda_runs]
    start = time.perf_counter()
    for _, row in rows.iterrows():
        lsoda_run(model, experiment, solver, row)
    per_run = (time.perf_counter() - start) / len(rows)
    print(f"SALib sample through scipy solve_ivp LSODA: {1e3 * per_run:.1f} ms per run -> "
          f"14 336 runs would take {14336 * per_run:.0f} s on one core "
          f"({14336 * per_run / 2:.0f} s on two), vs the batch engine above")
    print(f"  (LSODA per run / batch per run on 2 workers: {per_run * rates[2]:.0f}x)")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
