"""Identification on a family of actuators: accuracy, verdicts, interval coverage, time.

Run: python benchmarks/bench_identify_family.py [--actuators 40] [--seeds 2] [--seed 7]
[--family wide] [--bench] [--rounds 2 [--together]] [--validation] [--keep DIR]
[--recombine DIR]

Draws actuators from ``parameters.family.ActuatorFamily`` (the ranges of issue 18: Fc
0.5-10 N, Fs/Fc 1.05-2, σ0 1e4-1e6 N/m, σ1 10-1000 N·s/m, σ2 0.5-30 N·s/m, vs 0.1-10
mm/s, δ 1 or 2, realistic geometry; with ``--family wide``, ``ActuatorFamily.wide()``:
diaphragms of 30-250 mm, strokes of 8-50 mm, 0.05-6 kg, Fc 0.3-300 N scaled with the
size, Fs/Fc 1.05-2.2, vs 0.05-20 mm/s), designs each one's bench campaign from a prior up
to ±50 % off, simulates it with sensor noise for each noise seed, identifies it from
that prior (``identify_paper`` defaults), and prints:

- per actuator and seed: the wall time, the verdicts and the errors;
- per parameter: how often it is identified, the largest error of an identified one
  against its tolerance (5 %; σ0, σ1 15 %), and the coverage of the reported 95 %
  intervals;
- overall: the identified share, the coverage of every reported interval, and the
  median and largest wall time.

With ``--bench`` each campaign also gets what a real bench adds, drawn per campaign
(``identification.BenchFamily``): a pressure-sensor offset (±0-2 kPa), a
position-sensor lag (none in a third of the campaigns, else 0.5-20 ms log-uniform), a
position resolution (none in a third, else 2-50 µm) and a sample rate (none in half,
else 100 Hz-1 kHz, the records resampled); the table then adds whether each fault was named.

With ``--rounds 2`` each campaign gets a second round designed from the first round's
result (``PaperIdentification.next_round``), simulated on the same actuator (and bench),
and identified from its records with the first round's estimates as the prior (with
``--together``, from both rounds' records); the tables are printed per round, and for
the two rounds combined per parameter (``combine_rounds``, round "1+2"; not with
``--together``, whose rounds share records). ``--keep DIR`` pickles each campaign's
rounds as ``combine.RoundEstimates`` (with the truth) for a later look.

``--recombine DIR``: no identification; the rounds kept in ``DIR`` combined again with
the current rules (``combine.combined_table``), and the "1+2" table printed.

``--validation``: the setting of ``tests/validation/test_identification_family.py``
(one noise seed per actuator, its index; 6 ramp pairs; 16 input replicates; the second
round's noise seeded with 1000 + the index) instead of seeds 0.. for every actuator,
10 ramp pairs and 64 replicates.

The same study, smaller, is the validation test
``tests/validation/test_identification_family.py``.
"""

from __future__ import annotations

import argparse
import os
import pickle
import statistics
import sys
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from pneumact.identification import (
    BenchFamily,
    Noise,
    combine_rounds,
    design_campaign,
    identify_paper,
    synthetic_campaign,
)
from pneumact.identification.campaign import add_noise
from pneumact.identification.combine import combined_table, round_estimates
from pneumact.parameters.family import ActuatorFamily
from pneumact.progress import stop_threads

FREE = ("F0", "k", "Fc", "sigma2", "Fs", "vs", "sigma0", "sigma1")
TOLERANCE = {"F0": 5.0, "k": 5.0, "Fc": 5.0, "sigma2": 5.0, "Fs": 5.0, "vs": 5.0,
             "sigma0": 15.0, "sigma1": 15.0}
SPREAD = 0.5


def prior_of(truth, rng):
    factor = {n: rng.uniform(1 - SPREAD, 1 + SPREAD) for n in FREE}
    values = {n: truth[n] * factor[n] for n in FREE}
    values["Fs"] = values["Fc"] * (1 + (truth["Fs"] / truth["Fc"] - 1) * factor["Fs"])
    return truth.replace(values)


def bench_faults(noise: Noise | None) -> dict[str, float]:
    """The drawn bench's faults as the table's columns (a resolution column of 0 where
    the bench adds none to the default sensor's)."""
    if noise is None:
        return {}
    return {"pressure_offset": noise.pressure_offset, "position_lag": noise.lag,
            "position_resolution": noise.resolution
            if noise.resolution > Noise().resolution else 0.0,
            "sample_rate": noise.sample_rate}


#: The validation test's setting (``--validation``): ramp pairs, input replicates.
VALIDATION_RAMPS = 6
VALIDATION_REPLICATES = 16


def run_one(job):
    index, seed, truth, args = job
    rng = np.random.default_rng(args.seed * 1000 + index)
    prior = prior_of(truth, rng)
    bench = BenchFamily().sample(np.random.default_rng([args.seed, index, seed])) \
        if args.bench else None
    setting = ({"ramps": VALIDATION_RAMPS}, {"replicates": VALIDATION_REPLICATES}) \
        if args.validation else ({}, {})
    tic = time.perf_counter()
    records = campaign_records(truth, design_campaign(prior, spread=SPREAD,
                                                      **setting[0]).tests, bench, seed)
    result = identify_paper(records, prior, seed=seed, executor=1, **setting[1])
    wall = time.perf_counter() - tic
    rows = rows_of(result, truth, seed, "1", wall, named(bench, result))
    summary = result.summary()
    if args.rounds == 2:  # designed from round 1's result, run on the same bench
        tic = time.perf_counter()
        plan = result.next_round(**setting[0])
        second = campaign_records(truth, plan.tests, bench, seed + SECOND_ROUND_SEED)
        again = identify_paper((records if args.together else []) + second, plan.prior,
                               seed=seed, executor=1, **setting[1])
        rows += rows_of(again, truth, seed, "2", time.perf_counter() - tic,
                        named(bench, again))
        summary += "\n  round 2: " + again.headline()
        if args.keep:
            keep = args.keep / f"{truth.name}-seed{seed}.pickle"
            keep.write_bytes(pickle.dumps({"truth": dict(truth.values),
                                           "rounds": (round_estimates(result, 1),
                                                      round_estimates(again, 2))}))
        if not args.together:  # independent records: the rounds combine
            combined = combine_rounds(result, again)
            rows += rows_of(combined, truth, seed, "1+2", 0.0, named(bench, again))
            summary += "\n  rounds 1+2: " + combined.headline()
    return rows, summary


def campaign_records(truth, tests, bench: Noise | None, seed: int):
    """The ``tests`` run on ``truth``: with the default noise, or as the drawn ``bench``
    logs them (each record's noise seeded on its own)."""
    if bench is None:
        return synthetic_campaign(truth, tests, seed=seed)
    exact = synthetic_campaign(truth, tests, noise=Noise(0.0, 0.0, 0.0))
    return [add_noise([record], bench, seed=seed * 1000 + i)[0]
            for i, record in enumerate(exact)]


#: The noise of a second round's records is drawn with the first's seed plus this.
SECOND_ROUND_SEED = 1000


def rows_of(result, truth, seed: int, round_number: str, wall: float, faults: dict
            ) -> list[dict]:
    """One row per free parameter: verdict, error, interval reported and covering."""
    table = result.to_pandas(truth=truth)
    rows = []
    for name in FREE:
        row = table.loc[name]
        reported = bool(np.isfinite(row["ci95_low"]) and np.isfinite(row["ci95_high"]))
        rows.append({"actuator": truth.name, "seed": seed, "round": round_number,
                     "parameter": name, "verdict": row["verdict"],
                     "error_%": row["error_%"], "reported": reported,
                     "covered": bool(row["truth_in_ci95"]) if reported else None,
                     "wall_s": wall, **faults})
    return rows


def named(bench: Noise | None, result) -> dict:
    """Each drawn fault and whether the result named it (a bench diagnostic)."""
    if bench is None:
        return {}
    said = " ".join(d.message for d in result.diagnostics if d.stage == "bench")
    return {**bench_faults(bench),
            "offset_named": "pressure sensor reads" in said,
            "lag_named": "position sensor lags" in said,
            "quantisation_named": "quantised at" in said,
            "rate_named": "sampled at" in said}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--actuators", type=int, default=40)
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--seed", type=int, default=7, help="seed of the family")
    parser.add_argument("--csv", type=Path, default=None, help="write every row here")
    parser.add_argument("--family", choices=("default", "wide"), default="default",
                        help="wide: ActuatorFamily.wide() (diaphragms of 30-250 mm, "
                             "Fc 0.3-300 N, ...; friction scaled with the size)")
    parser.add_argument("--bench", action="store_true",
                        help="add a drawn bench (offset, lag, resolution, rate) per campaign")
    parser.add_argument("--rounds", type=int, choices=(1, 2), default=1,
                        help="2: a second round per campaign, designed from the first "
                             "round's result (next_round), and both rounds' shares")
    parser.add_argument("--together", action="store_true",
                        help="identify round 2 from both rounds' records (default: from "
                             "the second round's, with the first round's estimates as "
                             "its prior)")
    parser.add_argument("--validation", action="store_true",
                        help="the validation test's setting: one noise seed per actuator "
                             "(its index), 6 ramp pairs, 16 input replicates")
    parser.add_argument("--keep", type=Path, default=None,
                        help="with --rounds 2: pickle each campaign's rounds here")
    parser.add_argument("--recombine", type=Path, default=None,
                        help="combine the rounds kept in this folder (--keep) again")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    if args.recombine:
        return recombine(args)
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
    drawn = ActuatorFamily.wide() if args.family == "wide" else ActuatorFamily()
    family = drawn.draw(args.actuators, seed=args.seed)
    jobs = [(i, i if args.validation else s, truth, args)
            for i, truth in enumerate(family)
            for s in range(1 if args.validation else args.seeds)]
    rows = []
    started = time.perf_counter()
    # Ctrl-C: the identifications stop at their next simulation, no table is written
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool, \
            stop_threads(pool):
        for (_index, seed, truth, *_), (result_rows, summary) in zip(
                jobs, pool.map(run_one, jobs), strict=True):
            rows += result_rows
            errors = " | ".join(
                f"round {n}: " + " ".join(f"{r['parameter']}:{r['error_%']:+.2g}%"
                                          for r in result_rows if r["round"] == n)
                for n in dict.fromkeys(r["round"] for r in result_rows))
            print(f"{truth.name} seed {seed}: {result_rows[0]['wall_s']:.1f} s; {summary}; "
                  f"{errors}", flush=True)
    total = time.perf_counter() - started
    every = pd.DataFrame(rows)
    for round_number in dict.fromkeys(every["round"]):
        print(f"\n--- round {round_number}")
        report(every[every["round"] == round_number], len(family), args, total)
    if args.csv:
        every.to_csv(args.csv, index=False)


def recombine(args) -> None:
    """The rounds kept by ``--keep`` combined with the current rules: the "1+2" table."""
    rows = []
    kept = sorted(args.recombine.glob("*.pickle"))
    for path in kept:
        stored = pickle.loads(path.read_bytes())
        table = combined_table(*stored["rounds"])
        truth = stored["truth"]
        for name in FREE:
            row = table.loc[name]
            reported = bool(np.isfinite(row["ci95_low"]) and np.isfinite(row["ci95_high"]))
            rows.append({"actuator": path.stem, "seed": 0, "round": "1+2", "parameter": name,
                         "verdict": row["verdict"],
                         "error_%": 100 * (row["value"] / truth[name] - 1),
                         "reported": reported, "wall_s": 0.0,
                         "covered": bool(row["ci95_low"] <= truth[name] <= row["ci95_high"])
                         if reported else None})
        print(f"{path.stem}: {sum(table.loc[list(FREE), 'verdict'] == 'identified')} of 8 "
              "identified, rounds " + " ".join(f"{n}:{table.loc[n, 'round']}" for n in FREE))
    print("\n--- rounds 1+2, recombined")
    report(pd.DataFrame(rows), len(kept), args, 0.0)


def report(table: pd.DataFrame, actuators: int, args, total: float) -> None:
    """Per parameter and overall: identified share, errors, coverage, times."""
    identified = table[table["verdict"] == "identified"]
    reported = table[table["reported"]]
    per = pd.DataFrame({
        "identified_%": 100 * table.groupby("parameter")["verdict"].apply(
            lambda v: np.mean(v == "identified")),
        "max_error_identified_%": identified.groupby("parameter")["error_%"].apply(
            lambda e: np.max(np.abs(e))),
        "tolerance_%": pd.Series(TOLERANCE),
        "coverage_reported_%": 100 * reported.groupby("parameter")["covered"].mean(),
    }).reindex(list(FREE))
    print()
    print(per.to_string(float_format=lambda x: f"{x:.3g}"))
    wrong = identified[identified["error_%"].abs() > identified["parameter"].map(TOLERANCE)]
    walls = table.drop_duplicates(["actuator", "seed"])["wall_s"]
    print(f"\n{actuators} actuators, {len(walls)} campaigns: identified "
          f"{100 * len(identified) / len(table):.1f} % of the parameters, "
          f"{len(wrong)} identified but out of tolerance; reported intervals "
          f"{len(reported)}, coverage {100 * reported['covered'].mean():.1f} %; "
          f"wall per identification median {statistics.median(walls):.1f} s, "
          f"max {walls.max():.1f} s; total {total:.0f} s on {os.cpu_count()} cores, "
          f"{time.process_time():.0f} s of CPU (the process, all rounds)")
    if args.bench:
        runs = table.drop_duplicates(["actuator", "seed"])
        for fault, column, present in (
                ("pressure offset above 0.5 kPa", "offset_named",
                 runs["pressure_offset"].abs() > 500),
                ("position lag", "lag_named", runs["position_lag"] > 0),
                ("quantisation", "quantisation_named", runs["position_resolution"] > 0),
                ("sample rate below 1 kHz", "rate_named", runs["sample_rate"] > 0)):
            print(f"{fault}: in {int(present.sum())} campaigns, named in "
                  f"{int(runs.loc[present, column].sum())}; named without it in "
                  f"{int(runs.loc[~present, column].sum())}")


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit("stopped (Ctrl-C): no table written")
