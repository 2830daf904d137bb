r"""The harmonic basis of harmonic balance and its time sampling (AFT), shared by the HB equations
(``harmonic_balance.py``) and Hill's method (``hill.py``).

A periodic orbit of angular frequency omega is x(t) = sum_j A[j] c_j(theta), theta = omega t, with
c_j = cos(h_j theta) or sin(h_j theta):

* ``"odd"``: cosines of the odd harmonics 1, 3, ..., <= H (the symmetric NNMs of odd springs);
* ``"full"``: the mean and cosines and sines of 1..H (general periodic orbits).

E (N, N_b) samples the basis at N equispaced instants of one period; P (N_b, N) is its projector
(Galerkin weights 1/N for the mean, 2/N otherwise), so P E = I.
"""
from __future__ import annotations

import numpy as np

__all__ = ["BASES", "HBBasis", "harmonics_in"]

BASES = ("odd", "full")


class HBBasis:
    """Harmonic basis and its time sampling: orders h (N_b,), sine (N_b,) bool, E (N, N_b), P (N_b, N)."""

    def __init__(self, harmonics, kind="odd", samples=None):
        H = int(harmonics)
        if kind == "odd":
            self.h = np.arange(1, H + 1, 2)
            self.sine = np.zeros(len(self.h), dtype=bool)
        else:
            self.h = np.concatenate([[0], np.repeat(np.arange(1, H + 1), 2)])
            self.sine = np.concatenate([[False], np.tile([False, True], H)])
        self.kind = kind
        self.harmonics = H
        self.samples = int(samples) if samples is not None else 4 * H + 4
        theta = 2.0 * np.pi * np.arange(self.samples) / self.samples
        self.E = self.functions(theta)
        w = np.where(self.h == 0, 1.0, 2.0) / self.samples
        self.P = self.E.T * w[:, None]
        #: c_j(0) and d c_j / d theta (0) (N_b,): the state at t = 0 (the orbit's initial state, its energy),
        #: asked for at every corrector step, so evaluated once
        self.at_zero = self.functions([0.0])[0]
        self.slope_at_zero = self.derivatives([0.0])[0]

    def __len__(self):
        return len(self.h)

    def state_at_zero(self):
        """(c_j(0), d c_j / d theta (0)) (N_b,) each: the cached ones, or computed for a basis built without them."""
        c0 = getattr(self, "at_zero", None)
        if c0 is None:
            return self.functions([0.0])[0], self.derivatives([0.0])[0]
        return c0, self.slope_at_zero

    def galerkin(self, g_prime):
        """The Galerkin blocks C (n_s, N_b, N_b) of the stiffnesses g_prime (N, n_s) sampled at this basis's
        instants: C_s = P diag(g_prime[:, s]) E, i.e. C_s[j, l] = the coefficient on c_j of g'_s(t) c_l(t) (the
        springs' part of the HB Jacobian and of Hill's matrix; N/m, per spring)."""
        # a batched product: 2-4x faster than the einsum on small bases (2.2x at 7 odd harmonics); it rounds
        # differently, by ~1e-16 (the 2-DOF benchmark's skip-mode labels past its 5:1 tongue once turned on that,
        # before the skeleton's guide)
        return (self.P[None] * np.asarray(g_prime).T[:, None]) @ self.E

    def galerkin_matrix(self, K):
        """The Galerkin matrix (N_b n, N_b n) of modal stiffnesses K (N, n, n) sampled at this basis's instants:
        block [j, l] = sum_k P[j, k] K_k E[k, l], rows (j, i), columns (l, m) (the coupled elements' part of the HB
        Jacobian and of Hill's matrix, whose stiffness is not diagonal on the deformations)."""
        K = np.asarray(K)
        nb, n = len(self.h), K.shape[-1]
        G = self.P.T[:, :, None] * self.E[:, None, :]                        # (N, N_b, N_b): P[j, k] E[k, l]
        return np.tensordot(G, K, axes=(0, 0)).transpose(0, 2, 1, 3).reshape(nb * n, nb * n)

    def functions(self, theta):
        """c_j(theta) (len(theta), N_b)."""
        ht = np.outer(np.asarray(theta, dtype=float), self.h)
        return np.where(self.sine, np.sin(ht), np.cos(ht))

    def derivatives(self, theta):
        """d c_j / d theta (len(theta), N_b)."""
        ht = np.outer(np.asarray(theta, dtype=float), self.h)
        return np.where(self.sine, np.cos(ht), -np.sin(ht)) * self.h


def harmonics_in(basis, source_basis, A):
    """The rows of coefficients A (on source_basis) for the functions of ``basis`` (zero where it has one
    that the source has not)."""
    out = np.zeros((len(basis), A.shape[1]))
    key = 2 * np.asarray(basis.h) + np.asarray(basis.sine, dtype=int)            # (harmonic, sine) of each function
    source = 2 * np.asarray(source_basis.h) + np.asarray(source_basis.sine, dtype=int)
    i, j = np.nonzero(key[:, None] == source[None, :])
    out[i] = np.asarray(A)[j]
    return out
