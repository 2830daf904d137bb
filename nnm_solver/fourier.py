r"""Fourier series of periodic signals sampled uniformly over one period.

A periodic signal x(t) of period T (s), sampled at S instants t_j = j T / S (the sample at t = T,
a repeat of t = 0, excluded), is written

    x(t) = a_0 + sum_{k >= 1} Re(a_k exp(i k 2 pi t / T)),

with a_0 the mean and a_k complex vectors in the units of x.  |a_k| is the amplitude of harmonic
k.  These are the only Fourier helpers of the package: orbits, harmonic content and the viewer use
them.
"""
from __future__ import annotations

import numpy as np

__all__ = ["fourier_coefficients", "fourier_amplitudes", "resample_periodic"]


def fourier_coefficients(x, n):
    """Complex coefficients (n+1, ...) a_0..a_n of samples x (S, ...) uniform over one period.

    Harmonics above the Nyquist order S / 2 cannot be seen in S samples: their rows are zero.
    """
    x = np.asarray(x, dtype=float)
    n = int(n)
    if n < 0:
        raise ValueError(f"n (highest harmonic) must be >= 0, got {n}")
    S = len(x)
    X = np.fft.rfft(x, axis=0) / S
    X[1:] *= 2.0
    if X.shape[0] < n + 1:
        X = np.concatenate([X, np.zeros((n + 1 - X.shape[0],) + X.shape[1:], dtype=complex)])
    return X[: n + 1]


def fourier_amplitudes(x, n):
    """Amplitudes |a_k| (n+1, ...) of harmonics 0..n of samples x (S, ...) (units of x; k = 0: |mean|)."""
    return np.abs(fourier_coefficients(x, n))


def resample_periodic(X, samples):
    """Periodic samples X (N, ...) on a uniform grid -> (samples, ...) on another one, by Fourier
    interpolation (exact for signals with no harmonic above min(N, samples) / 2)."""
    X = np.asarray(X)
    N = len(X)
    samples = int(samples)
    if samples == N:
        return X
    F = np.fft.rfft(X, axis=0)
    m = samples // 2 + 1
    G = np.zeros((m,) + X.shape[1:], dtype=complex)
    k = min(m, len(F))
    G[:k] = F[:k]
    if samples % 2 == 0 and k == m and N > samples:
        G[-1] = G[-1].real  # the Nyquist term of a real signal
    if N % 2 == 0 and k == len(F) and samples > N:
        G[k - 1] *= 0.5     # split the old Nyquist term between +/- frequencies
    return np.fft.irfft(G, n=samples, axis=0) * (samples / N)
