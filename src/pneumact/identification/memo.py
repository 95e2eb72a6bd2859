"""Runs remembered by their content, so that identification does not repeat them.

The joint refinement simulates the same records at the same parameter values more than
once: the chaos screen (``joint.amplification``) runs the forward sensitivities of a
record at the start of a round, and that round's fit starts there; a round's fit ends
where the next one starts, on the records both use. Measured on a drawn actuator of the
family test: 12 of 37 sensitivity runs repeated one made before. Within
``remembering()`` such a run is done once (``sensitivities``): its key is everything
the run depends on (the model's structure and every parameter value, the rebuilt input's
knots, the output times, the parameters differentiated, the solver), compared exactly,
so a run is reused only where it would come out bit for bit the same.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator, Mapping, Sequence

import numpy as np

__all__ = ["MEMO_BYTES", "MEMO_ENTRIES", "content_key", "remembered", "remembering",
           "sensitivities"]

#: Sensitivity runs remembered at most (the least recently used are forgotten first):
#: a round's records twice over (the last evaluation of one round, the screen of the
#: next), 12 records per campaign.
MEMO_ENTRIES = 32
#: and at most this many bytes of their arrays (a run of 8 parameters holds ~465 bytes
#: per sample: the vgt-paper campaign's 32 runs ~140 MiB; long records keep fewer runs)
MEMO_BYTES = 256 * 2**20

_LOCK = threading.Lock()
_STATE: dict = {"depth": 0, "runs": OrderedDict(), "bytes": 0}


def _nbytes(run) -> int:
    """The bytes of a sensitivity run's arrays: its sensitivities and its signals."""
    return (sum(a.nbytes for a in run.sensitivities.values())
            + run.result.time.nbytes + sum(a.nbytes for a in run.result.signals.values()))


def content_key(*arrays: np.ndarray) -> bytes:
    """A digest of the arrays' shapes and bytes: equal for equal content."""
    digest = hashlib.blake2b(digest_size=20)
    for a in arrays:
        a = np.ascontiguousarray(a, dtype=float)
        digest.update(repr(a.shape).encode())
        digest.update(a.tobytes())
    return digest.digest()


@contextlib.contextmanager
def remembering() -> Iterator[None]:
    """Within it, ``sensitivities`` remembers its runs (nested or concurrent uses share
    them; the last to leave forgets them, freeing their memory)."""
    with _LOCK:
        _STATE["depth"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _STATE["depth"] -= 1
            if _STATE["depth"] == 0:
                _STATE["runs"].clear()
                _STATE["bytes"] = 0


def remembered(function: Callable) -> Callable:
    """``function`` run within ``remembering()``."""

    @functools.wraps(function)
    def run(*args, **kwargs):
        with remembering():
            return function(*args, **kwargs)

    return run


def _key(model, experiment, knots: tuple[np.ndarray, np.ndarray], time: np.ndarray,
         names: Sequence[str], solver, values: Mapping[str, float]) -> tuple:
    """The run's identity: the model, its drive's knots, its other inputs (a cylinder's
    load), the output times, the parameters asked, the solver and the values."""
    others = tuple((name, content_key(signal.encode()))
                   for name, signal in experiment.drives.items())
    return (repr(model), content_key(*knots, time), others,
            tuple(names), repr(solver), tuple(sorted((n, float(v)) for n, v in values.items())))


def sensitivities(model, experiment, knots: tuple[np.ndarray, np.ndarray], time: np.ndarray,
                  names: Sequence[str], solver, values: Mapping[str, float]):
    """``simulate_sensitivities(model, experiment, names, solver, t_eval=time)`` with
    every parameter of ``model`` at ``values``, where ``experiment`` is the input rebuilt
    on ``knots``; remembered within ``remembering()`` (see the module docstring)."""
    from ..simulation import simulate_sensitivities

    key = _key(model, experiment, knots, time, names, solver, values)
    with _LOCK:
        found = _STATE["runs"].get(key)
        if found is not None:
            _STATE["runs"].move_to_end(key)
            return found
    run = simulate_sensitivities(model, experiment, list(names), solver, t_eval=time,
                                 values=dict(values))
    with _LOCK:
        runs = _STATE["runs"]
        if _STATE["depth"] > 0 and key not in runs:
            runs[key] = run
            _STATE["bytes"] += _nbytes(run)
            while len(runs) > 1 and (len(runs) > MEMO_ENTRIES
                                     or _STATE["bytes"] > MEMO_BYTES):
                _STATE["bytes"] -= _nbytes(runs.popitem(last=False)[1])
    return run
