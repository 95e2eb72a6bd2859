"""Benchmark: one slow cycle of ``vgt-paper``, pneumact's compiled Rodas4 against scipy.

Cases (one 20 s triangle cycle, 4001 output points):
  (a) pressure-driven: ``Actuator(params, valve=PressureSource())`` under
      ``PressureCycle(high=100e3, low=20e3, period=20)``; with the paper's delta = 1
      (real stick-slip, thousands of steps) and, labelled, with delta = 2;
  (b) valve-driven with the chamber: ``Actuator(params, valve=CommandValve())`` under
      ``CommandCycle(0, 1, period=20)``.

Methods, all on the same model at the same tolerances (rtol = 1e-6 and pneumact's per-state
atol vector):
  - pneumact ``simulate(..., solver=Rodas4(rtol=1e-6))``, end to end;
  - scipy ``solve_ivp`` (LSODA, Radau) on the *compiled* kernel's ``rhs``/``jac`` wrapped in
    Python functions, restarted at every input breakpoint (a careful user; a strong
    alternative, since the right-hand side itself is compiled);
  - case (a) only, labelled: LSODA on a plain-Python right-hand side and Jacobian.

Accuracy: against a tight reference (pneumact Rodas4, rtol = 1e-11), cross-checked with
scipy Radau (rtol = 1e-11, atol = 1e-3 × pneumact's atol); their mutual difference is
printed. Timing: cold compile and warm-cache load of the kernels in fresh subprocesses
(temporary ``PNEUMACT_CACHE_DIR`` and ``NUMBA_CACHE_DIR``), then the median of repeated
simulations in this process, compilation excluded.

Run (after ``pip install -e .``, or with ``PYTHONPATH=src`` from the repository root):
    python benchmarks/bench_simulate.py            # full run, a few minutes on 2 cores
    python benchmarks/bench_simulate.py --quick    # smoke run, fewer repeats
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

try:
    import pneumact as pa
except ImportError:  # not installed: use the source tree next to this script
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    import pneumact as pa

from pneumact.simulation.simulate import prepare

RTOL = 1e-6
REF_RTOL = 1e-11
REF_ATOL_FACTOR = 1e-3  # scipy reference atol = this × pneumact's atol
MATCH_RTOLS = tuple(10.0 ** -e for e in np.arange(6.5, 10.01, 0.5))  # LSODA, =accuracy row
SLOW_RUN_S = 0.5  # scipy runs slower than this get only the slow repeat count
TARGET_SPEEDUP = 20.0  # issue target: pneumact vs LSODA, valve-driven case

CASE_SETUP = {
    "a": ("PressureSource", "PressureCycle(high=100e3, low=20e3, period=20)"),
    "b": ("CommandValve", "CommandCycle(0, 1, period=20)"),
}


@dataclass
class Case:
    label: str
    actuator: object
    experiment: object
    has_pressure_state: bool


def make_cases() -> list[Case]:
    params = pa.load_params("vgt-paper")
    cycle_a = pa.PressureCycle(high=100e3, low=20e3, period=20)
    return [
        Case("a  pressure, delta=1", pa.Actuator(params, valve=pa.PressureSource()), cycle_a,
             False),
        Case("a' pressure, delta=2", pa.Actuator(params.replace(delta=2.0),
                                                 valve=pa.PressureSource()), cycle_a, False),
        Case("b  valve+chamber", pa.Actuator(params, valve=pa.CommandValve()),
             pa.CommandCycle(0, 1, period=20), True),
    ]


# ------------------------------------------------------------------------------ runners
def run_pneumact(case: Case, rtol: float = RTOL):
    """(position, pressure state or None, steps) from one pneumact simulation."""
    result = pa.simulate(case.actuator, case.experiment, solver=pa.Rodas4(rtol=rtol))
    pressure = result["pressure"] if case.has_pressure_state else None
    return result["position"], pressure, result.meta["steps"], \
        result.meta["rhs_evaluations"], result.meta["jacobian_evaluations"]


def integrate_by_intervals(fun_for, jac_for, bp, t_out, y0, method, rtol, atol):
    """solve_ivp restarted at every breakpoint, states written at the output times.

    ``fun_for(ts)`` / ``jac_for(ts)`` give the right-hand side / Jacobian of the interval
    whose midpoint is ``ts``. Returns (states at t_out, nfev, njev).
    """
    y = np.array(y0, dtype=float)
    y_out = np.empty((t_out.size, y.size))
    j = int(np.searchsorted(t_out, bp[0], side="right"))
    y_out[:j] = y
    nfev = njev = 0
    for lo, hi in itertools.pairwise(bp):
        ts = 0.5 * (lo + hi)
        k = int(np.searchsorted(t_out, hi, side="right"))
        t_eval = t_out[j:k]
        if t_eval.size == 0 or t_eval[-1] < hi:
            t_eval = np.append(t_eval, hi)  # always get the state at the breakpoint
        sol = solve_ivp(fun_for(ts), (lo, hi), y, method=method, t_eval=t_eval, rtol=rtol,
                        atol=atol, jac=jac_for(ts))
        if sol.status != 0:
            raise RuntimeError(f"solve_ivp {method} failed on [{lo}, {hi}]: {sol.message}")
        y_out[j:k] = sol.y[:, : k - j].T
        y = sol.y[:, -1].copy()
        nfev += sol.nfev
        njev += sol.njev
        j = k
    return y_out, nfev, njev


def compiled_wrappers(kernel, prm, sig, ptr):
    """Python closures around the compiled kernel's rhs and jac, per interval."""
    n = kernel.NSTATE

    def fun_for(ts):
        def fun(t, y):
            dydt = np.empty(n)
            kernel.rhs(t, ts, y, prm, sig, ptr, dydt)
            return dydt
        return fun

    def jac_for(ts):
        def jac(t, y):
            out = np.zeros((n, n))
            kernel.jac(t, ts, y, prm, sig, ptr, out)
            return out
        return jac

    return fun_for, jac_for


def _prepared(case: Case):
    """(kernel, vector, sig, ptr, breakpoints, output times, y0, atol) of a case."""
    prep = prepare(case.actuator, case.experiment, pa.Rodas4(rtol=RTOL))
    return (prep.kernel, prep.vector, prep.sig, prep.ptr, prep.breakpoints, prep.t_out,
            prep.y0, prep.atol, prep.assembly)


def run_scipy(case: Case, method: str, rtol: float = RTOL, atol_factor: float = 1.0):
    kernel, prm, sig, ptr, bp, t_out, y0, atol, _ = _prepared(case)
    fun_for, jac_for = compiled_wrappers(kernel, prm, sig, ptr)
    y_out, nfev, njev = integrate_by_intervals(fun_for, jac_for, bp, t_out, y0, method, rtol,
                                               atol * atol_factor)
    return y_out[:, 0], (y_out[:, 3] if case.has_pressure_state else None), None, nfev, njev


def python_lugre_model(values, drive, bp):
    """Plain-Python rhs and Jacobian of the pressure-driven LuGre actuator (case a)."""
    m, f0, k, ad, patm, xmax, ks, cs, s0, s1, s2, fc, fs, vs, delta = (
        values[name] for name in ("m", "F0", "k", "A_d", "p_atm", "x_max", "k_stop",
                                  "c_stop", "sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs",
                                  "delta"))
    p_at = dict(zip(bp, np.asarray(drive(bp), dtype=float), strict=True))
    half = {0.5 * (a + b): (a, b) for a, b in itertools.pairwise(bp)}

    def parts(t, ts, y):
        x, v, z = y
        a, b = half[ts]
        p = p_at[a] + (p_at[b] - p_at[a]) * (t - a) / (b - a)  # linear between breakpoints
        r = abs(v) / vs
        e = math.exp(-(r**delta)) if r > 0 else 1.0
        g = fc + (fs - fc) * e
        dg = -(fs - fc) * e * delta * r ** (delta - 1) * math.copysign(1, v) / vs if r else 0.0
        zdot = v - s0 * abs(v) * z / g
        fstop, dsx, dsv = 0.0, 0.0, 0.0  # Hunt-Crossley stops: pen·(ks + cs·pen_rate) >= 0
        if x < 0 and -x * (ks - cs * v) > 0:
            fstop, dsx, dsv = -x * (ks - cs * v), -(ks - cs * v), x * cs
        elif x > xmax and (x - xmax) * (ks + cs * v) > 0:
            pen = x - xmax
            fstop, dsx, dsv = -pen * (ks + cs * v), -(ks + cs * v), -cs * pen
        net = (patm - p) * ad - (f0 + k * x) - (s0 * z + s1 * zdot + s2 * v) + fstop
        return v, z, g, dg, zdot, net, dsx, dsv

    def fun_for(ts):
        def fun(t, y):
            v, _, _, _, zdot, net, _, _ = parts(t, ts, y)
            return np.array([v, net / m, zdot])
        return fun

    def jac_for(ts):
        def jac(t, y):
            v, z, g, dg, _, _, dsx, dsv = parts(t, ts, y)
            dzv = 1.0 - s0 * z * (math.copysign(1, v) * (v != 0) * g - abs(v) * dg) / (g * g)
            dzz = -s0 * abs(v) / g
            return np.array([[0.0, 1.0, 0.0],
                             [(-k + dsx) / m, (-(s1 * dzv + s2) + dsv) / m, -(s0 + s1 * dzz) / m],
                             [0.0, dzv, dzz]])
        return jac

    return fun_for, jac_for


def run_python_lsoda(case: Case):
    _, prm, _, _, bp, t_out, y0, atol, assembly = _prepared(case)
    fun_for, jac_for = python_lugre_model(assembly.values(prm), case.experiment.drive, bp)
    y_out, nfev, njev = integrate_by_intervals(fun_for, jac_for, bp, t_out, y0, "LSODA", RTOL,
                                               atol)
    return y_out[:, 0], None, None, nfev, njev


def check_python_model(case: Case) -> float:
    """Max relative difference of the Python rhs/jac from the compiled ones at sample states."""
    kernel, prm, sig, ptr, bp, _, _, _, assembly = _prepared(case)
    fun_for, jac_for = python_lugre_model(assembly.values(prm), case.experiment.drive, bp)
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(200):
        seg = rng.integers(bp.size - 1)
        ts = 0.5 * (bp[seg] + bp[seg + 1])
        t = rng.uniform(bp[seg], bp[seg + 1])
        y = np.array([rng.uniform(-1e-4, 0.021), rng.normal(0, 2e-3) * rng.integers(2),
                      rng.uniform(-3.2e-5, 3.2e-5)])
        f_c = np.empty(3)
        j_c = np.zeros((3, 3))
        kernel.rhs(t, ts, y, prm, sig, ptr, f_c)
        kernel.jac(t, ts, y, prm, sig, ptr, j_c)
        for mine, theirs in ((fun_for(ts)(t, y), f_c), (jac_for(ts)(t, y), j_c)):
            worst = max(worst, float(np.max(np.abs(mine - theirs) /
                                            (np.abs(theirs) + 1e-12 * np.max(np.abs(theirs))))))
    return worst


# ------------------------------------------------------------------------------- timing
def median_time(fn, repeats: int) -> tuple[float, object]:
    times = []
    out = None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


CHILD = r"""
import json, sys, time, warnings
t0 = time.perf_counter()
warnings.simplefilter("ignore")
import pneumact as pa
t1 = time.perf_counter()
out = {"import_s": t1 - t0}
params = pa.load_params("vgt-paper")
for key, valve, experiment in (
        ("a", pa.PressureSource(), pa.PressureCycle(high=100e3, low=20e3, period=20)),
        ("b", pa.CommandValve(), pa.CommandCycle(0, 1, period=20))):
    actuator = pa.Actuator(params, valve=valve)
    ta = time.perf_counter()
    pa.simulate(actuator, experiment, solver=pa.Rodas4(rtol=1e-6))
    tb = time.perf_counter()
    pa.simulate(actuator, experiment, solver=pa.Rodas4(rtol=1e-6))
    tc = time.perf_counter()
    out[key] = [tb - ta, tc - tb]
print(json.dumps(out))
"""


def compile_times() -> dict[str, dict]:
    """Cold compile and warm-cache load, each in a fresh subprocess."""
    src = str(Path(pa.__file__).resolve().parents[1])
    results = {}
    with tempfile.TemporaryDirectory(prefix="pneumact-bench-") as tmp:
        env = dict(os.environ, PNEUMACT_CACHE_DIR=str(Path(tmp) / "kernels"),
                   NUMBA_CACHE_DIR=str(Path(tmp) / "numba"),
                   PYTHONPATH=os.pathsep.join(
                       [src, *filter(None, [os.environ.get("PYTHONPATH")])]))
        for label in ("cold", "warm"):
            proc = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True,
                                  text=True, check=False)
            if proc.returncode != 0:
                results[label] = {"error": proc.stderr.strip().splitlines()[-1:]}
                continue
            results[label] = json.loads(proc.stdout.strip().splitlines()[-1])
    return results


# ------------------------------------------------------------------------------- report
def max_err(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


def fmt(value, spec: str) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) \
        else format(value, spec)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repeats (smoke run)")
    parser.add_argument("--no-compile", action="store_true",
                        help="skip the cold/warm compile subprocesses")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", pa.PassivityWarning)
    reps_fast, reps_slow = (3, 1) if args.quick else (9, 3)

    print(f"pneumact {pa.__version__} from {Path(pa.__file__).resolve().parent}")
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, "
          f"scipy {__import__('scipy').__version__}, numba {__import__('numba').__version__}, "
          f"{os.cpu_count()} cpu(s)")
    print(f"rtol = {RTOL:g}, atol = pneumact's per-state vector (rtol × state scale); "
          f"repeats: pneumact {reps_fast}, scipy {reps_slow} (median)\n")

    if not args.no_compile:
        print("Compilation (fresh subprocesses, temporary PNEUMACT_CACHE_DIR + NUMBA_CACHE_DIR)")
        ct = compile_times()
        for label in ("cold", "warm"):
            r = ct.get(label, {})
            if "error" in r:
                print(f"  {label}: failed: {r['error']}")
                continue
            print(f"  {label}: import pneumact {r['import_s']:.2f} s; "
                  + "; ".join(f"case {k} ({CASE_SETUP[k][0]}): first simulate "
                              f"{r[k][0]:.2f} s, second {1e3 * r[k][1]:.1f} ms" for k in "ab"))
        print()

    rows = []
    for case in make_cases():
        t_case = time.perf_counter()
        kernel = _prepared(case)[0]
        run_pneumact(case)  # warm-up (loads/compiles the kernel, numba dispatch)
        ref_x, ref_p, ref_steps, _, _ = run_pneumact(case, REF_RTOL)
        rad_x, rad_p, _, _, _ = run_scipy(case, "Radau", REF_RTOL, REF_ATOL_FACTOR)
        name = getattr(kernel, "__name__", type(kernel).__name__)  # a C library has none
        print(f"[{case.label}] kernel {name}; reference Rodas4 rtol={REF_RTOL:g} "
              f"({ref_steps} steps) vs Radau rtol={REF_RTOL:g}, atol={REF_ATOL_FACTOR:g}×: "
              f"max |dx| = {1e6 * max_err(ref_x, rad_x):.3g} µm"
              + (f", max |dp| = {max_err(ref_p, rad_p):.3g} Pa" if ref_p is not None else ""))
        methods = [("pneumact Rodas4", lambda c=case: run_pneumact(c), reps_fast),
                   ("scipy LSODA (compiled rhs)", lambda c=case: run_scipy(c, "LSODA"),
                    reps_slow),
                   ("scipy Radau (compiled rhs)", lambda c=case: run_scipy(c, "Radau"),
                    reps_slow)]
        if not case.has_pressure_state:
            methods.append(("scipy LSODA (Python rhs+jac)",
                            lambda c=case: run_python_lsoda(c), reps_slow))
            print(f"    Python rhs/jac vs compiled: max relative difference "
                  f"{check_python_model(case):.2g} at 200 random states")
        base = None
        for name, fn, reps in methods:
            start = time.perf_counter()
            fn()  # warm-up: numba dispatch, scipy imports
            if time.perf_counter() - start < SLOW_RUN_S:
                reps = max(reps, reps_fast)
            seconds, (x, p, steps, nfev, njev) = median_time(fn, reps)
            errors = (1e6 * max_err(x, ref_x), max_err(p, ref_p) if p is not None else None)
            if base is None:
                base, base_errors = seconds, errors
                kernel_ms = 1e3 * statistics.median(
                    pa.simulate(case.actuator, case.experiment, solver=pa.Rodas4(rtol=RTOL))
                    .meta["wall_time_s"] for _ in range(reps))
            rows.append((case.label, name, 1e3 * seconds, steps, nfev, njev, *errors,
                         seconds / base))
        # LSODA tightened until it is at least as accurate as pneumact at rtol = 1e-6
        for rtol in MATCH_RTOLS:
            x, p, _, nfev, njev = run_scipy(case, "LSODA", rtol, rtol / RTOL)
            errors = (1e6 * max_err(x, ref_x), max_err(p, ref_p) if p is not None else None)
            if all(e is None or e <= b for e, b in zip(errors, base_errors, strict=True)):
                seconds, _ = median_time(lambda c=case, r=rtol: run_scipy(c, "LSODA", r,
                                                                           r / RTOL),
                                         reps_slow)
                rows.append((case.label, f"scipy LSODA rtol={rtol:.2g} (=acc.)",
                             1e3 * seconds, None, nfev, njev, *errors, seconds / base))
                break
        else:
            print(f"    LSODA did not reach pneumact's accuracy down to rtol={MATCH_RTOLS[-1]:g}")
        print(f"    pneumact kernel alone (meta wall_time_s, median): {kernel_ms:.1f} ms of "
              f"{1e3 * base:.1f} ms end to end")
        print(f"    case done in {time.perf_counter() - t_case:.1f} s")

    header = (f"{'case':<22} {'method':<32} {'median ms':>10} {'steps':>7} {'f-evals':>8} "
              f"{'J-evals':>8} {'max|dx| µm':>11} {'max|dp| Pa':>11} {'t/t_pneumact':>12}")
    print("\n" + header + "\n" + "-" * len(header))
    for label, name, ms, steps, nfev, njev, ex, ep, ratio in rows:
        print(f"{label:<22} {name:<32} {ms:>10.1f} {fmt(steps, 'd'):>7} {nfev:>8d} "
              f"{njev:>8d} {ex:>11.3g} {fmt(ep, '.3g'):>11} {ratio:>12.1f}")
    print("(steps: accepted steps reported by pneumact; solve_ivp does not report them. "
          "Errors: max abs over the 4001 output points against the Rodas4 rtol=1e-11 "
          "reference.)")

    case_b = [r for r in rows if r[0] == "b  valve+chamber"]
    pn = case_b[0]
    same_tol = next(r for r in case_b if r[1] == "scipy LSODA (compiled rhs)")
    same_acc = next((r for r in case_b if r[1].endswith("(=acc.)")), None)
    print(f"\nTarget (valve-driven case b: pneumact >= {TARGET_SPEEDUP:g}x faster than LSODA at "
          f"equal or better accuracy):")
    print(f"  same tolerances (rtol=1e-6): {same_tol[8]:.1f}x, pneumact errors "
          f"{pn[6]:.3g} µm / {pn[7]:.3g} Pa vs LSODA {same_tol[6]:.3g} µm / "
          f"{same_tol[7]:.3g} Pa")
    if same_acc is not None:
        print(f"  same accuracy ({same_acc[1]}): {same_acc[8]:.1f}x")
    as_accurate = pn[6] <= same_tol[6] and pn[7] <= same_tol[7]
    met = as_accurate and same_tol[8] >= TARGET_SPEEDUP
    print(f"  -> {'MET' if met else 'NOT MET'} at equal tolerances"
          + ("" if as_accurate else " (pneumact less accurate than LSODA here)")
          + (f"; {'MET' if same_acc[8] >= TARGET_SPEEDUP else 'NOT MET'} at equal accuracy"
             if same_acc is not None else ""))

if __name__ == "__main__":
    main()
