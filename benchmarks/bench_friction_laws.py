"""Benchmark: what a friction law costs per run, against LuGre on the same experiment.

Experiments (the same for every law; each law's shipped or matched parameters):
  (a) the vgt-paper actuator behind its command valve, one 20 s command cycle 0 → 1 → 0
      (``CommandCycle``; the benchmark of ``bench_simulate.py``, case b), with
      ``vgt-paper-gms4`` for the GMS blocks;
  (b) the same actuator under the pressure cycle 100 → 20 → 100 kPa (case a's stick-slip);
  (c) the 1995 friction rig's stick-slip (spring pulled at 0.1 m/s, 40 s), with
      ``canudas1995-gms4`` / ``canudas1995-elastoplastic``.

Each law is timed warm (its kernel compiled first, then the median of ``--repeats``
runs in this process, compilation excluded) at the solver's default tolerances; the
table gives the wall time per run, the solver's steps, and the ratio to LuGre. The
issue's budget for GMS with 4 blocks is 3× LuGre.

Run (after ``pip install -e .``, or with ``PYTHONPATH=src``):
    python benchmarks/bench_friction_laws.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

try:
    import pneumact as pa
except ImportError:  # not installed: use the source tree next to this script
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    import pneumact as pa

from pneumact.analysis.friction_tests import run_friction_test, solver_for
from pneumact.experiments.friction import StickSlip

LAWS = {"LuGre": pa.LuGre(), "elasto-plastic": pa.ElastoPlastic(), "GMS-4": pa.GMS(4),
        "GMS-8": pa.GMS(8)}


def _median_time(run, repeats: int) -> tuple[float, object]:
    result = run()  # compiles (or loads) the kernel
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def _actuator_case(params, valve, experiment):
    def case(law):
        model = pa.Actuator(params, friction=law, valve=valve)
        return lambda: pa.simulate(model, experiment)
    return case


def _rig_case(params):
    def case(law):
        test = StickSlip(t_end=40.0)
        return lambda: run_friction_test(test, params, friction=law,
                                         solver=solver_for(test, params, law)).result
    return case


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    actuator = pa.load_params("vgt-paper-gms4")
    actuator = actuator.replace(pa.GMS(8).matched_values(actuator))  # GMS-8: matched blocks
    rig = pa.load_params("canudas1995-elastoplastic")
    rig = rig.replace({**pa.GMS(8).matched_values(rig),
                       **{n: pa.load_params("canudas1995-gms4")[n]
                          for n in pa.GMS(4).block.parameters if n.startswith("gms_")}})
    cases = {
        "(a) command-valve cycle": _actuator_case(actuator, pa.CommandValve(),
                                                  pa.CommandCycle(0.0, 1.0, period=20.0)),
        "(b) pressure cycle": _actuator_case(actuator, pa.PressureSource(),
                                             pa.PressureCycle(high=100e3, low=20e3,
                                                              period=20.0)),
        "(c) rig stick-slip": _rig_case(rig),
    }
    print(f"{'case':26s} {'law':15s} {'ms/run':>9s} {'steps':>7s} {'× LuGre':>8s}")
    for label, case in cases.items():
        base = None
        for name, law in LAWS.items():
            seconds, result = _median_time(case(law), args.repeats)
            base = seconds if base is None else base
            steps = result.meta.get("steps", "")  # type: ignore[attr-defined]
            print(f"{label:26s} {name:15s} {1e3 * seconds:9.2f} {steps:>7} "
                  f"{seconds / base:8.2f}")


if __name__ == "__main__":
    main()
