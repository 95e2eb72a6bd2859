"""Memory a run will need, estimated before it starts, and refused when it cannot fit.

A simulation keeps every output point (states and derived signals, float64), and its
``Result`` holds them again as named signals; a batch keeps the requested signals of every
set, once in chunks and once assembled. A 1 kHz grid over a day is 86 million points: such
a run is refused at once with the figure, not after minutes of integration by an
allocation the machine cannot make.
"""

from __future__ import annotations

import os

from ..errors import ResourceError

__all__ = ["available_memory", "batch_bytes", "check_memory", "simulate_bytes"]

#: share of the available memory one run may plan to use
MEMORY_FRACTION = 0.8
#: copies of the output arrays a run holds at its peak (kernel output, Result, a table)
RUN_COPIES = 3
BATCH_COPIES = 3
FLOAT = 8


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux MemAvailable; else physical
    memory), or None when the system does not tell."""
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


def check_memory(needed: int, what: str) -> None:
    """ResourceError when ``needed`` bytes exceed the share of the available memory a run
    may use; ``what`` names the run (its sizes) in the message."""
    available = available_memory()
    if available is None or needed <= MEMORY_FRACTION * available:
        return
    raise ResourceError(
        f"{what} would need about {_size(needed)} of memory; {_size(available)} are "
        "available", api_hint="keep fewer output points (a shorter run, n_points or t_eval), "
                              "fewer signals or fewer sets per run",
        cli_hint="keep fewer output points (a shorter --t-end, fewer samples per second or "
                 "--times), fewer --signals or fewer sets")
