"""Numba functions declared without importing numba (issue 43: a warm command in well
under a second).

Every kernel component, signal and feature is a numba function. Declaring them with
``numba.njit`` imports numba (0.4-0.8 s) and makes ~300 dispatchers in every process,
although a run on the C engine, a parameter listing or ``--help`` never calls one of
them. ``njit`` here records the Python function and its options and makes numba's
dispatcher the first time something needs it: a call from Python, or numba typing a
function that calls it (numba reads a global's type from its ``_numba_type_``, which
this stand-in hands on from the real dispatcher), or any other dispatcher attribute
(``py_func`` excepted: the C back end and the kernel generator read it without numba).
Dunder names are never forwarded, so probing a stand-in (``getattr(obj,
"__kernel_options__", None)``, ``copy``, ``inspect``) does not import numba.
"""

from __future__ import annotations

import functools
import importlib
import sys
import threading
from collections.abc import Callable
from typing import Any, TypeGuard

__all__ = ["LazyDispatcher", "dispatcher_of", "is_compiled_function", "lazy_dispatcher", "njit"]

_MAKING = threading.RLock()


class LazyDispatcher:
    """A numba function whose dispatcher is made on first use (see the module)."""

    def __init__(self, py_func: Callable, options: dict[str, Any],
                 prepare: Callable[[Any], Any] | None = None):
        functools.update_wrapper(self, py_func)
        self.py_func = py_func
        self.options = options
        self._prepare = prepare
        self._dispatcher: Any = None

    def dispatcher(self) -> Any:
        """numba's dispatcher of this function (made, and numba imported, on first call)."""
        if self._dispatcher is None:
            with _MAKING:
                if self._dispatcher is None:
                    import numba

                    made = numba.njit(**self.options)(self.py_func)
                    self._dispatcher = self._prepare(made) if self._prepare else made
        return self._dispatcher

    @property
    def made(self) -> bool:
        """Whether the dispatcher exists (numba was needed for this function)."""
        return self._dispatcher is not None

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.dispatcher()(*args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") and name.endswith("__"):
            raise AttributeError(name)
        return getattr(self.dispatcher(), name)

    def __reduce__(self) -> tuple:
        # a module's function pickles by name, as numba's dispatchers do for them
        return _module_attribute, (self.__module__, self.__qualname__)

    def __repr__(self) -> str:
        state = "made" if self.made else "not made yet"
        return f"<numba function {self.__module__}.{self.__qualname__} ({state})>"


def _module_attribute(module: str, qualname: str) -> Any:
    value: Any = importlib.import_module(module)
    for part in qualname.split("."):
        value = getattr(value, part)
    return value


def njit(*args: Any, **options: Any) -> Any:
    """``numba.njit`` without importing numba until the function is needed: used bare
    (``@njit``) or with options (``@njit(cache=True, inline="always")``)."""
    if len(args) == 1 and callable(args[0]) and not options:
        return LazyDispatcher(args[0], {})
    if args:
        raise TypeError("pneumact's njit takes keyword options only (no signatures)")
    return lambda py_func: LazyDispatcher(py_func, options)


def lazy_dispatcher(py_func: Callable, options: dict[str, Any],
                    prepare: Callable[[Any], Any] | None = None) -> LazyDispatcher:
    """``py_func`` compiled with ``options``; ``prepare(dispatcher)`` applied when it is
    made (the kernel generator wraps its functions' compilation in a file lock)."""
    return LazyDispatcher(py_func, options, prepare)


def is_compiled_function(value: Any) -> TypeGuard[Any]:
    """Whether ``value`` is a numba function (a stand-in or numba's own dispatcher),
    without importing numba when it is not loaded yet."""
    if isinstance(value, LazyDispatcher):
        return True
    registry = sys.modules.get("numba.core.registry")
    return registry is not None and isinstance(value, registry.CPUDispatcher)


def dispatcher_of(value: Any) -> Any:
    """numba's dispatcher behind ``value`` (a stand-in's, made now), else ``value``."""
    return value.dispatcher() if isinstance(value, LazyDispatcher) else value
