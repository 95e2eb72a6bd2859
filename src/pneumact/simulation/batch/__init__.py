"""The batch engine: many parameter sets of one model, on all cores or a Dask cluster."""

from .engine import BatchResult, check_outputs, signal_names, simulate_batch
from .runner import STATUS_ERROR, STATUS_INVALID, STATUS_OK, STATUS_SOLVER
from .spec import BatchSpec

__all__ = ["STATUS_ERROR", "STATUS_INVALID", "STATUS_OK", "STATUS_SOLVER", "BatchResult",
           "BatchSpec", "check_outputs", "signal_names", "simulate_batch"]
