"""The C ABI of the back end's generated code as ctypes mirrors (no numba needed): what a
caller of a built unit passes. The tests, the benchmarks, the run-time engine and the FMU
check load the same library and call it through these."""

from __future__ import annotations

import ctypes
import functools

import numpy as np

__all__ = ["Arena", "array_struct", "c_array"]


class Arena(ctypes.Structure):
    """``pa_arena``: the allocations of a function that allocates (zero it to start)."""

    _fields_ = [("first", ctypes.c_void_p), ("current", ctypes.c_void_p),
                ("failed", ctypes.c_int)]


@functools.cache
def array_struct(element: type, ndim: int) -> type[ctypes.Structure]:
    """The ctypes mirror of the back end's ``ndim``-d array struct of ``element`` (one
    class per kind, made once)."""
    fields = [("data", ctypes.POINTER(element)), ("shape", ctypes.c_int64 * ndim),
              ("strides", ctypes.c_int64 * ndim)]
    return type(f"Array{ndim}", (ctypes.Structure,), {"_fields_": fields})


def c_array(values: np.ndarray) -> ctypes.Structure:
    """The back end's array struct of ``values`` (float64 or int64, any ndim): data,
    shape[ndim], strides[ndim] in elements; it points into ``values``, which must
    outlive the call."""
    element = ctypes.c_int64 if values.dtype == np.int64 else ctypes.c_double
    ndim = values.ndim
    struct = array_struct(element, ndim)
    return struct(values.ctypes.data_as(ctypes.POINTER(element)),
                  (ctypes.c_int64 * ndim)(*values.shape),
                  (ctypes.c_int64 * ndim)(*[n // values.itemsize for n in values.strides]))
