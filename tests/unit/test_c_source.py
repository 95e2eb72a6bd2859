"""The kernel generator's C back end (``core.c_source``): Python's semantics in C.

Functions in the numba subset the kernels use (integer floor division and modulo of
negative numbers, negative indices, tuples, loops, ``min``/``max``, ``math``) are
translated, compiled with the machine's C compiler and called through ctypes: each
returns what the compiled Python returns. A construct the back end does not translate is
refused naming it and the function.
"""

from __future__ import annotations

import ctypes
import math
import re
import shutil
import subprocess
from collections import namedtuple

import numpy as np
import pytest
from numba import njit
from numba.core import types

from pneumact.core.c_source import Arena, CSourceError, _Shadows, _translate, translate

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")


@njit
def _pair(a, b):
    return a // b, a % b


@njit
def integer_semantics(a, b):
    q, r = _pair(a, b)
    return q * 1000 + r


@njit
def float_semantics(x, y):
    return (x // y) + (x % y) * 10.0 + 2.0 ** y + abs(-x) + min(x, y) - max(x, y)


@njit
def last_and_sum(values):
    total = 0.0
    for i in range(values.shape[0]):
        total += values[i] * i
    return values[-1] + total + math.exp(-values[0])


@njit
def write_rows(out):
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            out[i, j] = i * 10 + j if i != j else -1.0


Bounds = namedtuple("Bounds", ["low", "high"])


@njit
def _bounds(x):
    return Bounds(x - 1.0, x + 3.0)


@njit
def rounding_and_records(x):
    """Python's round (half to even, an int) and a namedtuple built and read by name."""
    b = _bounds(x)
    return round(x) * 1000.0 + b.high - 2.0 * b.low


@njit
def _weighted(view):
    total = 1000.0 * view.shape[0]
    for i in range(view.shape[0]):
        total += view[i] * (i + 1)
    return total


@njit
def slices(values, a, b, c):
    """Python's slices of a 1-d array (bounds negative, past the end, None; steps both
    ways): each view's length and items, weighted so that order and length count."""
    return (_weighted(values[a:b]) + 1e4 * _weighted(values[:b]) + 1e8 * _weighted(values[a:])
            + 1e12 * _weighted(values[a:b:c]) + 1e16 * _weighted(values[::c]))


@njit
def raising(x):
    if x < 0:
        raise ValueError("negative")
    return x


F64 = types.float64
I64 = types.int64


def array(values: np.ndarray) -> ctypes.Structure:
    """The back end's array struct: data, shape[ndim], strides[ndim] (in elements)."""
    ndim = values.ndim

    class Array(ctypes.Structure):
        _fields_ = [("data", ctypes.POINTER(ctypes.c_double)),
                    ("shape", ctypes.c_int64 * ndim), ("strides", ctypes.c_int64 * ndim)]

    strides = [s // values.itemsize for s in values.strides]
    return Array(values.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                 (ctypes.c_int64 * ndim)(*values.shape), (ctypes.c_int64 * ndim)(*strides))


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    unit = translate({"c_integer": (integer_semantics, (I64, I64)),
                      "c_float": (float_semantics, (F64, F64)),
                      "c_last": (last_and_sum, (types.float64[::1],)),
                      "c_rows": (write_rows, (types.float64[:, ::1],)),
                      "c_rounding": (rounding_and_records, (F64,)),
                      "c_slices": (slices, (types.float64[::1], I64, I64, I64))})
    folder = tmp_path_factory.mktemp("c")
    (folder / "unit.c").write_text(unit.source)
    subprocess.run([CC, "-O2", "-std=c99", "-shared", "-fPIC", "-o", str(folder / "unit.so"),
                    str(folder / "unit.c"), "-lm"], check=True)
    lib = ctypes.CDLL(str(folder / "unit.so"))
    lib.c_integer.restype = ctypes.c_int64
    lib.c_float.restype = ctypes.c_double
    lib.c_last.restype = ctypes.c_double
    lib.c_rounding.restype = ctypes.c_double
    lib.c_slices.restype = ctypes.c_double
    return lib


@pytest.mark.parametrize(("a", "b"), [(7, 2), (-7, 2), (7, -2), (-7, -2), (6, 3), (0, 5)])
def test_integer_floor_division_and_modulo_are_python_s(library, a, b):
    assert library.c_integer(a, b) == integer_semantics(a, b)


@pytest.mark.parametrize(("x", "y"), [(7.5, 2.0), (-7.5, 2.0), (7.5, -2.0), (0.25, 3.0)])
def test_float_arithmetic_is_python_s(library, x, y):
    assert library.c_float(ctypes.c_double(x), ctypes.c_double(y)) == float_semantics(x, y)


@pytest.mark.parametrize("x", [0.5, 1.5, 2.5, -0.5, -1.5, 2.4999, 7.0, -3.75])
def test_round_and_namedtuples_are_python_s(library, x):
    assert library.c_rounding(ctypes.c_double(x)) == rounding_and_records(x)


def test_negative_indices_loops_and_math(library):
    values = np.array([0.5, -1.25, 3.0, 2.5])
    assert library.c_last(array(values)) == last_and_sum(values)


def test_slices_are_python_s(library):
    values = np.array([0.5, -1.25, 3.0, 2.5, 7.0])
    for a in range(-7, 8):
        for b in range(-7, 8):
            for c in (-3, -2, -1, 1, 2, 3):
                assert library.c_slices(array(values), a, b, c) == slices(values, a, b, c), \
                    (a, b, c)


def test_two_dimensional_arrays_are_row_major(library):
    c_out, py_out = np.zeros((3, 4)), np.zeros((3, 4))
    library.c_rows(array(c_out))
    write_rows(py_out)
    np.testing.assert_array_equal(c_out, py_out)


def test_an_untranslated_construct_is_refused_by_name():
    with pytest.raises(CSourceError, match=r"raising.*raise statement"):
        translate({"c_raising": (raising, (F64,))})


WEIGHTS = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])  # a global array: frozen, a constant
FLAGS_OF = (False, True, True)  # a global tuple indexed at run time


@njit
def _scaled_row(m, i, factor):
    row = m[i]  # a view: writing it writes m
    for j in range(row.shape[0]):
        row[j] *= factor
    return m


@njit
def allocating(values, extra):
    """np.empty/zeros/full, .copy(), row views, a global array and a global tuple indexed
    at run time, min of three, an optional argument decided by its type; returns a new
    array (in the caller's arena)."""
    n = values.shape[0]
    out = values.copy()
    grid = np.zeros((2, n))
    marks = np.full(n, 2.0)
    flags = np.zeros(n, dtype=np.bool_)
    work = np.empty(n)
    for j in range(n):
        grid[0, j] = values[j] * WEIGHTS[1, j % 3]
        grid[1, j] = min(values[j], marks[j], 1.5)
        flags[j] = FLAGS_OF[j % 3]
        work[j] = grid[1, j] + (1.0 if flags[j] else 0.0)
    _scaled_row(grid, 1, 10.0)
    for j in range(n):
        out[j] += grid[0, j] + grid[1, j] + work[j]
        if extra is not None:
            out[j] += extra
    return out


@njit
def ones(n):
    return np.ones(n)


def test_allocations_views_and_constants_are_python_s(tmp_path):
    arr1d = types.float64[::1]
    unit = translate({"c_allocating": (allocating, (arr1d, types.none))})
    assert "pa_arena *" in unit.header  # it allocates: the caller passes the arena
    (tmp_path / "unit.c").write_text(unit.source)
    subprocess.run([CC, "-O2", "-std=c99", "-shared", "-fPIC", "-o", str(tmp_path / "unit.so"),
                    str(tmp_path / "unit.c"), "-lm"], check=True)
    lib = ctypes.CDLL(str(tmp_path / "unit.so"))

    class Result(ctypes.Structure):
        _fields_ = [("data", ctypes.POINTER(ctypes.c_double)), ("shape", ctypes.c_int64 * 1),
                    ("strides", ctypes.c_int64 * 1)]

    lib.c_allocating.restype = Result
    values = np.array([0.5, -1.25, 3.0, 2.5, 1.0])
    arena = Arena()
    for _ in range(2):  # a reset arena is used again
        result = lib.c_allocating(ctypes.byref(arena), array(values))
        got = np.array(result.data[:values.size])
        assert result.shape[0] == values.size
        np.testing.assert_array_equal(got, allocating(values, None))
        lib.pa_arena_reset(ctypes.byref(arena))
    assert not arena.failed
    lib.pa_arena_free(ctypes.byref(arena))


def test_an_allocation_it_does_not_know_is_refused():
    with pytest.raises(CSourceError, match=r"ones.*a call of"):
        translate({"c_ones": (ones, (I64,))})


# -- typing without compiling ------------------------------------------------------------
# Functions no other test calls: numba has compiled none of them when the test starts.
@njit
def _twice(x):
    return 2.0 * x


@njit(inline="always")
def _inlined_step(x, k):
    return _twice(x) + k  # a call in an inlined function: in the inlined code


def _closing_over(callee):
    @njit
    def through_closure(x):
        return callee(x) - 1.0  # a compiled function in a closure cell
    return through_closure


_from_closure = _closing_over(_twice)


@njit
def typed_not_compiled(x, n):
    total = 0.0
    for k in range(n):
        total += _inlined_step(x, k)
    return total + _from_closure(x) + _pair(n, 3)[1]


def test_what_a_root_calls_is_typed_not_compiled(tmp_path):
    """numba types a call of a compiled function by compiling it; the translation types
    the functions a root calls with stand-ins instead: the root, the function it calls,
    one inlined into it, and one in a closure are left without a compiled overload, and
    the C still computes what numba does."""
    fresh = (typed_not_compiled, _inlined_step, _twice, _from_closure)
    assert [f.signatures for f in fresh] == [[]] * len(fresh)
    unit = translate({"c_typed": (typed_not_compiled, (F64, I64))})
    assert [f.signatures for f in fresh] == [[]] * len(fresh)
    (tmp_path / "unit.c").write_text(unit.source)
    subprocess.run([CC, "-O2", "-std=c99", "-shared", "-fPIC", "-o", str(tmp_path / "unit.so"),
                    str(tmp_path / "unit.c"), "-lm"], check=True)
    lib = ctypes.CDLL(str(tmp_path / "unit.so"))
    lib.c_typed.restype = ctypes.c_double
    for x, n in ((1.5, 4), (-0.25, 7), (3.0, 0)):
        assert lib.c_typed(ctypes.c_double(x), ctypes.c_int64(n)) == typed_not_compiled(x, n)


def _same_code(source: str) -> str:
    """``source`` without what numba numbers process-wide: the IR variable names in the C
    variables' names (``v12_name`` -> ``v12``) and the block labels (renumbered in order
    of appearance)."""
    source = re.sub(r"\bv(\d+)_\w+", r"v\1", source)
    labels: dict[str, int] = {}
    return re.sub(r"\bL(\d+)\b",
                  lambda m: f"L{labels.setdefault(m.group(1), len(labels))}", source)


@njit(inline="always")
def _inlined_pair(a, b):
    return _pair(a + 1, b)


@njit
def with_inlined(a, b):
    q, r = _inlined_pair(a, b)
    return q + _pair(q, b)[1] * 10 + r


def test_the_stand_ins_give_the_code_that_compiling_the_callees_gives():
    """The same C, function for function, whether the callees are typed by stand-ins or
    compiled by numba (what the back end did before the stand-ins: it compiles them, so
    the functions here are not those of the test before)."""
    roots = {"c_integer": (integer_semantics, (I64, I64)),
             "c_pair": (_pair, (I64, I64)),  # a root that another calls: one C function
             "c_inlined": (with_inlined, (I64, I64)),
             "c_last": (last_and_sum, (types.float64[::1],)),
             "c_allocating": (allocating, (types.float64[::1], types.none))}
    typed = _translate(roots, _Shadows(inline=True)).source  # numba inlines compiling
    compiled = _translate(roots, _Shadows(enabled=False)).source
    assert _same_code(typed) == _same_code(compiled)


def test_an_inline_function_is_one_c_function_that_computes_the_same(tmp_path):
    """The translation types an ``inline="always"`` function once and writes it as a C
    function of its own (numba's inlining would copy it, and type it, at every call):
    the C calls it and computes what the inlined C and numba compute."""
    roots = {"c_inlined": (with_inlined, (I64, I64))}
    called, inlined = translate(roots).source, _translate(roots, _Shadows(inline=True)).source
    assert re.search(r"\b\w*_inlined_pair\w*\(", called)
    assert not re.search(r"\b\w*_inlined_pair\w*\(", inlined)
    for name, source in (("called", called), ("inlined", inlined)):
        (tmp_path / f"{name}.c").write_text(source)
        subprocess.run([CC, "-O2", "-std=c99", "-shared", "-fPIC", "-o",
                        str(tmp_path / f"{name}.so"), str(tmp_path / f"{name}.c"), "-lm"],
                       check=True)
        lib = ctypes.CDLL(str(tmp_path / f"{name}.so"))
        lib.c_inlined.restype = ctypes.c_int64
        for a, b in ((7, 2), (-7, 3), (0, 5)):
            assert lib.c_inlined(ctypes.c_int64(a), ctypes.c_int64(b)) == with_inlined(a, b)


def test_translations_sharing_a_name_type_each_function_once_and_write_the_same_c(
        monkeypatch):
    """Two translations under one ``share`` name (one kernel's libraries and its FMU)
    type what they both call once; each writes the C it writes alone."""
    from pneumact.core import c_source

    typings: list[str] = []
    typed_ir = c_source._typed_ir
    monkeypatch.setattr(c_source, "_typed_ir", lambda f, args: (
        typings.append(f.__name__), typed_ir(f, args))[1])

    first = {"c_inlined": (with_inlined, (I64, I64))}
    second = {"c_pair": (_pair, (I64, I64)), "c_inlined": (with_inlined, (I64, I64))}
    alone = [_same_code(translate(roots).source) for roots in (first, second)]
    shared = [_same_code(translate(roots, share="test kernel").source)
              for roots in (first, second)]
    assert shared == alone
    typings.clear()
    translate(second, share="test kernel")
    assert typings == []  # nothing typed again
    translate(second)
    assert sorted(typings) == ["_inlined_pair", "_pair", "with_inlined"]
    for k in range(c_source.SHARED_KEPT):
        translate(first, share=f"other {k}")
    assert "test kernel" not in c_source._SHARED  # only the last few are kept
