"""The linear algebra of the corrector: [J; row^T] stacked for LAPACK, and its Moore-Penrose solve factorised once
(QR with Householder reflectors kept, or LU for a square system), used by the engine's corrector, its tangent and
the fixed-parameter Newton."""
from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.linalg as sla
from scipy.linalg import lapack

from ..jit import jit, numba

__all__ = ["stacked", "LeastSquares", "all_finite"]

_GEQRF = _ORGQR = None
if numba is not None:
    try:   # numba's own LAPACK entry points (numba/np/linalg.py), as jit.py's: scipy's dgeqrf and dorgqr
        from numba.core import types as _types
        from numba.np.linalg import _LAPACK, ensure_lapack as _ensure_lapack

        _ensure_lapack()
        _GEQRF, _ORGQR = _LAPACK().numba_ez_geqrf(_types.float64), _LAPACK().numba_ez_xxgqr(_types.float64)
    except Exception:  # pragma: no cover - another numba version, or no scipy: scipy's functions below
        _GEQRF = _ORGQR = None

if _GEQRF is not None:
    @jit
    def _qr_explicit(A):
        """(Q (m, n), R (n, n)) of A (m >= n, Fortran-ordered; overwritten): LAPACK dgeqrf then dorgqr, the routines
        scipy.linalg.qr(mode="economic") calls (its numbers), without its wrappers' ~50 us a call."""
        m, n = A.shape
        tau = np.empty(n)
        if _GEQRF(ord("d"), m, n, A.ctypes, m, tau.ctypes) < 0:
            raise ValueError("dgeqrf was called with an invalid argument")
        R = np.zeros((n, n))
        for j in range(n):
            for i in range(j + 1):
                R[i, j] = A[i, j]
        if _ORGQR(ord("d"), m, n, n, A.ctypes, m, tau.ctypes) != 0:
            raise ValueError("dorgqr failed")
        return A, R

    @jit
    def _qr_solve(Q, R, b):
        """x = R^-1 (Q^T b) (b (m,)); NaN where R has a zero on its diagonal (an exactly singular A)."""
        m, n = Q.shape
        x = np.zeros(n)
        for j in range(n):
            if R[j, j] == 0.0:
                x[:] = np.nan
                return x
            acc = 0.0
            for i in range(m):
                acc += Q[i, j] * b[i]
            x[j] = acc
        for j in range(n - 1, -1, -1):
            x[j] /= R[j, j]
            xj = x[j]
            for i in range(j):
                x[i] -= xj * R[i, j]
        return x


#: the compiled R^-1 Q^T b on LeastSquares.compiled_qr's factors, for compiled callers (None without numba's LAPACK)
compiled_qr_solve = _qr_solve if _GEQRF is not None else None


def all_finite(x):
    """np.all(np.isfinite(x)), its answer: x . x is finite exactly when every x_i is, unless the
    squares overflow (|x_i| > 1e154), for which the elementwise test is taken (one dot product, ~1 us, against
    np.all's dispatch, ~4 us: the corrector asks at every iteration)."""
    if x.ndim == 1 and x.dtype == np.float64 and math.isfinite(float(x.dot(x))):
        return True
    return bool(np.isfinite(x).all())


def stacked(J, row):
    """[J; row^T] in Fortran order (what LAPACK's QR works on in place)."""
    A = np.empty((J.shape[0] + 1, J.shape[1]), order="F")
    A[:-1] = J
    A[-1] = row
    return A


class LeastSquares:
    """Moore-Penrose solve of A x = b for a full-column-rank A (m >= n), factorised once.  A is
    overwritten (pass a temporary, e.g. ``stacked(J, row)``).

    Over-determined A (m > n): QR, with Q kept as LAPACK's Householder reflectors and applied to each
    right-hand side (ormqr), which halves the cost of the factorisation compared with forming Q explicitly.
    Square A (e.g. quarter-period shooting, whose n equations in n + 1 unknowns have no redundant row): LU
    with partial pivoting, a third of the QR's work; the solution of a nonsingular square system is its
    Moore-Penrose solution."""

    #: below this many columns Q is formed explicitly (cheaper than a LAPACK call per solve)
    EXPLICIT_Q = 64

    def __init__(self, A):
        self.n = A.shape[1]
        self._lu = None
        if A.shape[0] == self.n and self.n >= self.EXPLICIT_Q:
            # An exactly singular A (e.g. a tongue jump's level-set guess on the aircraft) makes scipy warn
            # "LinAlgWarning: Diagonal number k is exactly zero. Singular matrix." and nothing else: the zero
            # pivot shows in rcond (0) and gives a non-finite Newton step, which the corrector reports as its
            # own failure (CorrectorFailure), and the caller tries another guess or a shorter step.  The
            # warning is harmless and told the user nothing, so it is not shown.
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sla.LinAlgWarning)
                self._lu = sla.lu_factor(A, overwrite_a=True, check_finite=False)
            return
        if self.n < self.EXPLICIT_Q and _GEQRF is not None and A.flags.f_contiguous and A.dtype == float:
            self._Q, self.R = _qr_explicit(A)
        elif self.n < self.EXPLICIT_Q:
            self._Q, self.R = sla.qr(A, mode="economic", check_finite=False)
        else:
            self._Q = None
            (self._h, self._tau), self.R = sla.qr(A, mode="raw", overwrite_a=True, check_finite=False)

    @property
    def compiled_qr(self):
        """(Q, R) where ``solve`` is the compiled R^-1 Q^T b (``_qr_solve``, which compiled callers may run on them:
        the same numbers), else None."""
        return (self._Q, self.R) if _GEQRF is not None and self._lu is None and self._Q is not None else None

    @property
    def rcond(self):
        """min |d_i| / max |d_i| of the triangular factor's diagonal (R, or U of the LU): a cheap conditioning
        indicator, made when read (the corrector does not read it)."""
        d = np.abs(np.diag(self._lu[0] if self._lu is not None else self.R))
        return d.min() / max(d.max(), 1e-300)

    def solve(self, b):
        """x of A x = b (least squares for m > n).  An exactly singular A gives a non-finite x, as LU does (the
        triangular solve's LinAlgError at a zero pivot is not raised): the corrector reports it as its own failure
        (a singular corrector system) and the continuation halves its step (mode 20 of the aircraft with 13
        condensed harmonics met one on its way into a tongue, 2026-12-07)."""
        if self._lu is not None:
            return sla.lu_solve(self._lu, b, check_finite=False)
        if self._Q is not None:
            if _GEQRF is not None and (b.ndim if isinstance(b, np.ndarray) else np.ndim(b)) == 1:
                return _qr_solve(self._Q, self.R, np.asarray(b, dtype=float))
            return self._triangular(self._Q.T @ b)
        c, _, info = lapack.dormqr("L", "T", self._h, self._tau, np.asarray(b, dtype=float).reshape(len(b), -1),
                                   lwork=64 * max(1, np.ndim(b) and (1 if np.ndim(b) == 1 else np.shape(b)[1])))
        if info != 0:
            raise np.linalg.LinAlgError(f"ormqr failed (info {info})")
        x = self._triangular(c[:self.n])
        return x[:, 0] if np.ndim(b) == 1 else x

    def _triangular(self, c):
        if not np.all(np.diag(self.R)):
            return np.full(np.shape(c), np.nan)
        return sla.solve_triangular(self.R, c, check_finite=False)
