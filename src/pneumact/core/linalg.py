"""Dense LU with partial pivoting for the small (≤ 10 states) systems of the integrator.

LAPACK through ``np.linalg`` allocates and dispatches on every call, which costs more
than the factorisation itself at this size; these loops are compiled into the kernel.
"""

from .jit import njit


@njit(cache=True, inline="always")
def lu_factor(a, piv, n):  # pragma: no cover - compiled
    """In-place LU of a[:n, :n]; returns False if the matrix is singular. The diagonal
    of U is stored as its reciprocals, so that solving multiplies instead of divides."""
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
        inv = 1.0 / a[k, k]
        a[k, k] = inv
        for i in range(k + 1, n):
            a[i, k] *= inv
            f = a[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= f * a[k, j]
    return True


@njit(cache=True, inline="always")
def lu_det_sign(a, piv, n):  # pragma: no cover - compiled
    """Sign of the determinant of the matrix factored by ``lu_factor`` (+1 or −1)."""
    sign = 1.0
    for k in range(n):
        if piv[k] != k:
            sign = -sign
        if a[k, k] < 0.0:  # the reciprocal has the sign of U's diagonal entry
            sign = -sign
    return sign


@njit(cache=True, inline="always")
def lu_solve(a, piv, b, n):  # pragma: no cover - compiled
    """Solve in place with the factors of ``lu_factor``.

    A zero factor is skipped, as ``lu_factor`` skips a zero multiplier: subtracting its
    product changes nothing but the sign of a zero (and a NaN where b holds an infinity,
    which the caller finds non-finite in that entry anyway). The systems of the stiff
    friction laws are sparse (a GMS block's states couple only to the velocity), and each
    row of the back substitution waits for the row below it: the rows' dependency chains
    were most of a Co-Simulation step's time."""
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            f = a[i, j]
            if f != 0.0:
                s -= f * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            f = a[i, j]
            if f != 0.0:
                s -= f * b[j]
        b[i] = s * a[i, i]
