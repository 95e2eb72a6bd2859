"""The C engine: a model's kernel built as a shared library by the C back end.

The numba engine compiles each kernel function with LLVM the first time a machine meets a
model combination (about 15 s); the C back end (``core.c_source``) writes the same
functions as C99 from numba's typed IR, and a C compiler builds them in about a second.
``c_kernel`` gives a kernel that looks like the numba kernel module (its constants,
every function) but whose entry points — ``derive``, ``initial_state``,
``state_scales``, ``rhs``, ``jac``, ``outputs`` and the RODAS4 integrator — run in that
library, called with ctypes (which lets go of the GIL, so threads run rows at once).
Functions the library does not carry (the explicit integrator, sensitivities, friction
evaluation) are the numba kernel's.

The library is cached on disk beside the numba kernels, under the kernel's key (its
generated text, every source it depends on, the numba and Python versions) extended by
the C back end's own source, this module and the compiler: one build per machine and
model combination, safe when several processes build it at once (a lock, an atomic
rename). Which engine runs is chosen by ``engine`` arguments, else ``PNEUMACT_ENGINE``
(``auto``, ``c`` or ``numba``; default ``auto``: C where a compiler is found and the
back end translates the model, numba otherwise, with a warning saying why).
"""

from __future__ import annotations

import contextvars
import ctypes
import functools
import hashlib
import math
import os
import re
import tempfile
import threading
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from ..errors import ArgumentError, EngineWarning
from . import codegen
from .c_abi import Arena, array_struct
from .c_build import CBuildError, compile_library, compiler_path, missing_compiler
from .c_build import shared_library_suffix as _suffix
from .c_shipped import read_shipped, translation_key
from .compile_lock import announce_build, file_lock

__all__ = ["ENGINES", "ENGINE_VARIABLE", "CFunction", "CKernel", "EngineWarning", "Kernel",
           "build_ahead", "c_kernel", "cached_library", "check_engine", "current_engine",
           "engine_kernel", "engine_scope", "engine_setting", "kernel_translation_key",
           "library_functions", "library_path", "shipped_name", "sources_digest",
           "translate_kernel", "translate_roots"]

ENGINES = ("auto", "c", "numba")
ENGINE_VARIABLE = "PNEUMACT_ENGINE"
#: how the engine's libraries are compiled: no -ffast-math and ISO C (no contraction into
#: fused multiply-adds), so the arithmetic is numba's; no -march=native, so a cache shared by
#: machines with different CPUs stays valid (-O3: 1.02x numba's time per batch row, -O2 1.26x);
#: -fno-tree-vectorize as the FMU's (export/compiler.py: faster triangular solves)
FLAGS = ("-O3", "-fno-tree-vectorize", "-std=c99", "-fPIC", "-shared")
#: the functions the libraries carry: one library per group, built on the group's first use
GROUPS = {"run": ("derive", "initial_state", "state_scales", "rhs", "jac", "outputs",
                  "integrate_rodas4"),
          "sensitivities": ("integrate_rodas4_sens", "output_sensitivities"),
          "states": ("integrate_rodas4_states",)}
_GROUP_OF = {name: group for group, names in GROUPS.items() for name in names}
PREFIX = "pa_"

_LOCK = threading.RLock()
_KERNELS: dict[str, CKernel] = {}
_REFUSED: dict[tuple[str, str | None, str], str] = {}
#: library path -> why a ``build_ahead`` thread could not build it (raised once, then retried)
_FAILED_AHEAD: dict[str, Exception] = {}
#: (kernel spec, the settings below) ``build_ahead`` has looked at: once each per process
_LOOKED_AHEAD: set[tuple] = set()
_AHEAD_SETTINGS = ("CC", "PATH", "PNEUMACT_CACHE_DIR", "XDG_CACHE_HOME", "HOME")
#: the engine a call chose for everything it runs in this thread (None: the setting)
_SCOPE: ContextVar[str | None] = ContextVar("pneumact_engine", default=None)


def check_engine(engine: str | None, where: str = "engine") -> str:
    """``engine`` (None: the ``PNEUMACT_ENGINE`` setting) as one of ``ENGINES``."""
    if engine is None:
        return engine_setting()
    if not isinstance(engine, str) or engine not in ENGINES:
        raise ArgumentError(f"{where} = {engine!r}: must be one of {', '.join(ENGINES)}")
    return engine


def engine_setting() -> str:
    """The engine ``PNEUMACT_ENGINE`` names (``auto`` when unset)."""
    value = os.environ.get(ENGINE_VARIABLE, "auto").strip().lower() or "auto"
    if value not in ENGINES:
        raise ArgumentError(f"{ENGINE_VARIABLE} = {value!r}: must be one of "
                            f"{', '.join(ENGINES)}")
    return value


@contextmanager
def engine_scope(engine: str | None) -> Iterator[str]:
    """Run what the block runs in this thread on ``engine`` (None: as before); yields
    the engine in force."""
    token = _SCOPE.set(check_engine(engine)) if engine is not None else None
    try:
        yield current_engine()
    finally:
        if token is not None:
            _SCOPE.reset(token)


def current_engine() -> str:
    """The engine in force: the innermost ``engine_scope``, else ``PNEUMACT_ENGINE``."""
    return _SCOPE.get() or engine_setting()


# ------------------------------------------------------------------------ ctypes mirrors
#: the back end's array struct names -> (numpy dtype, ctypes element)
_ELEMENTS: dict[str, tuple[Any, Any]] = {
    "float64": (np.float64, ctypes.c_double), "int64": (np.int64, ctypes.c_int64),
    "bool": (np.bool_, ctypes.c_uint8)}
_SCALARS: dict[str, Any] = {"double": ctypes.c_double, "float": ctypes.c_float,
                            "int64_t": ctypes.c_int64, "int": ctypes.c_int}


def _array_converter(name: str, ctype: str) -> tuple[type, type, Callable[[Any], Any]]:
    """(the struct a result comes back as, the struct an argument goes as, the converter
    of an argument) for the C array type ``ctype``."""
    match = re.fullmatch(r"pa_arr_(\w+?)_(\d+)d", ctype)
    if match is None or match.group(1) not in _ELEMENTS:
        raise CBuildError(f"{name}: no ctypes mirror for the C type {ctype}")
    dtype, element = _ELEMENTS[match.group(1)]
    ndim = int(match.group(2))
    argument = _argument_struct(ndim)
    size = np.dtype(dtype).itemsize

    def convert(values: Any) -> ctypes.Structure:
        if not isinstance(values, np.ndarray) or values.dtype != dtype or values.ndim != ndim:
            raise TypeError(f"{name}: expected a {ndim}-d {np.dtype(dtype).name} array, got "
                            f"{getattr(values, 'dtype', type(values).__name__)} with "
                            f"{getattr(values, 'ndim', '?')} dimensions")
        return argument(values.ctypes.data, *values.shape,
                        *[s // size for s in values.strides])

    return array_struct(element, ndim), argument, convert


@functools.cache
def _argument_struct(ndim: int) -> type[ctypes.Structure]:
    """An array argument as the library reads it (the back end's struct: data, shape[ndim],
    strides[ndim] in elements), made of plain numbers: its data pointer as an address, each
    extent and stride a field of its own. The same memory layout as
    ``c_source.array_struct``'s typed pointer and arrays; a typed pointer from
    ``ndarray.ctypes.data_as`` and arrays filled from tuples cost 2-3 times as much per
    argument (a batch row on the C engine passes about 25) and the pointer left reference
    cycles for the garbage collector."""
    fields = [("data", ctypes.c_void_p),
              *((f"shape{k}", ctypes.c_int64) for k in range(ndim)),
              *((f"stride{k}", ctypes.c_int64) for k in range(ndim))]
    return type(f"ArrayArgument{ndim}", (ctypes.Structure,), {"_fields_": fields})


class CFunction:
    """One entry point of the library, called like the numba kernel function it was
    translated from (numpy arrays and numbers in, the same result out). Arrays are passed
    by reference: what the C function writes lands in them, as with numba."""

    def __init__(self, library: ctypes.CDLL, name: str, prototype: str):
        match = re.fullmatch(r"(\w+) (\w+)\((.*)\);", prototype.strip())
        if match is None:
            raise CBuildError(f"cannot read the prototype {prototype!r}")
        restype, symbol, params = match.groups()
        self.name = name
        self._function = getattr(library, symbol)
        self._free = library.pa_arena_free
        arguments = [p.strip().rsplit(" ", 1)[0] for p in params.split(",") if p.strip()]
        self._arena = bool(arguments) and arguments[0].startswith("pa_arena")
        if self._arena:
            arguments = arguments[1:]
        self._converters: list[Callable[[Any], Any]] = []
        argtypes: list[Any] = [ctypes.POINTER(Arena)] if self._arena else []
        for ctype in arguments:
            if ctype in _SCALARS:
                argtypes.append(_SCALARS[ctype])
                self._converters.append(_scalar)
            else:
                _, argument, convert = _array_converter(name, ctype)
                argtypes.append(argument)
                self._converters.append(convert)
        self._function.argtypes = argtypes
        self._result = self._result_reader(restype)

    def _result_reader(self, restype: str) -> Callable[[Any], Any]:
        if restype == "void":
            self._function.restype = None
            return lambda value: None
        if restype in _SCALARS:
            self._function.restype = _SCALARS[restype]
            return (lambda value: bool(value)) if restype == "int" else (lambda value: value)
        struct, _, _ = _array_converter(self.name, restype)
        self._function.restype = struct
        dtype, element = _ELEMENTS[restype.split("_")[2]]

        def copy_out(value: Any) -> np.ndarray:  # the array lives in the arena: copy it
            shape = tuple(value.shape)
            count = math.prod(shape)
            if tuple(value.strides) == _c_order(shape):  # one block: one copy
                address = ctypes.cast(value.data, ctypes.c_void_p).value
                return np.frombuffer((element * count).from_address(address) if count
                                     else b"", dtype).reshape(shape).copy()
            flat = np.ctypeslib.as_array(value.data, shape=(max(count, 1),))[:count]
            strides = tuple(s * np.dtype(dtype).itemsize for s in value.strides)
            return np.lib.stride_tricks.as_strided(flat, shape, strides).copy()

        return copy_out

    def __call__(self, *args: Any) -> Any:
        if len(args) != len(self._converters):
            raise TypeError(f"{self.name}() takes {len(self._converters)} arguments, "
                            f"{len(args)} given")
        converted = [convert(a) for convert, a in zip(self._converters, args, strict=True)]
        if not self._arena:
            return self._result(self._function(*converted))
        arena = Arena()
        try:
            value = self._function(ctypes.byref(arena), *converted)
            if arena.failed:
                raise MemoryError(f"{self.name}: the C engine could not allocate its work "
                                  "arrays")
            return self._result(value)
        finally:
            self._free(ctypes.byref(arena))

    def __repr__(self) -> str:
        return f"<C function {self.name}>"


def _scalar(value: Any) -> Any:
    return value


def _c_order(shape: tuple[int, ...]) -> tuple[int, ...]:
    """The strides, in elements, of a C-ordered array of ``shape``."""
    strides, step = [], 1
    for extent in reversed(shape):
        strides.append(step)
        step *= extent
    return tuple(reversed(strides))


class CKernel:
    """A kernel whose entry points run in C libraries: ``run``'s (everything a run needs)
    at once, ``sensitivities``' and ``states``' (the batch's integrator without derived
    outputs) on first use (a plain run does not wait for them);
    attributes no library carries (constants, other functions) are the numba kernel
    module's, as are a group's functions where the back end cannot translate them (with
    an ``EngineWarning``)."""

    engine = "c"

    def __init__(self, module: ModuleType, spec: codegen.KernelSpec, compiler: str):
        self._module = module
        self._spec = spec
        self._compiler = compiler
        self._groups: dict[str, Path | None] = {}
        self._load("run")  # raises: without it the C engine cannot run the model

    def _load(self, group: str) -> None:
        with _LOCK:
            if group in self._groups:
                return
            target = library_path(self._spec, self._compiler, group)
            library, header = cached_library(
                target, self._compiler, lambda: _translation(self._module, self._spec, group))
            for name, function in library_functions(library, header).items():
                if name in GROUPS[group]:
                    setattr(self, name, function)
            self._groups[group] = library

    @property
    def library_path(self) -> Path | None:
        """The library of the ``run`` group."""
        return self._groups.get("run")

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):  # not set yet (or a protocol lookup): not the module's
            raise AttributeError(name)
        group = _GROUP_OF.get(name)
        if group is not None and group not in self.__dict__.get("_groups", {group: None}):
            from .c_build import CSourceError

            try:
                self._load(group)
                return self.__dict__[name]
            except (CSourceError, CBuildError, OSError) as error:
                self._groups[group] = None
                reason = str(error).strip().splitlines()[0]
                warnings.warn(f"the C engine cannot run {group} of kernel {self._spec.label} "
                              f"here ({reason}); numba runs them", EngineWarning, stacklevel=2)
        return getattr(self._module, name)

    def __repr__(self) -> str:
        return f"<C kernel {self._module.__name__}>"


#: what a model's kernel is on either engine
Kernel = ModuleType | CKernel


# ------------------------------------------------------------------------------- building
def _roots(module: ModuleType, group: str) -> dict[str, tuple[Callable, Sequence]]:
    from numba.core import types

    f64, vector, matrix = types.float64, types.float64[::1], types.float64[:, ::1]
    indices, cube = types.int64[::1], types.float64[:, :, ::1]
    run = (f64, f64, vector, vector, vector, indices)
    integrate = (vector, vector, vector, indices, vector, vector, f64, vector, f64, f64,
                 types.int64, matrix, matrix, vector)
    directions = (indices, indices, vector)
    signatures = {
        "derive": (vector,), "initial_state": (f64, f64, vector, vector, indices, vector),
        "state_scales": (vector, vector), "rhs": (*run, vector), "jac": (*run, matrix),
        "outputs": (*run, vector), "integrate_rodas4": integrate,
        "integrate_rodas4_sens": (*integrate, *directions, types.boolean[::1], matrix, cube),
        "integrate_rodas4_states": (*integrate[:12], vector),
        "output_sensitivities": (vector, vector, matrix, cube, vector, vector, indices,
                                 *directions, cube)}
    return {PREFIX + name: (getattr(module, name), signatures[name]) for name in GROUPS[group]
            if getattr(module, name, None) is not None}  # a friction law alone has no integrator


def library_path(spec: codegen.KernelSpec, compiler: str, group: str = "run") -> Path:
    """Where the C library of ``spec``'s ``group`` built by ``compiler`` lives (its name
    carries the kernel's key extended by the C back end, this module, the compiler and
    its flags)."""
    key = hashlib.sha256(codegen.kernel_key(spec).encode()).hexdigest()
    digest = hashlib.sha256(f"{key} {sources_digest(compiler=compiler)}".encode())
    tail = "" if group == "run" else f"-{group}"
    return codegen.cache_dir() / f"{codegen.module_name(spec)}-c{digest.hexdigest()[:12]}" \
        f"{tail}{_suffix()}"


def kernel_translation_key(spec: codegen.KernelSpec, group: str = "run") -> str:
    """The key of the C of ``spec``'s library ``group`` (``c_shipped.translation_key``
    over the kernel's content key: the same on every machine)."""
    return translation_key(f"{codegen.content_key(spec)} {group}", ())


def shipped_name(spec: codegen.KernelSpec, group: str = "run") -> str:
    """The name a shipped translation of ``spec``'s library ``group`` goes by."""
    return f"{spec.label}-{group}"


def _translation(module: ModuleType, spec: codegen.KernelSpec, group: str) -> tuple[str, str]:
    """(C source, header) of ``spec``'s library ``group``: shipped with the package where
    its key matches, else translated (the groups of one kernel share their typing)."""
    shipped = _shipped_translation(spec, group)
    return shipped if shipped is not None else _translate_module(module, group)


def _shipped_translation(spec: codegen.KernelSpec, group: str) -> tuple[str, str] | None:
    return read_shipped(shipped_name(spec, group), kernel_translation_key(spec, group))


def translate_kernel(spec: codegen.KernelSpec, group: str = "run") -> tuple[str, str]:
    """(C source, header) of ``spec``'s library ``group`` translated now, never the
    shipped one (what ``tools/ship_c.py`` ships, and what its test compares with)."""
    return _translate_module(codegen.load(spec), group)


def _translate_module(module: ModuleType, group: str) -> tuple[str, str]:
    return translate_roots(_roots(module, group), module.__name__)


def translate_roots(roots: dict[str, tuple[Callable, Sequence]],
                    share: str | None = None) -> tuple[str, str]:
    """(C source, header) of the entry points ``roots`` (entry name -> (function, numba
    argument types)), translated by the back end (``share``: as in
    ``c_source.translate``)."""
    from .c_source import translate

    unit = translate(roots, share)
    return unit.source, unit.header


def _build(translation: tuple[str, str], target: Path, compiler: str) -> None:
    """Compile ``translation`` (C source, header) into ``target``, its header beside it
    (both atomically, the header first)."""
    source_text, header_text = translation
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".cbuild-") as tmp:
        source = Path(tmp) / "kernel.c"
        source.write_text(source_text, encoding="utf-8")
        built = Path(tmp) / f"kernel{_suffix()}"
        compile_library(compiler, [source], built, FLAGS)
        staged_header = Path(tmp) / "kernel.h"
        staged_header.write_text(header_text, encoding="utf-8")
        os.replace(staged_header, target.with_suffix(".h"))
        os.replace(built, target)


def cached_library(target: Path, compiler: str,
                   translation: Callable[[], tuple[str, str]]) -> tuple[Path, str]:
    """(library, header text) at ``target``: from the disk cache, else ``translation()``
    (its C source and header: shipped, or translated) built by ``compiler`` once per
    machine (several processes at once build it once)."""
    header = target.with_suffix(".h")
    if not (target.exists() and header.exists()):
        target.parent.mkdir(parents=True, exist_ok=True)
        with file_lock(target.with_name(f".{target.stem}.lock")):
            if not (target.exists() and header.exists()):
                announce_build()
                _build(translation(), target, compiler)
    return target, header.read_text(encoding="utf-8")


def library_functions(library: Path, header: str) -> dict[str, CFunction]:
    """The entry points of a built ``library`` (declared in its ``header``), by their
    names without the ``pa_`` prefix."""
    handle = ctypes.CDLL(str(library))
    prototypes = {m.group(1): line for line in header.splitlines()
                  if (m := re.match(rf"\w+ {PREFIX}(\w+)\(", line))}
    return {name: CFunction(handle, name, line) for name, line in prototypes.items()}


def sources_digest(*paths: Path, compiler: str) -> str:
    """A digest of the sources a library is translated from, the C back end, this module,
    the compiler (its path and date) and the flags: a library's cache name."""
    digest = hashlib.sha256()
    for path in (*paths, Path(__file__).with_name("c_source.py"), Path(__file__)):
        digest.update(path.read_bytes())
    digest.update(f"{compiler} {os.path.getmtime(compiler)} {FLAGS}".encode())
    return digest.hexdigest()[:12]


def c_kernel(spec: codegen.KernelSpec, compiler: str | None = None) -> CKernel:
    """The C kernel of ``spec``: its libraries loaded from the disk cache, else built
    (translated and compiled) once per machine. Raises ``CSourceError`` for a construct
    the back end does not translate, ``CBuildError`` when the compiler is missing or
    fails."""
    path = compiler_path(compiler)
    if path is None:
        raise CBuildError(missing_compiler(compiler))
    module = codegen.load(spec)
    key = str(library_path(spec, path))
    with _LOCK:
        kernel = _KERNELS.get(key)
        if kernel is None:
            failed = _FAILED_AHEAD.pop(key, None)
            if failed is not None:  # build_ahead tried: not twice
                raise failed
            kernel = _KERNELS[key] = CKernel(module, spec, path)
        return kernel


@contextmanager
def build_ahead(spec: codegen.KernelSpec) -> Iterator[None]:
    """Build ``spec``'s C kernel in a thread while the block runs, where the engine in
    force may run C, its run library is not on disk yet and its C is shipped
    (``core.c_shipped``): on a fresh install's first run its compiler then runs beside
    what the block builds (``check_drive``'s signal library), a second less to wait on
    two cores. Only shipped C: the thread then never imports numba (two threads
    importing it at once can see its modules half made). Joined when the block ends
    (not on Ctrl-C); a failure is raised by the next ``c_kernel`` of ``spec``
    (``engine_kernel`` warns or raises as usual), so nothing is built twice."""
    thread = None
    if current_engine() != "numba" and _first_look(spec):
        compiler = compiler_path()
        target = None if compiler is None else str(library_path(spec, compiler))
        if target is not None and not Path(target).exists() \
                and _shipped_translation(spec, "run") is not None:
            thread = threading.Thread(target=contextvars.copy_context().run,
                                      args=(_build_quietly, spec, target),
                                      name="pneumact-build-ahead", daemon=True)
            thread.start()
    try:
        yield
    except Exception:
        if thread is not None:
            thread.join()
        raise
    if thread is not None:
        thread.join()


def _first_look(spec: codegen.KernelSpec) -> bool:
    """Whether ``build_ahead`` sees ``spec`` for the first time where the compiler and the
    cache are as the environment names them now (a later ``build_ahead`` then costs
    ~13 us, not the ~0.5 ms of finding the compiler and the library)."""
    seen = (spec, *(os.environ.get(name) for name in _AHEAD_SETTINGS))
    with _LOCK:
        first = seen not in _LOOKED_AHEAD
        _LOOKED_AHEAD.add(seen)
    return first


def _build_quietly(spec: codegen.KernelSpec, key: str) -> None:
    """``c_kernel(spec)``, its error kept for the next ``c_kernel`` to raise."""
    try:
        c_kernel(spec)
    except Exception as error:  # raised where the run asks for the kernel
        with _LOCK:
            _FAILED_AHEAD[key] = error


def engine_kernel(spec: codegen.KernelSpec, engine: str) -> Kernel:
    """The kernel of ``spec`` on ``engine`` (``auto``: C when it can, else numba with an
    ``EngineWarning`` saying why, once per reason)."""
    engine = check_engine(engine)
    if engine == "numba":
        return codegen.load(spec)
    if engine == "c":
        return c_kernel(spec)
    from .c_build import CSourceError

    # the reason depends on the compiler and on what the cache holds
    refusal = (spec.label, os.environ.get("CC"), str(codegen.cache_dir()))
    reason = _REFUSED.get(refusal)
    if reason is None:
        try:
            return c_kernel(spec)
        except (CSourceError, CBuildError, OSError) as error:
            reason = _REFUSED[refusal] = str(error).strip().splitlines()[0]
            warnings.warn(f"the C engine cannot run kernel {spec.label} here ({reason}); the "
                          f"numba engine runs it (set {ENGINE_VARIABLE}=numba to silence this)",
                          EngineWarning, stacklevel=3)
    return codegen.load(spec)

