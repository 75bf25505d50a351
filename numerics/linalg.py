"""Small dense linear algebra in a fixed operation order: the same bits on every machine.

numpy's ``@``, ``np.linalg`` and ``scipy.linalg`` call the BLAS/LAPACK kernel that OpenBLAS picks for the CPU
(``OPENBLAS_CORETYPE``) and use as many threads as it allows; each kernel orders and fuses its multiply-adds
its own way, so their last bits differ from machine to machine. That is harmless for a design, but a
parameter -> model constant or a stored loop margin must not depend on the machine (docs/campaigns.md,
"The same numbers everywhere"). These functions are plain loops compiled by numba without ``fastmath``: every
sum is taken in index order and no multiply-add is contracted, so the result depends only on the inputs.
They are meant for the model's small systems (tens of unknowns), not for speed.

Algorithms: Gaussian elimination with partial pivoting (Golub & Van Loan, *Matrix Computations*, 4th ed.,
Alg. 3.4.1), least squares by Householder QR (ibid., Alg. 5.3.2 and Sec. 5.3.3), the matrix exponential by a
truncated Taylor series with scaling and squaring (Moler & Van Loan, SIAM Review 45, 2003, Method 3).
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: Taylor terms of :func:`expm` after scaling to a 1-norm of at most ``EXPM_SCALED_NORM``: the remainder
#: ``EXPM_SCALED_NORM**(EXPM_TERMS + 1) / (EXPM_TERMS + 1)!`` is below 1e-30, far under double precision.
EXPM_TERMS = 18
EXPM_SCALED_NORM = 0.5


@numba.njit(cache=True)
def matmul(a, b):
    """``a @ b`` (both real or both complex), each entry summed in index order."""
    n, m = a.shape
    p = b.shape[1]
    out = np.zeros((n, p), dtype=a.dtype)
    for i in range(n):
        for j in range(p):
            acc = out[i, j]
            for k in range(m):
                acc += a[i, k] * b[k, j]
            out[i, j] = acc
    return out


@numba.njit(cache=True)
def solve(a, b):
    """``x`` with ``a x = b`` for a square ``a`` and a 2-D right-hand side ``b`` (both real or both complex), by
    :func:`_eliminate`. ``a`` and ``b`` are not modified.

    Raises
    ------
    ZeroDivisionError
        If ``a`` is singular to working precision (an exactly zero pivot).
    """
    x = b.copy()
    if not _eliminate(a.copy(), x):
        raise ZeroDivisionError("singular matrix")
    return x


@numba.njit(cache=True)
def inverse_into(m, out):
    """``m^-1`` into ``out`` (square, of ``m``'s size; ``m`` is overwritten), allocating nothing: :func:`solve`
    against the identity, the same operations in the same order, for the compiled loop (which also runs as a CUDA
    kernel, where nothing may be allocated or raised).

    Returns
    -------
    bool
        ``False`` if ``m`` is singular to working precision; ``out`` is then all NaN, so that whatever uses it
        turns non-finite and the loop's guard stops the run (instead of an exception the GPU cannot raise).
    """
    n = m.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = 1.0 if i == j else 0.0
    if _eliminate(m, out):
        return True
    for i in range(n):
        for j in range(n):
            out[i, j] = np.nan
    return False


@numba.njit(cache=True)
def _eliminate(m, x):
    """Solve ``m y = x`` in place: ``x`` becomes ``y``, ``m`` is overwritten. Gaussian elimination with partial
    pivoting (the largest modulus in the column; the first one on a tie). ``False`` (``x`` left part-way) if ``m``
    is singular to working precision (an exactly zero pivot)."""
    n = m.shape[0]
    for k in range(n):
        pivot_row = k
        largest = abs(m[k, k])
        for i in range(k + 1, n):
            if abs(m[i, k]) > largest:
                pivot_row, largest = i, abs(m[i, k])
        if largest == 0.0:
            return False
        if pivot_row != k:
            for j in range(n):
                m[k, j], m[pivot_row, j] = m[pivot_row, j], m[k, j]
            for j in range(x.shape[1]):
                x[k, j], x[pivot_row, j] = x[pivot_row, j], x[k, j]
        for i in range(k + 1, n):
            factor = m[i, k] / m[k, k]
            for j in range(k + 1, n):
                m[i, j] -= factor * m[k, j]
            for j in range(x.shape[1]):
                x[i, j] -= factor * x[k, j]
    for i in range(n - 1, -1, -1):
        for j in range(x.shape[1]):
            acc = x[i, j]
            for k in range(i + 1, n):
                acc -= m[i, k] * x[k, j]
            x[i, j] = acc / m[i, i]
    return True


@numba.njit(cache=True)
def _norm_1(a):
    """The 1-norm (largest absolute column sum)."""
    largest = 0.0
    for j in range(a.shape[1]):
        total = 0.0
        for i in range(a.shape[0]):
            total += abs(a[i, j])
        largest = max(largest, total)
    return largest


@numba.njit(cache=True)
def balance(a):
    """``(b, d)`` with ``b = D^-1 a D``, ``D = diag(d)`` a diagonal of powers of two chosen so that each row and
    column of ``b`` has a comparable norm (Parlett & Reinsch, Numer. Math. 13, 1969; LAPACK ``dgebal`` without
    permutations). Scaling by powers of two is exact, so ``b`` carries no rounding error; a badly scaled model
    matrix (entries from 1 to 1e12) gets a far smaller norm, hence fewer squarings in :func:`expm`."""
    n = a.shape[0]
    b = a.copy()
    d = np.ones(n)
    radix = 2.0
    converged = False
    while not converged:
        converged = True
        for i in range(n):
            column = 0.0
            row = 0.0
            for j in range(n):
                if j != i:
                    column += abs(b[j, i])
                    row += abs(b[i, j])
            if column == 0.0 or row == 0.0:
                continue
            total = column + row
            factor = 1.0
            while column < row / radix:
                factor *= radix
                column *= radix * radix
            while column > row * radix:
                factor /= radix
                column /= radix * radix
            if (column + row) / factor < 0.95 * total:
                converged = False
                d[i] *= factor
                for j in range(n):
                    b[i, j] /= factor
                    b[j, i] *= factor
    return b, d


@numba.njit(cache=True)
def expm(a):
    """The matrix exponential ``exp(a)`` of a real square matrix.

    Balanced first (:func:`balance`, exact), then scaling and squaring: ``b / 2^s`` with a 1-norm of at most
    :data:`EXPM_SCALED_NORM`, its exponential by :data:`EXPM_TERMS` Taylor terms (Horner form), then ``s``
    squarings, and the balancing undone (``exp(a) = D exp(b) D^-1``). Every scaling is by a power of two.
    """
    n = a.shape[0]
    b, d = balance(a)
    result = _expm_balanced(b)
    for i in range(n):
        for j in range(n):
            result[i, j] = result[i, j] * d[i] / d[j]
    return result


@numba.njit(cache=True)
def _expm_balanced(a):
    """:func:`expm`'s scaling and squaring with the Taylor series."""
    n = a.shape[0]
    norm = _norm_1(a)
    squarings = 0
    if norm > EXPM_SCALED_NORM:
        squarings = int(math.ceil(math.log2(norm / EXPM_SCALED_NORM)))
    scaled = a * (0.5 ** squarings)
    result = np.eye(n)
    for k in range(EXPM_TERMS, 0, -1):  # I + A/1 (I + A/2 (I + ... (I + A/N)))
        result = matmul(scaled, result) * (1.0 / k)
        for i in range(n):
            result[i, i] += 1.0
    for _ in range(squarings):
        result = matmul(result, result)
    return result


@numba.njit(cache=True)
def lstsq(a, y):
    """The least-squares solution ``x`` minimising ``|a x - y|_2`` for a tall ``a`` of full column rank.

    Householder QR of ``a`` applied to ``y``, then back substitution on ``R``. ``a`` and ``y`` (1-D) are not
    modified.
    """
    rows, cols = a.shape
    r = a.copy()
    b = y.copy()
    v = np.empty(rows)
    for k in range(cols):
        norm = 0.0
        for i in range(k, rows):
            norm += r[i, k] * r[i, k]
        norm = math.sqrt(norm)
        alpha = -norm if r[k, k] >= 0.0 else norm
        for i in range(k, rows):
            v[i] = r[i, k]
        v[k] -= alpha
        v_norm = 0.0
        for i in range(k, rows):
            v_norm += v[i] * v[i]
        if v_norm == 0.0:
            continue
        for j in range(k, cols):
            dot = 0.0
            for i in range(k, rows):
                dot += v[i] * r[i, j]
            factor = 2.0 * dot / v_norm
            for i in range(k, rows):
                r[i, j] -= factor * v[i]
        dot = 0.0
        for i in range(k, rows):
            dot += v[i] * b[i]
        factor = 2.0 * dot / v_norm
        for i in range(k, rows):
            b[i] -= factor * v[i]
    x = np.empty(cols)
    for i in range(cols - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, cols):
            acc -= r[i, j] * x[j]
        x[i] = acc / r[i, i]
    return x


@numba.njit(cache=True)
def state_space_response(a, b, c, d, points):
    """``C (pI - A)^-1 B + D`` of a single-input single-output system at each complex point ``p`` (``s`` or
    ``z``): one :func:`solve` per point."""
    n = a.shape[0]
    out = np.empty(points.shape[0], dtype=np.complex128)
    shifted = np.empty((n, n), dtype=np.complex128)
    rhs = np.empty((n, 1), dtype=np.complex128)
    for q in range(points.shape[0]):
        for i in range(n):
            for j in range(n):
                shifted[i, j] = -a[i, j]
            shifted[i, i] += points[q]
            rhs[i, 0] = b[i, 0]
        x = solve(shifted, rhs)
        acc = complex(d[0, 0])
        for i in range(n):
            acc += c[0, i] * x[i, 0]
        out[q] = acc
    return out
