"""The batch engine: many parameter sets of one model, on all cores or a Dask cluster."""

from .engine import BatchResult, simulate_batch
from .runner import STATUS_INVALID, STATUS_OK, STATUS_SOLVER
from .spec import BatchSpec

__all__ = ["STATUS_INVALID", "STATUS_OK", "STATUS_SOLVER", "BatchResult", "BatchSpec",
           "simulate_batch"]
