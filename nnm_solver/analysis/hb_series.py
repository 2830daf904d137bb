"""What the per-point bookkeeping measures on a harmonic-balance orbit, from its basis coefficients, without sampling
it: its Fourier coefficients (the harmonic content) and its restoring-force ratio (the escape test).

A harmonic-balance orbit is q(theta) = sum_j A[j] c_j(theta) on an HBBasis (orbits/hb_basis.py: c_j = 1, cos(h_j
theta) or sin(h_j theta)).  In the convention of fourier.py, q = a_0 + sum_k Re(a_k e^(i k theta)), its coefficients
are a_0 = A[mean], a_k = A[cos k] - i A[sin k]: what ``fourier_coefficients`` returns for S >= 2 H + 1 samples of the
orbit (every harmonic of the basis is below S / 2), to round-off, and exactly 0 where the samples' transform has
round-off (the harmonics the basis has not).  O(N_b m) instead of the transform's O(S m log S); the restoring ratio
(``series_restoring_ratio``) in O(N_b^2 m) instead of O(S N_b m) (driver/candidate.py; issue 52).
"""
from __future__ import annotations

import numpy as np

__all__ = ["basis_fourier_coefficients", "basis_harmonic_amplitudes", "series_restoring_ratio"]


def basis_fourier_coefficients(basis, A, n):
    """Complex Fourier coefficients a_0..a_n (n + 1, m) of the orbit with coefficients A (N_b, m) on ``basis``
    (an HBBasis: orders h, sine flags); harmonics above n are left out."""
    A = np.asarray(A, dtype=float)
    c = np.zeros((int(n) + 1, A.shape[1]), dtype=complex)
    h, sine = np.asarray(basis.h), np.asarray(basis.sine, dtype=bool)
    cos_rows, sin_rows = np.flatnonzero(~sine & (h <= n)), np.flatnonzero(sine & (h <= n))
    c.real[h[cos_rows]] = A[cos_rows]           # (each harmonic has one cosine and at most one sine)
    if len(sin_rows):
        c.imag[h[sin_rows]] = -A[sin_rows]
    return c


def basis_harmonic_amplitudes(basis, A, n, r):
    """(amps, others) (n + 1,) each: |a_k| (the 2-norm over the modes of harmonic k's complex coefficients a_k,
    basis_fourier_coefficients) of the orbit with coefficients A (N_b, m) on ``basis``, over all modes and over the
    modes but r (0-based), for k = 0..n: the row sums of A^2 gathered by harmonic (|a_kj|^2 = A[cos k, j]^2 +
    A[sin k, j]^2), O(N_b m) without the (n + 1, m) complex array (np.linalg.norm's sums in another order: the same to
    round-off)."""
    A = np.asarray(A, dtype=float)
    sq = A * A
    rows = sq.sum(axis=1)
    sq[:, r] = 0.0                         # (not rows - sq[:, r]: that cancels where mode r dominates)
    rows_r = sq.sum(axis=1)
    h = np.asarray(basis.h)
    keep = h <= n
    hk, size = h[keep], int(n) + 1          # (bincount adds in the rows' order from zero: np.add.at's sums)
    return (np.sqrt(np.bincount(hk, weights=rows[keep], minlength=size)[:size]),
            np.sqrt(np.bincount(hk, weights=rows_r[keep], minlength=size)[:size]))


def series_restoring_ratio(system, basis, A, samples):
    """results/stops.restoring_ratio of the modal orbit q(theta_t) = sum_j A[j] c_j(theta_t) at ``samples``
    equispaced instants, from the coefficients A (N_b, m): the same r = max(|res| / |lin|, q . res / q . lin) with
    lin = Omega^2 q and res = lin + Bq^T g(Bq q), its smallest value over the samples of at least half the largest
    amplitude, with every m-long sum taken once on the coefficients (the Gram matrices A Omega^p A^T, N_b x N_b):
    O(N_b^2 m) instead of O(samples N_b m).  It agrees with the sampled form to round-off relative to |lin|^2 in
    r^2 (1e-12 in r at the escape threshold r = 1e-2)."""
    S = basis.functions(2 * np.pi * np.arange(samples) / samples)          # (samples, N_b)
    Bq, w2 = system.Bq, system.omega2
    Aw = A * w2                                                             # rows of Omega^2 q's coefficients
    quad = lambda G: np.einsum("ti,ij,tj->t", S, G, S)                      # noqa: E731  sample-wise S G S^T
    lin2, qlin, qq = quad(Aw @ Aw.T), quad(A @ Aw.T), quad(A @ A.T)
    d = S @ (A @ Bq.T)                                                      # element deformations (samples, n_d)
    g = system.force(d)
    lin_f = np.einsum("ti,is,ts->t", S, Aw @ Bq.T, g)                       # lin . Bq^T g
    ff = np.einsum("ts,su,tu->t", g, Bq @ Bq.T, g)                          # |Bq^T g|^2
    r = np.sqrt(np.maximum(lin2 + 2 * lin_f + ff, 0.0)) / np.maximum(np.sqrt(lin2), 1e-300)
    work = np.maximum(qlin + np.einsum("ts,ts->t", d, g), 0.0) / np.maximum(qlin, 1e-300)
    r = np.maximum(r, work)
    amp = np.sqrt(np.maximum(qq, 0.0))
    return float(np.min(r[amp >= 0.5 * np.max(amp)]))
