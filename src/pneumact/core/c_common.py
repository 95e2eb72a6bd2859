"""What every model shares, on the C engine: signal evaluation and the loop features.

A run's summary reads its drive signal (``core.signals``) and measures its loop
(``core.features``) outside the model's kernel. On numba these calls would start numba's
compiler machinery in every process (about a second even from its cache: the target
context, its registries and the BLAS it imports); on the C engine they run in one library
built once per installation from the same functions, by the same back end
(``core.c_source``) and compiler flags as a model's kernel, so a warm run never enters
numba. ``on_engine(function)`` gives the function to call on the engine in force.
"""

from __future__ import annotations

import os
import threading
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ..errors import EngineWarning
from . import codegen
from .c_build import CBuildError, compiler_path, missing_compiler
from .c_build import shared_library_suffix as _suffix
from .c_engine import (
    CFunction,
    cached_library,
    current_engine,
    library_functions,
    sources_digest,
    translate_roots,
)
from .c_shipped import read_shipped, translation_key
from .jit import dispatcher_of

__all__ = ["COMMON", "SHIPPED_NAME", "SOURCES", "common_functions", "common_library_path",
           "common_translation_key", "on_engine", "translate_common"]

#: the functions the library carries: entry name -> (module, function name)
COMMON = {"eval_many": ("signals", "_eval_many"), "stroke": ("features", "_stroke"),
          "pressure_features": ("features", "_pressure_features"),
          "all_features": ("features", "all_features"),
          "motion_onset": ("features", "_motion_onset"), "breakaway": ("features", "_breakaway"),
          "sliding_speed": ("features", "_sliding_speed"),
          "presliding_travel": ("features", "_presliding_travel"),
          "loop_width_pressure": ("features", "_loop_width_pressure"),
          "loop_width_position": ("features", "_loop_width_position"),
          "loop_area": ("features", "_loop_area"),
          "turning_points": ("features", "_turning_points")}

#: the modules the library's functions come from
SOURCES = ("pneumact.core.signals", "pneumact.core.features")
#: the name its shipped translation goes by (``core.c_shipped``)
SHIPPED_NAME = "common"
#: numba function name -> its entry
_ENTRIES = {function: entry for entry, (_, function) in COMMON.items()}
#: what decides where the compiler and the cache are
_SETTINGS = ("CC", "PATH", "PNEUMACT_CACHE_DIR", "XDG_CACHE_HOME", "HOME")

_LOCK = threading.Lock()
_PLACES: dict[tuple[str | None, ...], tuple[str | None, str]] = {}
#: (compiler, cache folder) -> the library's functions
_LOADED: dict[tuple[str | None, str], dict[str, CFunction]] = {}
#: (compiler, cache folder) -> why ``auto`` could not build it (said once)
_REFUSED: dict[tuple[str | None, str], str] = {}


def _roots() -> dict[str, tuple[Callable, Sequence]]:
    from numba.core import types

    from . import features, signals

    f64, ivec, flag = types.float64[::1], types.int64[::1], types.boolean
    loop = (f64, f64)  # pressure, position
    argtypes = {"eval_many": (f64, ivec, types.int64, f64, f64, f64), "stroke": (f64,),
                "pressure_features": (f64, f64, f64, f64),
                "all_features": (f64, f64, f64, f64, flag, f64, f64, flag, f64),
                "motion_onset": (*loop, types.float64), "breakaway": loop,
                "sliding_speed": (f64, *loop), "presliding_travel": loop,
                "loop_width_pressure": loop, "loop_width_position": loop, "loop_area": loop,
                "turning_points": (f64,)}
    modules = {"signals": signals, "features": features}
    return {f"pa_{entry}": (getattr(modules[module], name), argtypes[entry])
            for entry, (module, name) in COMMON.items()}


def common_translation_key() -> str:
    """The key of the library's C (``c_shipped.translation_key`` over the sources of the
    signals and features and every pneumact file they import)."""
    return translation_key(SHIPPED_NAME, codegen.dependency_files(SOURCES))


def _translation() -> tuple[str, str]:
    """(C source, header) of the library: shipped with the package where its key
    matches, else translated."""
    shipped = read_shipped(SHIPPED_NAME, common_translation_key())
    return shipped if shipped is not None else translate_common()


def translate_common() -> tuple[str, str]:
    """(C source, header) of the library translated now, never the shipped one (what
    ``tools/ship_c.py`` ships, and what its test compares with)."""
    return translate_roots(_roots())


def common_library_path(compiler: str) -> Path:
    """Where the library built by ``compiler`` lives: named by the sources it is
    translated from (with everything ``sources_digest`` adds) and numba's version (the
    typed IR it translates)."""
    from importlib.metadata import version

    from . import features, signals

    digest = sources_digest(Path(signals.__file__), Path(features.__file__), Path(__file__),
                            compiler=compiler)
    return codegen.cache_dir() / f"pneumact_common-numba{version('numba')}-c{digest}{_suffix()}"


def _place(compiler: str | None = None) -> tuple[str | None, str]:
    """(compiler path, cache folder) as the environment names them now, found once per
    setting (a lookup on PATH per call would cost more than the call)."""
    setting = (compiler, *(os.environ.get(name) for name in _SETTINGS))
    place = _PLACES.get(setting)
    if place is None:
        place = _PLACES[setting] = (compiler_path(compiler), str(codegen.cache_dir()))
    return place


def common_functions(compiler: str | None = None) -> dict[str, CFunction]:
    """The library's functions by entry name (``COMMON``), built on first use. Raises
    ``CBuildError`` (no compiler, or it failed) or ``CSourceError`` (a construct the back
    end does not translate)."""
    place = _place(compiler)
    loaded = _LOADED.get(place)
    if loaded is not None:
        return loaded
    path = place[0]
    if path is None:
        raise CBuildError(missing_compiler(compiler))
    with _LOCK:
        loaded = _LOADED.get(place)
        if loaded is None:
            target = common_library_path(path)
            library, header = cached_library(target, path, _translation)
            loaded = _LOADED[place] = library_functions(library, header)
    return loaded


def on_engine(function: Any) -> Any:
    """``function`` (one of ``COMMON``'s numba functions) as the engine in force runs
    it: its C translation on ``c`` (which raises where it cannot be built) and on
    ``auto`` where a compiler builds it, numba's otherwise (``auto`` says why once, where
    the compiler is there but the build failed)."""
    engine = current_engine()
    if engine == "numba":
        return dispatcher_of(function)
    entry = _ENTRIES.get(getattr(getattr(function, "py_func", function), "__name__", ""))
    if entry is None:
        raise ValueError(f"{function!r} is not one of the functions the common library "
                         "carries")
    if engine == "c":
        return common_functions()[entry]
    return _auto(entry, function)


def _auto(entry: str, function: Any) -> Any:
    from .c_build import CSourceError

    place = _place()
    loaded = _LOADED.get(place)
    if loaded is not None:
        return loaded[entry]
    if place[0] is None or place in _REFUSED:  # no compiler: the model's kernel said so
        return dispatcher_of(function)
    try:
        return common_functions()[entry]
    except (CSourceError, CBuildError, OSError) as error:
        reason = str(error).strip().splitlines()[0]
        with _LOCK:
            _REFUSED[place] = reason
        warnings.warn(f"the C engine cannot build the signal and feature functions here "
                      f"({reason}); numba runs them", EngineWarning, stacklevel=3)
        return dispatcher_of(function)
