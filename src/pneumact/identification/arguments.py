"""The arguments of ``fit`` checked where they enter, before any simulation: one message
naming the argument, the value and what is allowed (the identification procedure itself
lives in ``fit.py``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ..checks import (
    as_instance,
    check_bool,
    check_choice,
    check_finite,
    check_int,
    check_names,
    check_positive,
    check_seed,
)
from ..errors import ArgumentError, ArgumentTypeError
from ..io.records import Record, as_records
from ..progress import check_progress

__all__ = ["LOSSES", "check_fit_arguments", "check_window", "fit_records"]

#: the robust losses of scipy's least_squares
LOSSES = ("linear", "soft_l1", "huber", "cauchy", "arctan")
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


def _mapping(name: str, value, check_value) -> None:
    if value is None:
        return
    if not isinstance(value, Mapping):
        raise ArgumentTypeError(f"{WHERE}: {name} = {value!r:.60}: must be a dict (name -> "
                                f"value), not {type(value).__name__}")
    for key, item in value.items():
        if not isinstance(key, str):
            raise ArgumentTypeError(f"{WHERE}: {name} key {key!r}: must be a name")
        check_value(f"{name}[{key!r}]", item)


def _bound_pair(name: str, value) -> None:
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or len(value) != 2:
        raise ArgumentTypeError(f"{WHERE}: {name} = {value!r:.60}: must be a pair (low, high)")
    low = check_finite(f"{name} low", value[0], where=WHERE)
    high = check_finite(f"{name} high", value[1], where=WHERE)
    if not low < high:
        raise ArgumentError(f"{WHERE}: {name} = ({low:g}, {high:g}): must have low < high")


def check_fit_arguments(model, records: list[Record], free, *, per_record, start, bounds,
                        log, signals, weights, loss, f_scale, solver, multistart, seed,
                        workers, profile, profile_points, max_nfev, offsets, smooth_input,
                        progress) -> dict:
    """Every argument of ``fit`` checked; returns the normalised ones (lists of names,
    the solver instance)."""
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
        "offsets": check_names("offsets", offsets, where=WHERE, what="signal name"),
        "profile": check_names("profile", profile, where=WHERE, what="parameter name"),
    }
    if not isinstance(log, bool):
        check_names("log", log, where=WHERE, what="parameter name")
    _mapping("start", start, lambda n, v: check_finite(n, v, where=WHERE))
    _mapping("bounds", bounds, _bound_pair)
    _mapping("weights", weights, lambda n, v: check_positive(n, v, where=WHERE))
    check_choice("loss", loss, LOSSES, where=WHERE)
    check_positive("f_scale", f_scale, where=WHERE)
    check_int("multistart", multistart, minimum=0, where=WHERE)
    check_seed("seed", seed, where=WHERE)
    if workers is not None:
        check_int("workers", workers, minimum=1, where=WHERE)
    check_int("profile_points", profile_points, minimum=3, where=WHERE)
    if max_nfev is not None:
        check_int("max_nfev", max_nfev, minimum=1, where=WHERE)
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

