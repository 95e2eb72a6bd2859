"""Speed of identification: the paper's staged procedure, the whole procedure, and the
Jacobian choice.

Run: python benchmarks/bench_identify.py   (installed package or PYTHONPATH=src)

1. The staged identification alone (paper section III.2: spring, eq. 13, eq. 12,
   presliding output error; ``refine=False``) of the synthetic vgt-paper campaign
   (``design_campaign``, default noise, seed 1), kernels warm: median wall time
   (issue 18 target: under 1 s).
2. The whole procedure (stages, joint refinement of all eight spring and friction
   parameters over all records, the input-noise share of the covariance, residual
   checks and verdicts; ``identify_paper`` defaults): median wall time on all cores
   (issue 18 target: under 30 s on 2 cores), and the result table against the truth.
3. The signature alone (``identify_signature`` on the campaign's sweep): median wall
   time (issue 38 target: under 5 s).
4. The σ0/σ1 output-error fit of stage (d) on the presliding record from a far-off
   start, with scipy least_squares and (i) the forward-sensitivity Jacobian, (ii) a
   2-point finite-difference Jacobian (what a user of scipy or lmfit gets), and (iii) a
   3-point one: wall time, simulations, iterations and the ratio.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings

import pneumact as pa
from pneumact.identification import (
    fit,
    identify_paper,
    identify_signature,
    synthetic_campaign,
)
from pneumact.identification.stages import presliding_window

START = {"F0": 0.92, "k": 0.86, "Fc": 0.77, "sigma2": 1.5, "Fs": 1.25, "vs": 2.0,
         "sigma0": 1.5, "sigma1": 0.5}


def fresh(records):
    """New record objects with the same data, their rebuilt inputs forgotten: each timed
    run rebuilds its inputs (a fit remembers the rebuilt input of data it has seen; a
    user's first fit pays for it)."""
    from pneumact.identification.fit import forget_rebuilt_inputs
    from pneumact.io import Record

    forget_rebuilt_inputs()
    return [Record.from_arrays(r.time, r.signals, r.units, r.source, r.meta) for r in records]


def timed(fn, repeats: int):
    fn()  # warm-up: kernel compilation or cache load
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore", pa.PassivityWarning)
    truth = pa.load_params("vgt-paper")
    records = synthetic_campaign(truth, seed=1)
    start = truth.replace({n: truth[n] * f for n, f in START.items()})
    print(f"synthetic campaign: {len(records)} records, "
          f"{sum(len(r) for r in records)} samples")

    wall, staged = timed(lambda: identify_paper(fresh(records), start, refine=False),
                         args.repeats)
    stage_d = staged.stages["presliding"].extra["fit"]
    print(f"staged identification alone: {wall:.2f} s (median of {args.repeats}), "
          f"{stage_d.simulations} simulations (stage d; stages a-c simulate nothing)")
    print(f"  -> target < 1 s: {'MET' if wall < 1 else 'NOT MET'}")
    wall, result = timed(lambda: identify_paper(fresh(records), start), args.repeats)
    print(f"whole procedure (stages, joint refinement, input-noise intervals, checks): "
          f"{wall:.2f} s (median of {args.repeats}), {result.joint.simulations} "
          f"simulations in the joint fit; {result.headline()}")
    table = result.to_pandas(truth=truth)
    print(table[["stage", "staged", "value", "stderr", "truth", "error_%",
                 "truth_in_ci95", "verdict"]].to_string())
    print(f"  -> target < 30 s on 2 cores: {'MET' if wall < 30 else 'NOT MET'}")

    sweep = [r for r in records if r.meta["kind"] == "sweep"]
    wall, signature = timed(lambda: identify_signature(fresh(sweep), start), args.repeats)
    print(f"signature (one sweep: F0, k, Fc and the valve numbers): {1e3 * wall:.1f} ms "
          f"(median of {args.repeats}); {signature.headline()}")
    print(f"  -> target < 5 s: {'MET' if wall < 5 else 'NOT MET'}")

    presliding = next(r for r in records if r.meta["kind"] == "presliding")
    current = staged.parameters_unchecked  # stages a-c; σ0, σ1 refitted from the start
    model = pa.Actuator(current, valve=pa.PressureSource())
    window = (presliding_window(presliding, current), presliding.time[-1])
    begin = {"sigma0": start["sigma0"], "sigma1": start["sigma1"]}
    rows = []
    for jacobian in ("sensitivities", "2-point", "3-point"):
        wall, res = timed(lambda j=jacobian: fit(
            model, fresh([presliding])[0], ["sigma0", "sigma1"], start=begin,
            offsets=["position"],
            window=window, optimizer=pa.Optimizer(jacobian=j)), args.repeats)
        rows.append((jacobian, wall, res))
        print(f"fit sigma0, sigma1 with {jacobian:13s} Jacobian: {1e3 * wall:8.1f} ms, "
              f"{res.simulations:3d} simulations, {res.iterations:3d} evaluations, "
              f"sigma0 = {res.values['sigma0']:.6g}, sigma1 = {res.values['sigma1']:.6g}")
    base, reference = rows[0][1], rows[0][2].values
    converged = []
    for jacobian, wall, res in rows[1:]:
        ok = all(abs(res.values[n] / reference[n] - 1) < 0.01 for n in ("sigma0", "sigma1"))
        converged.append((wall, jacobian) if ok else None)
        print(f"  {jacobian} / sensitivities: {wall / base:.2f}x"
              + ("" if ok else "  (did not converge: stopped within 1 % of the start)"))
    usable = [c for c in converged if c is not None]
    if usable:
        wall, jacobian = min(usable)
        print(f"  -> target >= 3x faster than finite differences: "
              f"{'MET' if wall / base >= 3 else 'NOT MET'} ({wall / base:.2f}x against "
              f"{jacobian}, the fastest difference scheme that converged)")


if __name__ == "__main__":
    main()
