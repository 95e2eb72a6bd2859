"""Readers for the public measured data sets pneumact is tested on (``shared/data``).

- ``read_emps``: the EMPS prismatic drive (Janot, Gautier & Brunot, 2019), MATLAB files
  with position ``qm``, reference ``qg``, controller output ``vir`` and gains; the
  motor force is ``gtau·vir``.
- ``read_tudelft_cylinder``: the TU Delft 3D-printed pneumatic cylinder seal tests
  (Zillen, Vallery & Smit, 2021, CC0): whitespace text without header, time in ms,
  position in mm, supply pressure in bar **gauge**, load-cell force in N; the seal
  friction is force − p_gauge·A (the upstream definition).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pneumact.errors import DataError
from pneumact.io.records import PRESSURE_SIGNAL, Record, read_record
from pneumact.io.tables import PathLike, require_file

__all__ = ["TUDELFT_COLUMNS", "read_emps", "read_tudelft_cylinder"]

#: Columns of the TU Delft files (upstream README): raw voltages and calibrated values.
TUDELFT_COLUMNS = ("time", "laser_raw", "pressure_raw", "force_raw", "position",
                   "pressure_gauge", "force")


def read_emps(path: PathLike) -> Record:
    """An EMPS record: time [s], position (qm) [m], reference (qg) [m], force
    (gtau·vir) [N], and the applied pulses [N] where present; the gains kp, kv, gtau
    are in ``meta``."""
    from scipy.io import loadmat

    source = Path(path)
    require_file(source)
    try:
        data = loadmat(source)
    except Exception as exc:  # scipy raises several types for a bad file
        raise DataError(f"{source}: cannot read as a MATLAB file ({exc})") from exc
    missing = [k for k in ("t", "qm", "qg", "vir", "gtau", "kp", "kv") if k not in data]
    if missing:
        raise DataError(f"{source}: not an EMPS file: variables {missing} are missing")
    gtau = float(np.ravel(data["gtau"])[0])
    signals = {"position": np.ravel(data["qm"]), "reference": np.ravel(data["qg"]),
               "force": gtau * np.ravel(data["vir"])}
    if "pulses_N" in data:
        signals["pulses"] = np.ravel(data["pulses_N"])
    units = {"position": "m", "reference": "m", "force": "N", "pulses": "N"}
    meta = {k: repr(float(np.ravel(data[k])[0])) for k in ("gtau", "kp", "kv")}
    return Record.from_arrays(np.ravel(data["t"]), signals, units, str(source), meta)


def read_tudelft_cylinder(path: PathLike, bore: float | None = None,
                          p_atm: float = 101325.0, skip: int = 15) -> Record:
    """A TU Delft cylinder record in SI with ``friction`` = force − p_gauge·A added.

    ``bore`` [m] defaults to 25.7 mm for the ``*257`` seals and 25 mm otherwise;
    ``skip`` drops the first samples as the upstream analysis does. The supply pressure
    is gauge: ``pressure`` is made absolute with ``p_atm``."""
    source = Path(path)
    if bore is None:
        bore = 0.0257 if "257" in source.stem else 0.025
    record = read_record(source, names=TUDELFT_COLUMNS, p_atm=p_atm,
                         units={"time": "ms", "position": "mm", "pressure_gauge": "bar",
                                "force": "N", "laser_raw": "V", "pressure_raw": "V",
                                "force_raw": "V"})
    area = math.pi * bore**2 / 4
    keep = slice(skip, None)
    signals = {n: record[n][keep] for n in ("position", PRESSURE_SIGNAL, "force")}
    signals["friction"] = signals["force"] - (signals[PRESSURE_SIGNAL] - p_atm) * area
    return Record.from_arrays(record.time[keep], signals,
                              {"position": "m", PRESSURE_SIGNAL: "Pa", "force": "N",
                               "friction": "N"}, str(source),
                              {"bore": repr(bore), "p_atm": repr(p_atm)})
