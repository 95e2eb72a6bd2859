"""Speed of a closed-loop step with a digital controller: pneumact against scipy.

Run: python benchmarks/bench_closed_loop.py   (installed package or PYTHONPATH=src)

The vgt-paper actuator behind its command valve (LuGre friction, isothermal chamber)
under a sampled PID (Kp = 200 /m, Ki = 2000 /(m·s), output 0..1, back-calculation,
zero-order hold at 1 kHz) follows a set-point step 4 → 8 mm at 0.1 s; 1 s simulated,
Rodas4 rtol 1e-6. The alternative a user would pick: scipy's ``solve_ivp`` on the *same*
compiled model (the loop kernel's rhs and analytic-plus-coupling Jacobian), which has
to stop at every controller sample: one ``solve_ivp`` call per period, the controller
update (the kernel's own ``jump``) called from Python in between. Both write the same
output grid; the script prints wall times (best of ``--repeats``), the ratio and the
largest position difference.
"""

from __future__ import annotations

import argparse
import itertools
import time
import warnings

import numpy as np
from scipy.integrate import solve_ivp

import pneumact as pa
from pneumact.control import PID, ClosedLoop
from pneumact.experiments import SetpointStep
from pneumact.simulation.simulate import prepare


def build(sample_time: float):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)
        params = pa.load_params("vgt-paper")
    actuator = pa.Actuator(params, pa.LuGre(), valve=pa.CommandValve())
    pid = PID(kp=200.0, ki=2000.0, u_min=0.0, u_max=1.0, sample_time=sample_time)
    bias = ClosedLoop(actuator, pid).holding_input(0.004)
    return ClosedLoop(actuator, pid, bias=bias), SetpointStep(0.004, 0.008, 0.1, 1.0, 1001)


def scipy_run(loop, experiment, solver, method: str):
    """solve_ivp between samples on the compiled loop kernel; returns (wall, position)."""
    prep = prepare(loop, experiment, solver)
    kernel, prm, sig, ptr = prep.kernel, prep.vector, prep.sig.copy(), prep.ptr
    bp, t_out, atol = prep.breakpoints, prep.t_out, prep.atol
    n = kernel.NSTATE
    y = prep.y0.copy()
    positions = [y[0]] if t_out[0] <= bp[0] else []
    start = time.perf_counter()
    for a, b in itertools.pairwise(bp):
        ts = 0.5 * (a + b)
        kernel.jump(a, ts, y, prm, sig, ptr)  # the controller samples and holds
        dydt = np.empty(n)

        def f(t, yy, ts=ts, dydt=dydt):
            kernel.rhs(t, ts, yy, prm, sig, ptr, dydt)
            return dydt.copy()

        def jac(t, yy, ts=ts):
            out = np.zeros((n, n))
            kernel.jac(t, ts, yy, prm, sig, ptr, out)
            return out

        inside = t_out[(t_out > a) & (t_out <= b)]
        sol = solve_ivp(f, (a, b), y, method=method, jac=jac, rtol=solver.rtol, atol=atol,
                        t_eval=np.unique(np.concatenate([inside, [b]])))
        if not sol.success:
            raise RuntimeError(f"{method} failed at t = {a}: {sol.message}")
        positions.extend(sol.y[0][: inside.size])
        y = sol.y[:, -1].copy()
    return time.perf_counter() - start, np.asarray(positions)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sample-time", type=float, default=1e-3)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--methods", default="LSODA,BDF")
    args = parser.parse_args()
    loop, experiment = build(args.sample_time)
    solver = pa.Rodas4(rtol=1e-6)
    result = pa.simulate(loop, experiment, solver)  # warm-up: compile or load
    walls = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        result = pa.simulate(loop, experiment, solver)
        walls.append(time.perf_counter() - start)
    ours = min(walls)
    x = result.signals["position"]
    samples = round(1.0 / args.sample_time)
    print(f"closed-loop step, sampled PID at {1 / args.sample_time:g} Hz ({samples} samples),"
          f" 1 s of the valve-driven vgt actuator")
    print(f"  pneumact (Rodas4, compiled loop):  {ours * 1e3:8.1f} ms  "
          f"({result.meta.get('steps')} steps)")
    for method in args.methods.split(","):
        wall, position = scipy_run(loop, experiment, solver, method)
        diff = np.max(np.abs(position - x))
        print(f"  scipy solve_ivp {method:6s} per sample: {wall * 1e3:8.1f} ms  "
              f"ratio {wall / ours:6.1f}x  max |Δx| {diff * 1e6:.3f} µm")


if __name__ == "__main__":
    main()
