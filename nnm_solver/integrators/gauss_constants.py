"""The s-stage Gauss-Legendre method's constants: its Butcher tableau, the rotation of a linear mode by one step, and
the step-size dependent arrays of a model (``GaussConstants``, kept for reuse by ``constants``), which gauss.py's
stepping kernels and gauss_monodromy.py's sensitivity assembly read."""
from __future__ import annotations

import math
import threading
from functools import lru_cache

import numpy as np

from ..jit import jit as _jit, small_inverse
from .settings import KERNELS

__all__ = ["tableau", "rotation", "GaussConstants", "constants"]


@lru_cache(maxsize=None)
def tableau(s):
    """Butcher tableau (A (s, s), b (s,), c (s,)) of the s-stage Gauss-Legendre method (order 2s).

    c are the roots of the shifted Legendre polynomial of degree s on [0, 1]; A_lj = int_0^{c_l} L_j,
    b_j = int_0^1 L_j with L_j the Lagrange polynomials on c (collocation).
    """
    x, _ = np.polynomial.legendre.leggauss(s)
    c = 0.5 * (x + 1.0)
    A = np.empty((s, s))
    b = np.empty(s)
    for j in range(s):
        others = np.delete(c, j)
        L = np.poly1d(np.poly(others) / np.prod(c[j] - others))
        Li = np.polyint(L)
        b[j] = Li(1.0) - Li(0.0)
        A[:, j] = Li(c) - Li(0.0)
    return A, b, c


def rotation(y, s):
    """Angle (rad) by which one step of the s-stage Gauss method rotates a linear mode, y = h w.

    R(iy) = P(iy) / conj(P(iy)) with P the numerator of the (s, s) Pade approximant of exp:
    P(z) = sum_k (2s - k)! s! / ((2s)! k! (s - k)!) z^k; s = 1 is the trapezoidal rule (Newmark's
    average acceleration, 2 atan(y / 2)).
    """
    z = 1j * np.asarray(y, dtype=float)
    P = sum(math.factorial(2 * s - k) * math.factorial(s) / (math.factorial(2 * s) * math.factorial(k)
                                                              * math.factorial(s - k)) * z ** k for k in range(s + 1))
    return 2.0 * np.angle(P)


class GaussConstants:
    """The step-size dependent constants of one model and one h (s stages).

    C1, Cc (n, s): stage responses to q and v (Q_lin = C1 q + h Cc v per mode); F (n, s, s) = h^2 M^-1 Abar;
    G (s n_s, s n_s) the stage-deformation coupling; A_lin (n, 2, 2), E (n, 2, s), C (n, s, 2) the per-mode
    linear step of the sensitivities.
    """

    def __init__(self, omega2, Bq, h, s):
        A, b, c = (x.copy() for x in tableau(s))
        Abar = A @ A
        bbar = A.T @ b
        self.s, self.h = s, h
        self.b, self.bbar, self.c, self.Abar = b, bbar, c, Abar
        Bq = np.ascontiguousarray(Bq, dtype=float)
        ns, n = Bq.shape
        self.BB = (Bq[:, None, :] * Bq[None, :, :]).reshape(ns * ns, n)          # b_m b_m^T per mode
        (self.Minv, self.C1, self.Cc, self.F, self.G, self.C, self.A_lin,
         self.E) = _step_constants(np.asarray(omega2, dtype=float), Bq, float(h), Abar, b, bbar, c)


@_jit
def _step_constants(omega2, Bq, h, Abar, b, bbar, c):
    """GaussConstants' arrays in one compiled pass over the modes (numpy's batched 3 x 3 inverses and products took
    2-4 ms a step size on the aircraft, one per Newton iterate: each has its own period): per mode M = I + h^2 w^2
    Abar, Minv = M^-1 (jit.small_inverse), C1 = Minv 1, Cc = Minv c, F = h^2 Minv Abar, C = [C1, h Cc],
    A_lin = L - w^2 U C, E = U (I - w^2 F) with L = [[1, h], [0, 1]], U = [h^2 bbar; h b]; and G (s n_s, s n_s),
    G[(l, x), (j, y)] = sum_i F_i[l, j] Bq[x, i] Bq[y, i]."""
    n = omega2.shape[0]
    s = b.shape[0]
    ns = Bq.shape[0]
    Minv = np.empty((n, s, s))
    C1 = np.empty((n, s))
    Cc = np.empty((n, s))
    F = np.empty((n, s, s))
    C = np.empty((n, s, 2))
    A_lin = np.empty((n, 2, 2))
    E = np.empty((n, 2, s))
    M = np.empty((s, s))
    U = np.empty((2, s))
    for l in range(s):
        U[0, l] = h * h * bbar[l]
        U[1, l] = h * b[l]
    for i in range(n):
        hw = h * h * omega2[i]
        for a in range(s):
            for j in range(s):
                M[a, j] = hw * Abar[a, j] + (1.0 if a == j else 0.0)
        Mi = small_inverse(M)
        for a in range(s):
            acc1 = 0.0
            accc = 0.0
            for j in range(s):
                Minv[i, a, j] = Mi[a, j]
                acc1 += Mi[a, j]
                accc += Mi[a, j] * c[j]
            C1[i, a] = acc1
            Cc[i, a] = accc
            C[i, a, 0] = acc1
            C[i, a, 1] = h * accc
            for j in range(s):
                acc = 0.0
                for k in range(s):
                    acc += Mi[a, k] * Abar[k, j]
                F[i, a, j] = h * h * acc
        w2 = omega2[i]
        for t in range(2):
            for col in range(2):
                acc = 0.0
                for l in range(s):
                    acc += U[t, l] * C[i, l, col]
                A_lin[i, t, col] = (1.0 if t == col else 0.0) + (h if (t == 0 and col == 1) else 0.0) - w2 * acc
            for j in range(s):
                acc = 0.0
                for l in range(s):
                    acc += U[t, l] * ((1.0 if l == j else 0.0) - w2 * F[i, l, j])
                E[i, t, j] = acc
    G = np.zeros((s * ns, s * ns))
    for l in range(s):
        for j in range(s):
            for x in range(ns):
                for y in range(ns):
                    acc = 0.0
                    for i in range(n):
                        acc += F[i, l, j] * Bq[x, i] * Bq[y, i]
                    G[l * ns + x, j * ns + y] = acc
    return Minv, C1, Cc, F, G, C, A_lin, E


def constants(system, h, s):
    """GaussConstants of a ModalSystem for the step h (s) and s stages."""
    return _constants(system.omega2, system.Bq, h, s)


#: GaussConstants kept for reuse (KERNELS.gauss_constants_kept of them); the same objects are read only, so a reuse
#: gives the same numbers bit for bit
_recent = []                   # (omega2, Bq, h, s, GaussConstants), most recent first
_recent_lock = threading.Lock()


def _constants(omega2, Bq, h, s):
    """GaussConstants(omega2, Bq, h, s), the same object for the same arrays (identity) and h of a recent call."""
    h = float(h)
    with _recent_lock:
        for entry in _recent:
            if entry[0] is omega2 and entry[1] is Bq and entry[2] == h and entry[3] == s:
                return entry[4]
    k = GaussConstants(omega2, Bq, h, s)
    with _recent_lock:
        _recent.insert(0, (omega2, Bq, h, s, k))
        del _recent[KERNELS.gauss_constants_kept:]
    return k
