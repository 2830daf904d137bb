"""numba's njit for the time-stepping kernels, or the plain function when numba is absent.

Compiled kernels are cached on disk (``cache=True``) and release the GIL (``nogil``), so a branch
computed in a background thread does not block a GUI.  Small kernels called from other kernels
(the element force laws) are compiled once as functions of their own and inlined by LLVM; numba's
IR-level inlining (``inline="always"``) retyped them in every caller and cost compile time for
nothing.  numba keys its cache on each function's own source file: after editing laws.py during
development, touch newmark.py and gauss.py (or delete the ``*.nbi``/``*.nbc`` files in
``__pycache__``) so that their callers are recompiled.

Compile time (the first run after installing compiles everything, issue 32): numba's
``np.linalg.solve`` costs 6-8 s of compilation per argument type (its generic checks and
copies), ``np.linalg.inv`` 1.5 s.  ``lapack_solve``, ``lapack_solve_many`` and ``lapack_inv``
call the very LAPACK routines numba's versions call (``numba_xgesv``, ``numba_xxgetrf``,
``numba_ez_xxgetri``: scipy's LAPACK) on the same Fortran-ordered copies, with the same errors,
so the results are bit-identical; they compile in a fraction of a second.
"""
from __future__ import annotations

import numpy as np

try:
    import numba

    jit = numba.njit(cache=True, nogil=True)
    #: small kernels called from other kernels (kept as a name: LLVM inlines them)
    jit_inline = jit
except ImportError:  # pragma: no cover - the same source runs uncompiled
    numba = None

    def jit(f):
        return f

    jit_inline = jit

_LAPACK_ROUTINES = _BLAS_ROUTINES = None
if numba is not None:
    try:   # numba's own LAPACK entry points (numba/np/linalg.py): called by symbol name, so cacheable
        from numba.core import types as _types
        from numba.np.linalg import F_INT_nptype as _F_INT, _LAPACK, ensure_lapack as _ensure_lapack

        _ensure_lapack()
        _LAPACK_ROUTINES = (_LAPACK().numba_xgesv(_types.float64), _LAPACK().numba_xxgetrf(_types.float64),
                            _LAPACK().numba_ez_xxgetri(_types.float64))
        _c, _p, _v = _types.char, _types.intp, _types.voidptr     # numba's BLAS wrappers (numba/np/linalg.py)
        _BLAS_ROUTINES = (
            _types.ExternalFunction("numba_xxgemm", _types.intc(_c, _c, _c, _p, _p, _p, _v, _v, _p, _v, _p, _v, _v, _p)),
            _types.ExternalFunction("numba_xxgemv", _types.intc(_c, _c, _p, _p, _v, _v, _p, _v, _v, _v)),
            _types.ExternalFunction("numba_xxdot", _types.intc(_c, _c, _p, _v, _v, _v)))
    except Exception:  # pragma: no cover - another numba version, or no scipy: numpy's functions below
        _LAPACK_ROUTINES = _BLAS_ROUTINES = None

if _LAPACK_ROUTINES is not None:
    _xgesv, _xxgetrf, _xxgetri = _LAPACK_ROUTINES
    _KIND = ord("d")

    @jit
    def _check_finite1(a):
        for i in range(a.shape[0]):
            if not np.isfinite(a[i]):
                raise np.linalg.LinAlgError("Array must not contain infs or NaNs.")

    @jit
    def _check_finite2(a):
        for i in range(a.shape[0]):
            for j in range(a.shape[1]):
                if not np.isfinite(a[i, j]):
                    raise np.linalg.LinAlgError("Array must not contain infs or NaNs.")

    @jit
    def _fortran_copy(A):
        """A (n, n) copied in Fortran order, as a C array of A.T (what numba's linalg passes to LAPACK)."""
        n = A.shape[0]
        out = np.empty((n, n))
        for i in range(n):
            for j in range(n):
                out[j, i] = A[i, j]
        return out

    @jit
    def _lapack_error(r):
        if r > 0:
            raise np.linalg.LinAlgError("Matrix is singular to machine precision.")
        if r < 0:
            raise ValueError("LAPACK was called with an invalid argument")

    @jit
    def lapack_solve(A, b):
        """np.linalg.solve(A, b) for a square float64 A (n, n) and b (n,): LAPACK dgesv, as numba's."""
        n = A.shape[0]
        _check_finite2(A)
        _check_finite1(b)
        if b.shape[0] != n or A.shape[1] != n:
            raise np.linalg.LinAlgError("Incompatible array sizes, system is not dimensionally valid.")
        acpy = _fortran_copy(A)
        x = b.copy()
        if n == 0:
            return x
        ipiv = np.empty(n, dtype=_F_INT)
        _lapack_error(_xgesv(_KIND, n, 1, acpy.ctypes, n, ipiv.ctypes, x.ctypes, n))
        return x

    @jit
    def lapack_solve_many(A, B):
        """np.linalg.solve(A, B) for A (n, n) and B (n, k): LAPACK dgesv; the result is Fortran-ordered, as
        numba's."""
        n = A.shape[0]
        k = B.shape[1]
        _check_finite2(A)
        _check_finite2(B)
        if B.shape[0] != n or A.shape[1] != n:
            raise np.linalg.LinAlgError("Incompatible array sizes, system is not dimensionally valid.")
        acpy = _fortran_copy(A)
        xt = np.empty((k, n))
        for i in range(n):
            for c in range(k):
                xt[c, i] = B[i, c]
        if n == 0:
            return xt.T
        ipiv = np.empty(n, dtype=_F_INT)
        _lapack_error(_xgesv(_KIND, n, k, acpy.ctypes, n, ipiv.ctypes, xt.ctypes, n))
        return xt.T

    @jit
    def lapack_inv(A):
        """np.linalg.inv(A) for a square float64 A: LAPACK dgetrf + dgetri, as numba's (Fortran-ordered)."""
        n = A.shape[0]
        if A.shape[1] != n:
            raise np.linalg.LinAlgError("Last 2 dimensions of the array must be square.")
        _check_finite2(A)
        acpy = _fortran_copy(A)
        if n == 0:
            return acpy.T
        ipiv = np.empty(n, dtype=_F_INT)
        _lapack_error(_xxgetrf(_KIND, n, n, acpy.ctypes, n, ipiv.ctypes))
        _lapack_error(_xxgetri(_KIND, n, acpy.ctypes, n, ipiv.ctypes))
        return acpy.T
else:
    @jit
    def lapack_solve(A, b):
        return np.linalg.solve(A, b)

    @jit
    def lapack_solve_many(A, B):
        return np.linalg.solve(A, B)

    @jit
    def lapack_inv(A):
        return np.linalg.inv(A)


if _LAPACK_ROUTINES is not None and _BLAS_ROUTINES is not None:
    _xxgemm, _xxgemv, _xxdot = _BLAS_ROUTINES
    _TRANS, _NOTRANS = ord("t"), ord("n")

    @jit
    def _blas_error(r):
        if r != 0:
            raise ValueError("BLAS wrapper returned with an error")

    @jit
    def matvec(A, x):
        """A @ x for a C-contiguous float64 A (m, n) and x (n,): BLAS dgemv, called as numba's ``@`` calls it."""
        m, n = A.shape
        if x.shape[0] != n:
            raise ValueError("incompatible array sizes for np.dot(a, b) (matrix * vector)")
        if n == 0 or m == 0:
            return np.zeros(m)
        out = np.empty(m)
        one = np.ones(1)
        zero = np.zeros(1)
        _blas_error(_xxgemv(_KIND, _TRANS, n, m, one.ctypes, A.ctypes, n, x.ctypes, zero.ctypes, out.ctypes))
        return out

    @jit
    def matmul_t(A, B):
        """A @ B.T for C-contiguous float64 A (m, k) and B (n, k): what numba's ``@`` calls for these layouts
        (BLAS ddot, dgemv or dgemm by the shapes, with the same arguments)."""
        m, k = A.shape
        n = B.shape[0]
        if B.shape[1] != k:
            raise ValueError("incompatible array sizes for np.dot(a, b) (matrix * matrix)")
        out = np.empty((m, n))
        if k == 0 or m == 0 or n == 0:
            out[:, :] = 0.0
            return out
        one = np.ones(1)
        zero = np.zeros(1)
        if n == 1:
            if m == 1:                                   # vector . vector
                _blas_error(_xxdot(_KIND, 0, k, A.ctypes, B.ctypes, out.ctypes))
            else:                                        # matrix * vector (B.T a column)
                _blas_error(_xxgemv(_KIND, _TRANS, k, m, one.ctypes, A.ctypes, k, B.ctypes, zero.ctypes,
                                    out.ctypes))
        elif m == 1:                                     # vector * matrix
            _blas_error(_xxgemv(_KIND, _TRANS, k, n, one.ctypes, B.ctypes, k, A.ctypes, zero.ctypes, out.ctypes))
        else:
            _blas_error(_xxgemm(_KIND, _TRANS, _NOTRANS, n, m, k, one.ctypes, B.ctypes, k, A.ctypes, k,
                                zero.ctypes, out.ctypes, n))
        return out
else:
    @jit
    def matvec(A, x):
        return A @ x

    @jit
    def matmul_t(A, B):
        return A @ B.T


_GEEV = None
if _LAPACK_ROUTINES is not None:
    try:   # numba's dgeev entry point (as its np.linalg.eigvals calls it)
        _GEEV = _LAPACK().numba_ez_rgeev(_types.float64)
    except Exception:  # pragma: no cover - another numba version
        _GEEV = None

if _GEEV is not None:
    _NOVECTORS = ord("N")

    @jit
    def _geev_values(A):
        """(wr, wi, info) of LAPACK dgeev on a real square A, no eigenvectors (numba's np.linalg.eigvals, without its
        refusal of complex eigenvalues for real input)."""
        n = A.shape[0]
        acpy = _fortran_copy(A)
        wr = np.empty(n)
        wi = np.empty(n)
        vl = np.empty(1)
        vr = np.empty(1)
        info = 0
        if n > 0:
            info = _GEEV(_KIND, _NOVECTORS, _NOVECTORS, n, acpy.ctypes, n, wr.ctypes, wi.ctypes, vl.ctypes, 1,
                         vr.ctypes, 1)
        # (the copies used after the call: alive until LAPACK has returned)
        info += 0 * (acpy.shape[0] + vl.shape[0] + vr.shape[0])
        return wr, wi, info


def eigvals_nogil(A):
    """Eigenvalues (complex (n,)) of a real square float64 matrix A by LAPACK dgeev, called from compiled code that
    releases the GIL: a worker thread's eigenproblem then runs beside the main thread (numpy 1.26's eigvals holds the
    GIL; issue 52).  None where numba's LAPACK is not available (the caller uses numpy); NaN when dgeev does not
    converge (numpy raises LinAlgError there)."""
    if _GEEV is None:
        return None
    wr, wi, info = _geev_values(np.ascontiguousarray(A, dtype=float))
    if info != 0:
        return np.full(A.shape[0], np.nan, dtype=complex)
    return wr + 1j * wi


@jit
def small_inverse(A):
    """A^-1 of a small square matrix (a few rows: a Gauss step's s x s stage matrix, the Volterra recursion's s n_s
    block) by Gauss-Jordan elimination with partial pivoting, inside compiled kernels (no LAPACK call: its overhead
    exceeds the work at these sizes).  A is not modified; a zero pivot gives inf/NaN entries."""
    m = A.shape[0]
    W = np.zeros((m, 2 * m))
    for a in range(m):
        for b in range(m):
            W[a, b] = A[a, b]
        W[a, m + a] = 1.0
    for c in range(m):
        piv = c
        for a in range(c + 1, m):
            if abs(W[a, c]) > abs(W[piv, c]):
                piv = a
        if piv != c:
            for b in range(2 * m):
                t = W[c, b]
                W[c, b] = W[piv, b]
                W[piv, b] = t
        d = 1.0 / W[c, c]
        for b in range(2 * m):
            W[c, b] *= d
        for a in range(m):
            if a != c:
                f = W[a, c]
                if f != 0.0:
                    for b in range(2 * m):
                        W[a, b] -= f * W[c, b]
    return W[:, m:].copy()
