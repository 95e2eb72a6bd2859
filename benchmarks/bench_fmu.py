"""Benchmark: the exported FMU against pneumact on the same run, and what an export costs.

For each valve (the vgt-paper actuator with LuGre; GMS-4 behind the source as well):
  - the export (``pa.export_fmu``: translation of the kernel to C, the C compiler, the
    archive), its kernel already compiled in this process;
  - one 20 s cycle (``PressureCycle``, ``CommandCycle`` for the command valve) simulated by
    FMPy (CVode, BDF, relative tolerance 1e-6, 4000 output intervals) and by
    ``pa.simulate`` (Rodas4, rtol 1e-6), each warm, the median of ``--repeats`` runs;
  - the agreement: position RMS [% of stroke] and loop width [%].

Run (after ``pip install -e ".[fmu]"``, with a C compiler):
    python benchmarks/bench_fmu.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

try:
    import pneumact as pa
except ImportError:  # not installed: use the source tree next to this script
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    import pneumact as pa

import fmpy

from pneumact.core.features import loop_width_pressure

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore", pa.PassivityWarning)
    import pandas as pd

    with tempfile.TemporaryDirectory() as folder:
        rows = [case(label, args.repeats, Path(folder)) for label in CASES]
    print(pd.DataFrame(rows).set_index("case").to_string(float_format=lambda v: f"{v:.3g}"))


if __name__ == "__main__":
    main()
