"""The mark of a kernel template's functions (read by ``core.codegen``)."""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["kernel"]


def kernel(**options) -> Callable:
    """Mark a template function: bound into each generated kernel and compiled there with
    ``njit(cache=True, **options)`` (e.g. ``nogil=True`` for the integrators)."""

    def mark(fn):
        fn.__kernel_options__ = options
        return fn

    return mark
