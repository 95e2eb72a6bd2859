"""Validate identified friction laws on the real records in ../shared/data.

    python examples/real_data_validation.py [DATA_DIR] [OUT_DIR]

1. EMPS drive: Coulomb + viscous friction and the mass identified on DATA_EMPS.mat
   (inverse model, 50 Hz zero-phase filter) predict the force of DATA_EMPS_PULSES.mat.
2. TU Delft cylinder (O-ring seal): friction identified at 1 and 7 bar supply pressure,
   its parameters interpolated linearly in the pressure, predicts the friction at 3 and
   5 bar.

Each writes metrics.csv, parameters.csv, force.png and a self-contained report.html.
"""

from __future__ import annotations

import sys
from pathlib import Path

from pneumact.identification import inverse_friction
from pneumact.io.datasets import read_emps, read_tudelft_cylinder
from pneumact.validation import friction_across_levels, validate_friction

HERE = Path(__file__).resolve().parent
EMPS_CUTOFF = 50.0  # Hz: before differentiating the 1 kHz position
TUDELFT_CUTOFF = 5.0  # Hz: 100 Hz laser samples, slow strokes
TUDELFT_BARS = (1, 3, 5, 7)
TUDELFT_TRAIN = (1, 7)


def emps(data: Path, out: Path):
    estimation = read_emps(data / "emps" / "DATA_EMPS.mat")
    pulses = read_emps(data / "emps" / "DATA_EMPS_PULSES.mat")
    identified = inverse_friction(estimation, cutoff=EMPS_CUTOFF)
    validation = validate_friction(identified, pulses)
    validation.write(out, title="EMPS drive: friction identified on DATA_EMPS.mat, "
                                "validated on DATA_EMPS_PULSES.mat")
    return validation


def tudelft(data: Path, out: Path):
    folder = data / "pneumatic_cylinder_friction_tudelft"
    records = {bar: read_tudelft_cylinder(folder / f"O-ring_{bar}bar.csv")
               for bar in TUDELFT_BARS}
    validation = friction_across_levels(records, TUDELFT_TRAIN, force="friction",
                                        mass=False, cutoff=TUDELFT_CUTOFF)
    validation.write(out, title="TU Delft cylinder (O-ring): friction identified at 1 and "
                                "7 bar, predicted at 3 and 5 bar (supply pressure, bar)")
    return validation


def main(data: Path, out: Path) -> None:
    for name, run in (("emps", emps), ("tudelft", tudelft)):
        validation = run(data, out / name)
        print(f"{name}:")
        print(validation.metrics()[["record", "role", "fit_percent",
                                    "relative_force_error"]].to_string(index=False))
        print(f"  report: {out / name / 'report.html'}")


if __name__ == "__main__":
    args = sys.argv[1:]
    main(Path(args[0]) if args else HERE.parents[1] / "shared" / "data",
         Path(args[1]) if len(args) > 1 else Path("pneumact-real-data"))
