"""What a batch is: the model, experiment, solver, parameter columns and the outputs kept.

``BatchSpec`` is picklable (sent once to Dask workers) and describes itself as JSON for
the manifest of a resumable batch; the checks turn a user's table, names and reference
into clear errors before anything runs.
"""

from __future__ import annotations

import difflib
import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ...core.features import (
    FEATURE_UNITS,
    FEATURES,
    PRESSURE_FEATURES,
    REFERENCE_FEATURES,
    SUMMARY_FEATURES,
)
from ...errors import DataError, ParameterError
from ...experiments.actuator import Experiment
from ..solvers import Solver

__all__ = ["BatchSpec", "check_names", "check_reference", "check_table", "default_features"]


@dataclass(frozen=True, eq=False)
class BatchSpec:
    """Everything a chunk needs besides its rows."""

    model: Any
    experiment: Experiment
    solver: Solver
    columns: tuple[str, ...]
    features: tuple[str, ...]
    signals: tuple[str, ...]
    t_eval: np.ndarray | None = None
    reference: tuple[np.ndarray, np.ndarray] | None = None
    y0: np.ndarray | None = None
    #: the kernel's engine (``core.c_engine``); not in ``describe``: both give the same runs
    engine: str = "auto"

    def describe(self) -> dict[str, Any]:
        """JSON-able description (large arrays hashed) for the manifest and caching."""
        from ...core.assembly import assemble

        model, exp, solver = self.model, self.experiment, self.solver
        assembly = assemble(model)
        channels = model.channels(exp.drive, exp.drives)
        return {
            "model": {
                "type": type(model).__name__,
                "description": assembly.describe(),
                "kernel": assembly.kernel_spec().label,
                "parameter_set": getattr(model.params, "name", "custom"),
                "values": _hash_array(assembly.pack()),
                "channels": {name: None if c is None else _hash_array(c.encode())
                             for name, c in zip(assembly.channels, channels, strict=True)
                             if name != "drive"},
            },
            "experiment": {
                "name": exp.name, "quantity": exp.quantity, "t_start": exp.t_start,
                "t_end": exp.t_end, "n_points": int(exp.n_points),
                "drive": _hash_array(exp.drive.encode()),
                "breakpoints": _hash_array(exp.breakpoints()),
            },
            "solver": {
                "type": type(solver).__name__, "rtol": solver.rtol,
                "atol": solver.atol if not isinstance(solver.atol, Mapping)
                else dict(sorted(solver.atol.items())),
                "h_init": solver.h_init, "h_max": repr(solver.h_max),
                "max_steps": solver.max_steps,
            },
            "columns": list(self.columns),
            "features": list(self.features),
            "signals": list(self.signals),
            "t_eval": None if self.t_eval is None else _hash_array(self.t_eval),
            "reference": None if self.reference is None
            else [_hash_array(self.reference[0]), _hash_array(self.reference[1])],
            "y0": None if self.y0 is None else _hash_array(self.y0),
        }

    def token(self) -> str:
        return hashlib.sha256(json.dumps(self.describe(), sort_keys=True).encode()).hexdigest()

    @property
    def units(self) -> dict[str, str]:
        from ...core.assembly import assemble
        from ...parameters import catalogue

        specs = catalogue()
        own = assemble(self.model).parameter_units  # a controller's gains: the loop's
        units = {c: own.get(c) or specs[c].unit for c in self.columns}
        units.update({f: FEATURE_UNITS[f] for f in self.features})
        return units


def _hash_array(values) -> str:
    array = np.ascontiguousarray(np.asarray(values, dtype=np.float64))
    return hashlib.sha256(array.tobytes()).hexdigest()[:32]


def table_hash(columns: Sequence[str], values: np.ndarray) -> str:
    digest = hashlib.sha256(json.dumps(list(columns)).encode())
    digest.update(np.ascontiguousarray(values, dtype=np.float64).tobytes())
    return digest.hexdigest()


# --------------------------------------------------------------------------- checks
def check_table(table, assembly) -> tuple[tuple[str, ...], np.ndarray]:
    """(column names, values as a C-contiguous float array) of a parameter table."""
    if not isinstance(table, pd.DataFrame):
        raise ParameterError(f"table must be a pandas DataFrame (one column per parameter), "
                             f"got {type(table).__name__}")
    columns = [str(c) for c in table.columns]
    if not columns:
        raise ParameterError("table has no columns; give one column per parameter name")
    if len(table) == 0:
        raise ParameterError("table has no rows; give one row per parameter set")
    duplicates = sorted({c for c in columns if columns.count(c) > 1})
    if duplicates:
        raise ParameterError(f"table has duplicate parameter columns {duplicates}")
    assembly.check_parameters(columns, "table column")
    try:
        values = table.to_numpy(dtype=np.float64)
    except (TypeError, ValueError):
        for name in columns:
            converted = pd.to_numeric(table[name], errors="coerce")
            bad = converted.isna() & table[name].notna()
            if bad.any():
                raise ParameterError(
                    f"table column '{name}' row {int(np.flatnonzero(bad)[0])} = "
                    f"{table[name][bad].iloc[0]!r}: must be a number (SI value)") from None
        raise
    return tuple(columns), np.ascontiguousarray(values)


def check_names(kind: str, wanted: Sequence[str], allowed: Sequence[str]) -> tuple[str, ...]:
    wanted = tuple(dict.fromkeys(str(w) for w in wanted))
    for name in wanted:
        if name not in allowed:
            close = difflib.get_close_matches(name, list(allowed), n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'?" if close else f"allowed: {', '.join(allowed)}"
            raise ParameterError(f"unknown {kind} '{name}' ({hint})")
    return wanted


def check_reference(reference) -> tuple[np.ndarray, np.ndarray] | None:
    """(time, position) of a reference record, from arrays or a Record."""
    if reference is None:
        return None
    if hasattr(reference, "__getitem__") and not isinstance(reference, (tuple, list)):
        try:
            reference = (reference["time"], reference["position"])
        except (KeyError, IndexError) as exc:
            raise DataError(f"reference record needs 'time' and 'position' ({exc})") from exc
    if len(reference) != 2:
        raise DataError("reference must be (time, position) arrays or a Record with them")
    t, x = (np.ascontiguousarray(a, dtype=float) for a in reference)
    if t.ndim != 1 or t.shape != x.shape or t.size < 2:
        raise DataError(f"reference time {t.shape} and position {x.shape} must be 1-D arrays "
                        "of the same length (>= 2)")
    if np.any(np.diff(t) <= 0):
        raise DataError("reference time must be strictly increasing")
    return t, x


def default_features(summary_kind: str, has_pressure: bool, has_reference: bool,
                     signals) -> tuple[str, ...]:
    """The features a batch computes when none are named (none if signals are asked):
    those of the model's ``summary_kind`` (an actuator's hysteresis, a cylinder's or a
    rig's motion; the pressure features only where the model has a pressure)."""
    if signals:
        return ()
    features = [f for f in SUMMARY_FEATURES[summary_kind]
                if has_pressure or f not in PRESSURE_FEATURES]
    if has_reference:
        features += REFERENCE_FEATURES
    return tuple(features)


def check_features(features: Sequence[str], has_pressure: bool, has_reference: bool,
                   model_name: str) -> tuple[str, ...]:
    features = check_names("feature", features, FEATURES)
    if not has_pressure and set(features) & set(PRESSURE_FEATURES):
        raise ParameterError(
            f"features {sorted(set(features) & set(PRESSURE_FEATURES))} need a pressure "
            f"signal, which a {model_name} does not have: use them with an Actuator (a "
            f"{model_name}'s motion: {', '.join(SUMMARY_FEATURES['motion'])})")
    if not has_reference and set(features) & set(REFERENCE_FEATURES):
        raise ParameterError("features rms_error/max_error need reference=(time, position)")
    return features
