"""Benchmark: the exported FMU against pneumact on the same run, and what an export costs.

For each valve (the vgt-paper actuator with LuGre; GMS-4 behind the source as well):
  - the export (``pa.export_fmu``: translation of the kernel to C, the C compiler, the
    archive), its kernel already compiled in this process;
  - one 20 s cycle (``PressureCycle``, ``CommandCycle`` for the command valve) simulated by
    FMPy (CVode, BDF, relative tolerance 1e-6, 4000 output intervals) and by
    ``pa.simulate`` (Rodas4, rtol 1e-6), each warm, the median of ``--repeats`` runs;
  - the agreement: position RMS [% of stroke] and loop width [%].

The Co-Simulation FMU (``kind="cs"``: pneumact's RODAS4 translated to C inside), per case:
  - one 20 s cycle at a 1 ms communication step driven from FMPy (its ``FMU2Slave``, the
    input set before each step as FMPy's ``simulate_fmu`` does): the time spent inside the
    FMU's functions (doStep, setReal, getReal; ctypes' call included) and FMPy's own
    overhead apart (the rest of that loop), and ``fmpy.simulate_fmu``'s whole run;
  - the C integrator alone (the FMU's model.c built here, one call over the same held-input
    run) against the numba kernel (``integrate_rodas4``) on the same arrays;
  - the agreement with ``pa.simulate`` of the same held (staircase) input: position RMS
    [% of the travel].

Run (after ``pip install -e ".[fmu]"``, with a C compiler):
    python benchmarks/bench_fmu.py [--repeats 5] [--cs-only]
"""

from __future__ import annotations

import argparse
import ctypes
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
import zipfile
from pathlib import Path

import numpy as np

try:
    import pneumact as pa
except ImportError:  # not installed: use the source tree next to this script
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    import pneumact as pa

import fmpy

from pneumact.core.c_source import Arena, c_array
from pneumact.core.features import loop_width_pressure
from pneumact.core.signals import PiecewiseLinear
from pneumact.simulation.simulate import prepare
from pneumact.simulation.solvers import Rodas4

#: the CS FMU's communication step [s]
CS_STEP = 1e-3

CASES = {"source": (pa.PressureSource, pa.LuGre()), "command": (pa.CommandValve, pa.LuGre()),
         "regulator": (pa.PressureRegulator, pa.LuGre()),
         "source, GMS-4": (pa.PressureSource, pa.GMS(4))}


def timed(call, repeats: int) -> tuple[float, object]:
    times, value = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        value = call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), value


def fmu_run(path: str, fmu, experiment):
    name = fmu.names("input")[0]
    times = np.array([0.0, experiment.t_end / 2, experiment.t_end])
    drive = np.array([experiment.drive(t) for t in times])
    table = np.array(list(zip(times, drive, 0 * drive, strict=True)),
                     dtype=[("time", float), (name, float), ("external_force", float)])
    return fmpy.simulate_fmu(path, stop_time=experiment.t_end, input=table,
                             start_values={name: float(drive[0])}, relative_tolerance=1e-6,
                             output_interval=experiment.t_end / 4000,
                             output=["position", "pressure"])


def case(label: str, repeats: int, folder: Path) -> dict:
    valve, friction = CASES[label]
    name = "vgt-paper-gms4" if isinstance(friction, pa.GMS) else "vgt-paper"
    model = pa.Actuator(pa.load_params(name), friction=friction, valve=valve())
    experiment = pa.CommandCycle() if valve is pa.CommandValve else pa.PressureCycle()
    run = pa.simulate(model, experiment)  # compiles the kernel
    path = folder / f"{label.replace(', ', '_')}.fmu"
    pa.export_fmu(model, path)  # compiles what the export needs
    export_s, fmu = timed(lambda: pa.export_fmu(model, path), 1)
    fmu_s, out = timed(lambda: fmu_run(str(path), fmu, experiment), repeats)
    pa_s, run = timed(lambda: pa.simulate(model, experiment), repeats)
    x_fmu = np.interp(run.time, out["time"], out["position"])
    p_fmu = np.interp(run.time, out["time"], out["pressure"])
    width = loop_width_pressure(run["pressure"], run["position"])
    return {"case": label, "export [s]": export_s, "FMPy run [s]": fmu_s,
            "pa.simulate [s]": pa_s, "FMPy / pneumact": fmu_s / pa_s,
            "position RMS [% stroke]": 100 * np.sqrt(np.mean((x_fmu - run["position"]) ** 2))
            / float(model.params["x_max"]),
            "loop width [%]": 100 * (loop_width_pressure(p_fmu, x_fmu) / width - 1)}


# ------------------------------------------------------------------------- Co-Simulation
def held_input(experiment, step: float):
    """The communication points, the drive held over each step, and pa.simulate's
    experiment of that same staircase input."""
    grid = np.linspace(0.0, experiment.t_end, round(experiment.t_end / step) + 1)
    drive = np.array([experiment.drive(t) for t in grid])
    times = np.concatenate([[grid[0]], np.repeat(grid[1:-1], 2), [grid[-1]]])
    stairs = pa.Experiment(PiecewiseLinear(times, np.repeat(drive[:-1], 2)),
                           experiment.quantity, experiment.t_end, n_points=grid.size)
    return grid, drive, stairs


def fmpy_cs_loop(path: str, fmu, grid, drive) -> tuple[float, float, np.ndarray]:
    """One run through FMPy's FMU2Slave, as simulate_fmu drives a CS FMU (set the input,
    doStep, get the outputs): (seconds inside the FMU's functions, seconds of the whole
    loop, positions)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    description = read_model_description(path)
    refs = {v.name: v.valueReference for v in description.modelVariables}
    folder = extract(path)
    slave = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                      modelIdentifier=fmu.identifier, instanceName="bench")
    drive_ref = [refs[fmu.names("input")[0]]]
    position_ref = [refs["position"]]
    clock = time.perf_counter
    positions = np.empty(grid.size)
    start = clock()
    inside = 0.0
    t0 = clock()
    slave.instantiate()
    slave.setReal(drive_ref, [float(drive[0])])
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    positions[0] = slave.getReal(position_ref)[0]
    inside += clock() - t0
    for k in range(grid.size - 1):
        value = [float(drive[k])]
        t0 = clock()
        slave.setReal(drive_ref, value)
        slave.doStep(grid[k], grid[k + 1] - grid[k])
        x = slave.getReal(position_ref)
        inside += clock() - t0
        positions[k + 1] = x[0]
    total = clock() - start
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(folder, ignore_errors=True)
    return inside, total, positions


#: a C program that runs a CS FMU's binary as FMPy's loop does (set the input, doStep, get
#: the position), with no Python between the calls: the time spent inside the FMU
DRIVER = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                   fmi2String m, ...) {
    (void)e; (void)n; (void)s; (void)c;
    fprintf(stderr, "%s\\n", m);
}

#define LOAD(name) name##TYPE *name = (name##TYPE *)dlsym(lib, #name)

int main(int argc, char **argv) {
    /* argv: library, guid, input vr, position vr, step, n steps, repeats, input values file */
    void *lib = dlopen(argv[1], RTLD_NOW);
    fmi2ValueReference in = (fmi2ValueReference)atoi(argv[3]);
    fmi2ValueReference out = (fmi2ValueReference)atoi(argv[4]);
    double step = atof(argv[5]), best = 1e300, best_cpu = 1e300, x = 0.0;
    int n = atoi(argv[6]), repeats = atoi(argv[7]), r, k;
    double *u = (double *)malloc((size_t)(n + 1) * sizeof(double));
    FILE *f = fopen(argv[8], "rb");
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    LOAD(fmi2Instantiate); LOAD(fmi2SetupExperiment); LOAD(fmi2EnterInitializationMode);
    LOAD(fmi2ExitInitializationMode); LOAD(fmi2SetReal); LOAD(fmi2GetReal); LOAD(fmi2DoStep);
    LOAD(fmi2FreeInstance);
    if (!lib || !f || fread(u, sizeof(double), (size_t)(n + 1), f) != (size_t)(n + 1)) return 2;
    for (r = 0; r < repeats; r++) {
        struct timespec t0, t1, c0, c1;
        double seconds, cpu;
        fmi2Component c;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
        clock_gettime(CLOCK_MONOTONIC, &t0);
        c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
        fmi2SetReal(c, &in, 1, &u[0]);
        fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        fmi2EnterInitializationMode(c);
        fmi2ExitInitializationMode(c);
        for (k = 0; k < n; k++) {
            fmi2SetReal(c, &in, 1, &u[k]);
            if (fmi2DoStep(c, k * step, step, fmi2True) != fmi2OK) return 3;
            fmi2GetReal(c, &out, 1, &x);
        }
        fmi2FreeInstance(c);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
        seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        cpu = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
        if (seconds < best) best = seconds;
        if (cpu < best_cpu) best_cpu = cpu;
    }
    printf("%.9f %.17g %.9f\n", best, x, best_cpu);
    return 0;
}
"""


def fmu_time_in_c(path: Path, fmu, grid, drive, repeats: int,
                  folder: Path) -> tuple[float, float]:
    """The best of ``repeats`` runs of the CS FMU's binary by the C driver: seconds inside
    the FMU for the whole cycle (instantiate to free), wall-clock and CPU time (the process
    alone: what a machine shared with other jobs does not add)."""
    from fmpy import read_model_description

    from pneumact.export.compiler import find_compiler, fmi_headers

    description = read_model_description(str(path))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    binary = next(n for n in zipfile.ZipFile(path).namelist() if n.startswith("binaries/"))
    library = folder / Path(binary).name
    library.write_bytes(zipfile.ZipFile(path).read(binary))
    (folder / "driver.c").write_text(DRIVER)
    program = folder / "driver"
    subprocess.run([find_compiler(), "-O2", "-std=c99", "-D_POSIX_C_SOURCE=199309L",
                    "-I", str(fmi_headers()), "-o", str(program), str(folder / "driver.c"),
                    "-ldl"], check=True)
    drive.astype(float).tofile(folder / "drive.bin")
    step = float(grid[1] - grid[0])
    result = subprocess.run(
        [str(program), str(library), description.guid, str(refs[fmu.names("input")[0]]),
         str(refs["position"]), repr(step), str(grid.size - 1), str(repeats),
         str(folder / "drive.bin")], capture_output=True, text=True, check=True)
    fields = result.stdout.split()
    return float(fields[0]), float(fields[2])


def c_integrator(fmu_path: Path, folder: Path):
    """The FMU's model.c built here as a library whose pa_integrate ctypes can call."""
    (folder / "model.c").write_bytes(zipfile.ZipFile(fmu_path).read("sources/model.c"))
    library = folder / "model.so"
    from pneumact.export.compiler import FLAGS, find_compiler

    subprocess.run([find_compiler(), *(f for f in FLAGS if f != "-fvisibility=hidden"), "-o",
                    str(library), str(folder / "model.c"), "-lm"], check=True)
    lib = ctypes.CDLL(str(library))

    class State(ctypes.Structure):
        _fields_ = [("data", ctypes.POINTER(ctypes.c_double)),
                    ("shape", ctypes.c_int64 * 1), ("strides", ctypes.c_int64 * 1)]

    lib.pa_integrate.restype = State
    return lib


def integrator_times(lib, model, experiment, repeats: int) -> tuple[float, float]:
    """The C integrator and the numba kernel on the same run (arrays built once)."""
    solver = Rodas4()
    prep = prepare(model, experiment, solver)
    kernel = prep.kernel
    n_t = prep.t_out.size
    y_out, out = np.empty((n_t, kernel.NSTATE)), np.empty((n_t, kernel.NOUT))
    info = np.zeros(kernel.INFO_LENGTH)
    vector = prep.vector.copy()
    arrays = [c_array(a) for a in (prep.y0, vector, prep.sig, prep.ptr, prep.breakpoints,
                                   prep.t_out)]
    atol, c_y, c_out, c_info = (c_array(a) for a in (prep.atol, y_out, out, info))

    def run_c():
        arena = Arena()
        lib.pa_integrate(ctypes.byref(arena), *arrays, ctypes.c_double(solver.rtol), atol,
                         ctypes.c_double(solver.h_init), ctypes.c_double(solver.h_max),
                         ctypes.c_int64(prep.max_steps), c_y, c_out, c_info)
        lib.pa_arena_free(ctypes.byref(arena))

    def run_numba():
        kernel.integrate_rodas4(prep.y0, vector, prep.sig, prep.ptr, prep.breakpoints,
                                prep.t_out, solver.rtol, prep.atol, solver.h_init,
                                solver.h_max, prep.max_steps, y_out, out, info)

    run_numba()
    c_s, _ = timed(run_c, repeats)
    numba_s, _ = timed(run_numba, repeats)
    return c_s, numba_s


def cs_case(label: str, repeats: int, folder: Path) -> dict:
    valve, friction = CASES[label]
    name = "vgt-paper-gms4" if isinstance(friction, pa.GMS) else "vgt-paper"
    model = pa.Actuator(pa.load_params(name), friction=friction, valve=valve())
    experiment = pa.CommandCycle() if valve is pa.CommandValve else pa.PressureCycle()
    path = folder / f"{label.replace(', ', '_')}_cs.fmu"
    fmu = pa.export_fmu(model, path, kind="cs")
    grid, drive, stairs = held_input(experiment, CS_STEP)
    runs = [fmpy_cs_loop(str(path), fmu, grid, drive) for _ in range(repeats)]
    inside = statistics.median(r[0] for r in runs)
    loop = statistics.median(r[1] for r in runs)
    input_name = fmu.names("input")[0]
    table = np.array(list(zip(grid, drive, 0 * drive, strict=True)),
                     dtype=[("time", float), (input_name, float), ("external_force", float)])
    simulate_s, _ = timed(lambda: fmpy.simulate_fmu(
        str(path), fmi_type="CoSimulation", stop_time=experiment.t_end, input=table,
        start_values={input_name: float(drive[0])}, step_size=CS_STEP,
        output_interval=CS_STEP, output=["position"]), repeats)
    run = pa.simulate(model, stairs, t_eval=grid)
    travel = float(np.ptp(run["position"]))
    rms = float(np.sqrt(np.mean((runs[0][2] - run["position"]) ** 2)))
    lib_folder = folder / f"{label.replace(', ', '_')}_lib"
    lib_folder.mkdir()
    lib = c_integrator(path, lib_folder)
    c_s, numba_s = integrator_times(lib, model, stairs, repeats)
    in_c, in_c_cpu = fmu_time_in_c(path, fmu, grid, drive, repeats, lib_folder)
    return {"case": label, "FMU time [ms]": 1e3 * in_c, "FMU CPU time [ms]": 1e3 * in_c_cpu,
            "FMU calls from FMPy [ms]": 1e3 * inside,
            "FMPy loop [ms]": 1e3 * loop,
            "simulate_fmu [ms]": 1e3 * simulate_s,
            "C integrator [ms]": 1e3 * c_s, "numba kernel [ms]": 1e3 * numba_s,
            "C / numba": c_s / numba_s, "position RMS [% travel]": 100 * rms / travel}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--cs-only", action="store_true",
                        help="only the Co-Simulation FMU's measurements")
    args = parser.parse_args()
    warnings.simplefilter("ignore", pa.PassivityWarning)
    import pandas as pd

    def show(rows):
        print(pd.DataFrame(rows).set_index("case").to_string(
            float_format=lambda v: f"{v:.3g}"))

    with tempfile.TemporaryDirectory() as folder:
        if not args.cs_only:
            show([case(label, args.repeats, Path(folder)) for label in CASES])
            print()
        print(f"Co-Simulation FMU, one 20 s cycle at a {CS_STEP * 1e3:g} ms communication "
              "step (FMPy 'FMU2Slave'), and its C integrator against the numba kernel on "
              "the same held-input run:")
        show([cs_case(label, args.repeats, Path(folder)) for label in CASES])


if __name__ == "__main__":
    main()
