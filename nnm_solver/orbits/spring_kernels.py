"""Small compiled kernels of the spring laws for the per-point bookkeeping (issue 52): numba's integer power written
out (the condensed kernels' forces, condensed_kernels._forces) and the restoring-force bound of the escape test
(driver/candidate.restoring_lower_bound) in one pass over the modes per sample.  Models of springs only (the element
table of model/element_set.py); coupled elements take the numpy forms."""
from __future__ import annotations

import numpy as np

from ..jit import jit, numba
from ..model.laws import law_scalar

__all__ = ["int_power", "restoring_bound"]

if numba is not None:
    #: sums over the modes reassociated (vectorised), as condensed_kernels.py's
    jit_modes = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"reassoc", "contract"})
else:  # pragma: no cover
    jit_modes = jit


@jit
def int_power(x, e):
    """x ** e for an integer e, as numba computes ``float ** int`` (numba/cpython/numbers.py int_power: squaring, the
    same products in the same order, so the same number): model/laws.law_scalar's powers, in condensed_kernels._forces."""
    r = 1.0
    a = x
    invert = e < 0
    k = -e if invert else e
    if k > 0x10000:
        return x ** float(e)
    while k != 0:
        if k & 1:
            r *= a
        k >>= 1
        a *= a
    return 1.0 / r if invert else r


@jit_modes
def _sample_work(Q, t, Bq, omega2, powers, coeffs, kinks):
    """(q^T Omega^2 q, d . g(d)) of the modal sample q = Q[t] (d = Bq q): sums over the modes."""
    m = Q.shape[1]
    ns = Bq.shape[0]
    qlin = 0.0
    for k in range(m):
        qlin += omega2[k] * Q[t, k] * Q[t, k]
    work = 0.0
    for s in range(ns):
        d = 0.0
        for k in range(m):
            d += Bq[s, k] * Q[t, k]
        work += d * law_scalar(d, s, powers, coeffs, kinks)[0]
    return qlin, work


@jit
def restoring_bound(Q, Bq, omega2, powers, coeffs, kinks):
    """driver/candidate.restoring_lower_bound of the modal orbit Q (samples, m) for springs (the element table):
    min over the samples of 1 + d . g(d) / q^T Omega^2 q, 0 where some q^T Omega^2 q is not positive (NaN where a
    sample's is NaN), in one pass over the modes per sample (its numpy form's numbers to round-off)."""
    best = np.inf
    for t in range(Q.shape[0]):
        qlin, work = _sample_work(Q, t, Bq, omega2, powers, coeffs, kinks)
        if not qlin > 0.0:
            return 0.0
        v = 1.0 + work / qlin
        if v != v:
            return v
        if v < best:
            best = v
    return best
