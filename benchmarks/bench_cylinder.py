"""Benchmark: the double-acting cylinder's step response (issue 41, item 7), warm.

Cases (``iso15552-32``, LuGre, isothermal chambers, Rodas4 at rtol 1e-6, 2001 output
points over 2 s):
  (loop step)   the position loop (kp 100 1/m, kd 0.5 s/m, kdp 3e-6 1/Pa on the
                chambers' pressure difference, spool limited to ±1) with the piston placed
                at 90 mm (``y0``: it rests wherever its chambers balance) and held there, a
                20 mm set-point step at 1 s, 2 s in all: the issue's "20 mm, 2 s";
  (loop 1 Hz)   the same loop following a 20 mm square wave at 1 Hz (90 -> 110 -> 90 mm,
                steps every 0.5 s, 2 s): the other reading of "20 mm at 1 Hz";
  (spool step)  open loop: the spool stepped from -1 to 0.5 at 0.1 s, the piston across
                its 200 mm stroke into the end stop, 2 s;
  (actuator b)  with ``--case-b``: ``bench_simulate.py``'s case (b), the valve-driven
                diaphragm actuator under ``CommandCycle(0, 1, period=20)``.

Each case runs once on each engine (numba, C) to compile or load its kernel, then
``--repeats`` times; the figure is the CPU time (``time.process_time``: user + system of
this process; the integrator runs on one thread) of one ``pa.simulate`` call, median and
minimum over the repeats. CPU time, not wall time: other processes on a shared machine
stretch the wall clock but not this process's CPU time.

Run (with ``PYTHONPATH=src`` from the repository root, or after ``pip install -e .``):
    python benchmarks/bench_cylinder.py [--repeats 20] [--engines numba,c] [--case-b]
    python benchmarks/bench_cylinder.py --case-b --only actuator   # case (b) alone
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

from pneumact.control import PID, ClosedLoop
from pneumact.experiments import SetpointProfile, SetpointStep, SpoolStep

START, STEP = 0.09, 0.02  # m
T_END = 2.0  # s
N_POINTS = 2001
RTOL = 1e-6


def _loop():
    """The cylinder's state feedback with pressure feedback, holding START at t = 0."""
    cylinder = pa.Cylinder(pa.load_params("iso15552-32"))
    controller = PID(kp=100.0, kd=0.5, kdp=3e-6, derivative="velocity", u_min=-1.0,
                     u_max=1.0)
    bias = ClosedLoop(cylinder, controller).holding_input(START)
    return ClosedLoop(cylinder, controller, bias=bias)


def _square_wave():
    """START -> START + STEP -> START ... every half period of 1 Hz, over T_END."""
    edges = [0.5 * k for k in range(1, int(T_END / 0.5))]
    times, levels, level = [0.0], [START], START
    for edge in edges:
        times += [edge, edge]
        levels += [level, START + STEP if level == START else START]
        level = levels[-1]
    times.append(T_END)
    levels.append(level)
    return SetpointProfile(times, levels, name="20 mm square wave at 1 Hz",
                           n_points=N_POINTS)


def cases(case_b: bool) -> dict[str, tuple[object, object, dict | None]]:
    """name -> (model, experiment, initial states by name or None)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the shipped sets' passivity warning
        loop, at_start = _loop(), {"position": START}
        chosen: dict[str, tuple[object, object, dict | None]] = {
            "loop step (20 mm at 1 s, 2 s)": (loop, SetpointStep(
                START, START + STEP, t_step=1.0, t_end=T_END, n_points=N_POINTS), at_start),
            "loop 1 Hz (20 mm square wave, 2 s)": (loop, _square_wave(), at_start),
            "spool step (-1 -> 0.5 at 0.1 s, 2 s)": (
                pa.Cylinder(pa.load_params("iso15552-32")),
                SpoolStep(-1.0, 0.5, t_step=0.1, t_end=T_END, n_points=N_POINTS), None),
        }
        if case_b:
            chosen["actuator b (CommandValve, 20 s cycle)"] = (
                pa.Actuator(pa.load_params("vgt-paper"), valve=pa.CommandValve()),
                pa.CommandCycle(0, 1, period=20), None)
    return chosen


def cpu_times(model, experiment, y0, engine: str, repeats: int) -> tuple[list[float], dict]:
    """CPU seconds of each of ``repeats`` warm runs, and the last run's meta."""
    solver = pa.Rodas4(rtol=RTOL)
    result = pa.simulate(model, experiment, solver, y0=y0, engine=engine)  # compile or load
    times = []
    for _ in range(repeats):
        start = time.process_time()
        result = pa.simulate(model, experiment, solver, y0=y0, engine=engine)
        times.append(time.process_time() - start)
    return times, result.meta


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20, help="warm runs per case")
    parser.add_argument("--engines", default="numba,c", help="comma-separated engines")
    parser.add_argument("--case-b", action="store_true",
                        help="also bench_simulate.py's case (b), the actuator")
    parser.add_argument("--only", default="",
                        help="run only the cases whose name contains this text")
    args = parser.parse_args(argv)
    print(f"pneumact {pa.__version__} from {Path(pa.__file__).parent}")
    print(f"CPU time per warm run (process_time), {args.repeats} repeats; rtol {RTOL:g}")
    print(f"{'case':42s} {'engine':6s} {'median ms':>10s} {'min ms':>8s} {'steps':>6s} "
          f"{'rhs':>6s}")
    for name, (model, experiment, y0) in cases(args.case_b).items():
        if args.only not in name:
            continue
        for engine in args.engines.split(","):
            times, meta = cpu_times(model, experiment, y0, engine, args.repeats)
            print(f"{name:42s} {meta['engine']:6s} {1e3 * statistics.median(times):10.3f} "
                  f"{1e3 * min(times):8.3f} {meta['steps']:6d} "
                  f"{meta['rhs_evaluations']:6d}", flush=True)


if __name__ == "__main__":
    main()
