"""The Fourier coefficients of a harmonic-balance orbit read from its basis coefficients, without sampling it.

A harmonic-balance orbit is q(theta) = sum_j A[j] c_j(theta) on an HBBasis (orbits/hb_basis.py: c_j = 1, cos(h_j
theta) or sin(h_j theta)).  In the convention of fourier.py, q = a_0 + sum_k Re(a_k e^(i k theta)), its coefficients
are a_0 = A[mean], a_k = A[cos k] - i A[sin k]: what ``fourier_coefficients`` returns for S >= 2 H + 1 samples of the
orbit (every harmonic of the basis is below S / 2), to round-off, and exactly 0 where the samples' transform has
round-off (the harmonics the basis has not).  O(N_b m) instead of the transform's O(S m log S) (the per-point
harmonic content of condensed harmonic balance, driver/candidate.py; issue 52).
"""
from __future__ import annotations

import numpy as np

__all__ = ["basis_fourier_coefficients"]


def basis_fourier_coefficients(basis, A, n):
    """Complex Fourier coefficients a_0..a_n (n + 1, m) of the orbit with coefficients A (N_b, m) on ``basis``
    (an HBBasis: orders h, sine flags); harmonics above n are left out."""
    A = np.asarray(A, dtype=float)
    c = np.zeros((int(n) + 1, A.shape[1]), dtype=complex)
    for j, (h, sine) in enumerate(zip(basis.h, basis.sine)):
        if h > n:
            continue
        if sine:
            c[h].imag -= A[j]
        else:
            c[h].real += A[j]
    return c
