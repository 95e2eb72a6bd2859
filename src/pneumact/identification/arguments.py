"""The arguments of ``fit`` checked where they enter, before any simulation: one message
naming the argument, the value and what is allowed (the identification procedure itself
lives in ``fit.py``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ..checks import as_instance, check_bool, check_finite, check_names
from ..errors import ArgumentError, ArgumentTypeError
from ..io.records import Record, as_records
from ..progress import check_progress

__all__ = ["check_fit_arguments", "check_window", "fit_records"]

WHERE = "fit"


def fit_records(records) -> list[Record]:
    """Records as a list: one Record, a list of them, or paths (read with the defaults)."""
    return as_records(records, WHERE)


def check_window(window, where: str = WHERE) -> tuple[float, float] | None:
    """(t0, t1) with t0 < t1, finite, or None."""
    if window is None:
        return None
    if isinstance(window, (str, bytes)) or not isinstance(window, Sequence) or len(window) != 2:
        raise ArgumentTypeError(f"{where}: window = {window!r:.60}: must be a pair (t0, t1) of "
                                "times [s]")
    t0 = check_finite("window t0", window[0], where=where)
    t1 = check_finite("window t1", window[1], where=where)
    if not t0 < t1:
        raise ArgumentError(f"{where}: window = ({t0:g}, {t1:g}) s: must have t0 < t1")
    return t0, t1


def check_fit_arguments(model, records: list[Record], free, *, per_record, start, signals,
                        executor, smooth_input, progress, solver) -> dict:
    """The arguments of ``fit`` that are not option objects, checked; returns the
    normalised ones (lists of names, the solver instance)."""
    from ..simulation.simulate import check_model, model_stroke
    from ..simulation.solvers import Solver

    check_model(model, WHERE)
    names = {
        "free": check_names("free", free, where=WHERE, what="parameter name",
                            allow_empty=False),
        "per_record": check_names("per_record", per_record, where=WHERE,
                                  what="parameter name"),
        "signals": check_names("signals", signals, where=WHERE, what="signal name",
                               allow_empty=False),
    }
    if start is not None:
        if not isinstance(start, Mapping):
            raise ArgumentTypeError(f"{WHERE}: start = {start!r:.60}: must be a dict (name "
                                    f"-> value), not {type(start).__name__}")
        for key, item in start.items():
            if not isinstance(key, str):
                raise ArgumentTypeError(f"{WHERE}: start key {key!r}: must be a name")
            check_finite(f"start[{key!r}]", item, where=WHERE)
    if executor.chunk_size is not None:
        raise ArgumentError(f"{WHERE}: executor chunk_size = {executor.chunk_size}: a fit "
                            "runs one start per task; leave chunk_size None")
    check_bool("smooth_input", smooth_input, where=WHERE)
    check_progress(progress, WHERE)
    if solver is not None:
        solver = as_instance("solver", solver, Solver, where=WHERE,
                             examples="pa.Rodas4(rtol=1e-6)")
    stroke = model_stroke(model)
    if stroke is not None:
        for record in records:
            record.check_within_stroke(stroke, WHERE)
    return {**names, "solver": solver}
