"""Cost of forward sensitivities against one plain run.

Run: python benchmarks/bench_sensitivities.py   (installed package or PYTHONPATH=src)
Prints median wall times (compilation excluded) and the ratio, for the valve-driven and
the pressure-driven vgt-paper slow cycle: the state sensitivities of the six LuGre
parameters integrated with the state (issue #7 target: at most 3x one run), the same
plus every derived output's sensitivity (computed on first access), the sensitivities of
every parameter of the model, and for comparison central finite differences (the
alternative a user would pick: 2 extra runs per parameter).
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings

import pneumact as pa
from pneumact.simulation import assemble, simulate_sensitivities

PARAMETERS = ["sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs"]


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up (compilation or cache load)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    warnings.simplefilter("ignore", pa.PassivityWarning)
    params = pa.load_params("vgt-paper")
    cases = [
        ("valve-driven (CommandValve, CommandCycle 20 s)",
         pa.Actuator(params, valve=pa.CommandValve()), pa.CommandCycle(period=20.0)),
        ("pressure-driven (PressureSource, PressureCycle 20 s)",
         pa.Actuator(params), pa.PressureCycle(period=20.0)),
    ]
    solver = pa.Rodas4(rtol=1e-6)
    print(f"{'case':55s} {'plain [ms]':>11s} {'sens 6p [ms]':>13s} {'ratio':>6s} "
          f"{'+outputs [ms]':>14s} {'ratio':>6s} {'all N params':>13s} {'ratio':>6s} "
          f"{'FD, runs/plain':>15s}")
    for label, actuator, experiment in cases:
        def plain_run(actuator=actuator, experiment=experiment):
            return pa.simulate(actuator, experiment, solver)

        def sens_run(actuator=actuator, experiment=experiment):
            return simulate_sensitivities(actuator, experiment, PARAMETERS, solver)

        def sens_all_run(actuator=actuator, experiment=experiment):
            sens = simulate_sensitivities(actuator, experiment, PARAMETERS, solver)
            return [sens[name] for name in sens.signals]

        names = list(assemble(actuator).parameter_names)

        def every_run(actuator=actuator, experiment=experiment, names=names):
            return simulate_sensitivities(actuator, experiment, names, solver)

        plain = median_time(plain_run, args.repeats)
        sens = median_time(sens_run, args.repeats)
        sens_all = median_time(sens_all_run, args.repeats)
        every = median_time(every_run, args.repeats)
        print(f"{label:55s} {plain * 1e3:11.2f} {sens * 1e3:13.2f} {sens / plain:6.2f} "
              f"{sens_all * 1e3:14.2f} {sens_all / plain:6.2f} "
              f"{every * 1e3:9.2f} ({len(names):2d}) {every / plain:6.2f} "
              f"{2.0 * len(PARAMETERS):6.0f}/{2.0 * len(names):.0f}")


if __name__ == "__main__":
    main()
