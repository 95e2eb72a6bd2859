"""The public API as the meta-tests walk it: every name in the ``__all__`` of ``pneumact``,
of ``pneumact.reproduction`` and of each subpackage but the command line's."""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Iterator

import pneumact as pa


def public_objects() -> Iterator[object]:
    """Each object the public API exports (an object exported twice comes twice)."""
    modules = ["pneumact", "pneumact.reproduction"] + [
        m.name for m in pkgutil.walk_packages(pa.__path__, "pneumact.")
        if m.ispkg and ".cli" not in m.name]
    for name in modules:
        module = importlib.import_module(name)
        for public in getattr(module, "__all__", []):
            yield getattr(module, public)


def dotted_name(obj) -> str:
    """``module.qualname`` of a function or class."""
    return f"{obj.__module__}.{obj.__qualname__}"
