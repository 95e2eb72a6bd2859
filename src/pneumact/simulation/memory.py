"""Memory a run will need, estimated before it starts, and refused when it cannot fit.

A simulation keeps every output point (states and derived signals, float64), and its
``Result`` holds them again as named signals; a batch keeps the requested signals of every
set, once in chunks and once assembled. A 1 kHz grid over a day is 86 million points: such
a run is refused at once with the figure, not after minutes of integration by an
allocation the machine cannot make.
"""

from __future__ import annotations

import logging
import math
import os
import re
import time

from ..errors import ResourceError

__all__ = ["ESTIMATES", "MEMORY_LIMIT_ENV", "available_memory", "batch_bytes",
           "check_memory", "memory_limit", "simulate_bytes"]

#: the environment variable that sets the memory limit of one run ("8GiB", "500MB",
#: bytes); without it the limit is DEFAULT_MEMORY_LIMIT or the share MEMORY_FRACTION of
#: the available memory, whichever is smaller
MEMORY_LIMIT_ENV = "PNEUMACT_MEMORY_LIMIT"
#: the default limit [bytes]: larger runs are refused until the limit is raised
DEFAULT_MEMORY_LIMIT = 4 * 1024**3
#: estimates of memory and time before big work, as INFO records (the command line
#: prints them as they come)
ESTIMATES = logging.getLogger("pneumact.estimates")
#: runs planning this much memory or more say so before they start
ANNOUNCED_BYTES = 256 * 1024**2
_UNITS = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "kib": 1024, "m": 1e6, "mb": 1e6,
          "mib": 1024**2, "g": 1e9, "gb": 1e9, "gib": 1024**3, "t": 1e12, "tb": 1e12,
          "tib": 1024**4}

#: share of the available memory one run may plan to use
MEMORY_FRACTION = 0.8
#: copies of the output arrays a run holds at its peak (kernel output, Result, a table)
RUN_COPIES = 3
BATCH_COPIES = 3
FLOAT = 8


#: seconds a reading of the available memory is reused: every run checks its memory,
#: and reading /proc/meminfo took 30-60 µs of a 5 ms run
MEMORY_READING_AGE = 1.0
_last_reading: tuple[float, int | None] = (-math.inf, None)


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux MemAvailable; else physical
    memory), or None when the system does not tell; read at most once per
    ``MEMORY_READING_AGE``."""
    global _last_reading
    now = time.monotonic()
    if now - _last_reading[0] < MEMORY_READING_AGE:
        return _last_reading[1]
    found = _read_available_memory()
    _last_reading = (now, found)
    return found


def _read_available_memory() -> int | None:
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def simulate_bytes(n_times: int, n_states: int, n_outputs: int, n_parameters: int = 0
                   ) -> int:
    """Peak bytes of one run with ``n_times`` output points (and forward sensitivities
    of the states to ``n_parameters`` parameters)."""
    per_point = 1 + n_states + n_outputs + n_states * n_parameters
    return RUN_COPIES * FLOAT * int(n_times) * per_point


def batch_bytes(n_sets: int, n_signals: int, n_times: int, n_features: int) -> int:
    """Peak bytes of a batch keeping ``n_signals`` signals on ``n_times`` points and
    ``n_features`` features of each of ``n_sets`` sets."""
    return BATCH_COPIES * FLOAT * int(n_sets) * (int(n_signals) * int(n_times)
                                                 + int(n_features) + 4)


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} TiB"  # pragma: no cover - the loop returns


def memory_limit() -> tuple[int, str]:
    """(bytes one run may plan to use, where that limit comes from)."""
    text = os.environ.get(MEMORY_LIMIT_ENV, "").strip()
    if text:
        match = re.fullmatch(r"([0-9.]+(?:[eE][-+]?\d+)?)\s*([A-Za-z]*)", text)
        factor = _UNITS.get(match.group(2).lower()) if match else None
        if match is None or factor is None:
            raise ResourceError(f"{MEMORY_LIMIT_ENV} = {text!r}: give a size such as 8GiB, "
                                "500MB or a number of bytes")
        return int(float(match.group(1)) * factor), f"{MEMORY_LIMIT_ENV}={text}"
    available = available_memory()
    if available is not None and MEMORY_FRACTION * available < DEFAULT_MEMORY_LIMIT:
        return int(MEMORY_FRACTION * available), (
            f"{MEMORY_FRACTION:.0%} of the {_size(available)} available")
    return DEFAULT_MEMORY_LIMIT, f"the default; raise it with {MEMORY_LIMIT_ENV}, e.g. 16GiB"


def check_memory(needed: int, what: str) -> None:
    """ResourceError when ``needed`` bytes exceed the memory limit of one run
    (``memory_limit``); ``what`` names the run (its sizes) in the message. A run that
    plans ``ANNOUNCED_BYTES`` or more says its estimate first (``ESTIMATES``)."""
    limit, source = memory_limit()
    if needed <= limit:
        if needed >= ANNOUNCED_BYTES:
            ESTIMATES.info("%s: about %s of memory (limit %s)", what, _size(needed),
                           _size(limit))
        return
    available = available_memory()
    there = f"; {_size(available)} are available" if available is not None else ""
    raise ResourceError(
        f"{what} would need about {_size(needed)} of memory, above the limit of "
        f"{_size(limit)} ({source}){there}",
        api_hint="keep fewer output points (a shorter run, n_points or t_eval), fewer "
                 "signals or fewer sets per run",
        cli_hint="keep fewer output points (a shorter --t-end, fewer samples per second or "
                 f"--times), fewer --signals or fewer sets, or raise the limit "
                 f"({MEMORY_LIMIT_ENV}=16GiB pneumact ...)")
