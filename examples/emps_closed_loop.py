"""Replay the real EMPS drive in its closed loop and compare it with the measurements.

    python examples/emps_closed_loop.py [OUT_DIR] [--data DATA_DIR]

1. Identify mass, Coulomb + viscous friction and offset on DATA_EMPS.mat (inverse
   model, 50 Hz zero-phase low-pass, as examples/real_data_validation.py).
2. Put that drive under its own sampled P/P cascade (kp, kv, gtau of the record,
   ±10 V, backward-difference velocity at 1 kHz) and let it follow the recorded
   reference of BOTH records; DATA_EMPS_PULSES.mat adds its pulses to the controller
   output (volts: the recorded command contains them, see pneumact.control.drives).
3. Print the relative errors ‖y − ŷ‖/‖y‖ of position, velocity and motor force, the
   check of the control law on the records, and what the pulse record gives under the
   other readings of its pulses; write replay.csv, metrics.csv, replay.png and
   report.html per record under OUT_DIR (default pneumact-emps-closed-loop).
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

import pandas as pd

from pneumact.control.drives import control_law_check, replay_drive
from pneumact.identification import inverse_friction
from pneumact.io.datasets import read_emps

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
EMPS_CUTOFF = 50.0  # Hz: before differentiating the 1 kHz position
RECORDS = ("DATA_EMPS.mat", "DATA_EMPS_PULSES.mat")
COLUMNS = ["record", "pulses", "position_relative_error", "position_rms_mm",
           "tracking_relative_error", "velocity_relative_error", "force_relative_error",
           "force_rms_N"]


def main(out: Path, data: Path) -> pd.DataFrame:
    began = time.perf_counter()
    folder = data / "emps"
    records = {name: read_emps(folder / name) for name in RECORDS}
    identified = inverse_friction(records["DATA_EMPS.mat"], cutoff=EMPS_CUTOFF)
    print("identified on DATA_EMPS.mat:",
          ", ".join(f"{k} = {v:.5g}" for k, v in identified.estimates.as_dict().items()),
          f"(inverse-model force error {100 * identified.relative_force_error:.2f} %)")
    call = "python " + " ".join(shlex.quote(a) for a in sys.argv)
    replays = []
    for name, record in records.items():
        replay = replay_drive(record, identified)
        replay.write(out / Path(name).stem, call=call,
                     title=f"EMPS drive in closed loop: {name} (identified on DATA_EMPS.mat)")
        replays.append(replay)
    table = pd.concat([r.metrics() for r in replays], ignore_index=True)[COLUMNS]
    with pd.option_context("display.width", 160, "display.float_format", "{:.4g}".format):
        print("\nclosed-loop replay (relative errors ‖y − ŷ‖/‖y‖):")
        print(table.to_string(index=False))
        checks = pd.DataFrame({n: control_law_check(r) for n, r in records.items()}).T
        print("\ncontrol law u = kv·(kp·(qg − qm) − Δqm/Ts) against the recorded vir:")
        print(checks.to_string())
        pulses = records["DATA_EMPS_PULSES.mat"]
        other = pd.concat([replay_drive(pulses, identified, pulses=p).metrics()
                           for p in ("force", False)], ignore_index=True)[COLUMNS]
        print("\nDATA_EMPS_PULSES.mat under the other readings of its pulses:")
        print(other.to_string(index=False))
    print(f"\nreports: {out}/<record>/report.html  ({time.perf_counter() - began:.1f} s)")
    return table


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="pneumact-emps-closed-loop",
                        type=Path, help="output folder (default: %(default)s)")
    parser.add_argument("--data", type=Path, default=DATA,
                        help="folder holding emps/ (default: %(default)s)")
    args = parser.parse_args()
    main(args.out, args.data)
