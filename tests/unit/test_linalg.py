"""The integrator's dense LU (``core.linalg``): the solve skips zero factors (the speed of
the stiff friction laws' sparse systems, issue 39) and must give what the full
substitution gives, exactly; the FMU's compiler flags must not reorder arithmetic."""

from __future__ import annotations

import numpy as np
import pytest

from pneumact.core.c_engine import FLAGS as ENGINE_FLAGS
from pneumact.core.linalg import lu_det_sign, lu_factor, lu_solve
from pneumact.export.compiler import FLAGS


def full_substitution(a, piv, b):
    """``lu_solve`` as it was: every product subtracted, zero factors included (Python
    floats are the same IEEE doubles, in the same order)."""
    n = len(b)
    b = [float(v) for v in b]
    for k in range(n):
        p = int(piv[k])
        b[k], b[p] = b[p], b[k]
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= float(a[i, j]) * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= float(a[i, j]) * b[j]
        b[i] = s * float(a[i, i])
    return np.array(b)


def sparse_system(rng, n):
    """A GMS-like iteration matrix: a dominant diagonal, blocks coupled to one state (the
    velocity) only, a few other entries; scaled entries from 1e-6 to 1e6."""
    a = np.diag(rng.uniform(1.0, 10.0, n) * 10.0 ** rng.integers(-3, 4, n))
    v = int(rng.integers(0, n))
    for i in range(n):
        if i != v:
            a[i, v] = rng.normal() * 10.0 ** rng.integers(-3, 4)
            a[v, i] = rng.normal() * 10.0 ** rng.integers(-3, 4)
    for _ in range(n // 2):
        i, j = rng.integers(0, n, 2)
        a[i, j] = rng.normal() * 100.0  # may out-weigh the diagonal: pivoting
    return a


@pytest.mark.parametrize("n", [1, 3, 7, 10])
def test_skipping_zero_factors_is_the_full_substitution_exactly(n):
    rng = np.random.default_rng(39 + n)
    zero_factors = 0
    for _ in range(200):
        matrix = sparse_system(rng, n)
        lu = matrix.copy()
        piv = np.zeros(n, dtype=np.int64)
        assert lu_factor(lu, piv, n)
        assert lu_det_sign(lu, piv, n) == np.sign(np.linalg.det(matrix))
        zero_factors += int(np.sum(lu == 0.0))
        for b in (rng.normal(size=n), np.zeros(n), np.eye(n)[0]):
            x = b.copy()
            lu_solve(lu, piv, x, n)
            assert np.array_equal(x, full_substitution(lu, piv, b))  # bit for bit (±0 equal)
            scale = np.abs(matrix).sum(axis=1).max() * np.abs(x).max() + np.abs(b).max()
            assert np.abs(matrix @ x - b).max() <= 1e-12 * scale  # a backward-stable solve
    assert n < 3 or zero_factors > 0  # the skip was exercised


def test_a_dense_system_is_solved_too():
    rng = np.random.default_rng(6)
    matrix = rng.normal(size=(10, 10)) + 10.0 * np.eye(10)
    lu, piv, b = matrix.copy(), np.zeros(10, dtype=np.int64), rng.normal(size=10)
    assert lu_factor(lu, piv, 10)
    x = b.copy()
    lu_solve(lu, piv, x, 10)
    assert np.allclose(x, np.linalg.solve(matrix, b), rtol=1e-12, atol=0)


@pytest.mark.parametrize("flags", [FLAGS, ENGINE_FLAGS], ids=["fmu", "c engine"])
def test_the_c_flags_keep_the_arithmetic_of_the_compiled_kernels(flags):
    """The FMU's C integrator and the C engine are bit-equal to numba's only while no flag
    lets the C compiler reorder or contract floating-point operations (the vectoriser is
    off for speed; it never changes a result)."""
    reordering = ("-Ofast", "-ffast-math", "-funsafe-math-optimizations", "-fassociative-math",
                  "-ffp-contract=fast", "-freciprocal-math", "-fno-signed-zeros")
    assert not set(flags) & set(reordering)
    assert "-std=c99" in flags  # ISO C: no FMA contraction by default (gnu99 would allow it)
    assert "-fno-tree-vectorize" in flags
    assert not any(f.startswith("-march") for f in flags)  # a cache shared by other CPUs
