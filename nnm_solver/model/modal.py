r"""A model in mass-normalised modal coordinates, the form every periodic-orbit method works in.

With the linear modes Phi (Phi^T M Phi = I, Phi^T K Phi = Omega^2) and x = Phi q:

    q'' + Omega^2 q + Bq^T g(Bq q) = 0,      Bq = B Phi  (n_s, n),

where d = Bq q are the n_s element deformations (m) and g their force laws (elements.py).
Omega^2 is diagonal, so the linear part costs O(n) per evaluation and the nonlinearity, which is
localised on a few elements, O(n n_s).
"""
from __future__ import annotations

import threading
import weakref

import numpy as np

__all__ = ["ModalSystem", "modal_system"]


class ModalSystem:
    """A Model in mass-normalised modal coordinates:  q'' + Omega^2 q + Bq^T g(Bq q) = 0.

    omega2 (n,) rad^2/s^2; Phi (n, n) mode shapes (x = Phi q); PhiT_M (n, n) (q = Phi^T M x);
    Bq (n_s, n); powers, coefficients, kinks: the element force laws (elements.ElementSet);
    kernel = (omega2, Bq, powers, coefficients, kinks): the arguments of the Newmark kernels.
    Omega^2 are the eigenvalues of the linear model (M, Model.K_linear); ``eigensolution`` (lam, Phi) gives
    another M-orthonormal basis diagonalising K_linear (a Ritz basis of fewer columns, ritz.py).
    """

    def __init__(self, model, eigensolution=None):
        lam, Phi = model.eigensolution if eigensolution is None else eigensolution
        self.model = model
        self.n = len(lam)                        # modal coordinates: model.n, or fewer in a Ritz basis (ritz.py)
        self.elements = model.elements
        self.omega2 = np.ascontiguousarray(lam, dtype=float)
        self.Phi = np.ascontiguousarray(Phi)
        self.PhiT_M = np.ascontiguousarray(np.asarray(model.M @ Phi).T)
        self.Bq, self.powers, self.coefficients, self.kinks = self.elements.in_basis(Phi)
        self.kernel = (self.omega2, self.Bq, self.powers, self.coefficients, self.kinks)

    def to_modal(self, x):
        """Modal coordinates of x: (n,) -> (n,), or (k, n) -> (k, n) (complex rows allowed)."""
        return np.asarray(x) @ self.PhiT_M.T

    def to_physical(self, q):
        return np.asarray(q) @ self.Phi.T

    def force(self, d):
        """Element forces g(d) (..., n_s) for deformations d (..., n_s)."""
        return self.elements.force(d)

    def tangent(self, d):
        """Element stiffnesses g'(d) (..., n_s)."""
        return self.elements.tangent(d)

    def coupled_stiffness(self, d):
        """Modal stiffness (..., n, n) of the coupled elements (PolynomialStiffness) at the deformations d (..., n_d):
        sum over elements of W^T T(d) W, W = their rows of Bq (0 when there are none)."""
        d = np.asarray(d, dtype=float)
        K = np.zeros(d.shape[:-1] + (self.n, self.n))
        for rows, T in self.elements.coupled_tangents(d):
            W = self.Bq[rows]                                                  # (G, m, n)
            Y = np.einsum("...gab,gbj->...gaj", T, W).reshape(d.shape[:-1] + (-1, self.n))
            K += np.swapaxes(W.reshape(-1, self.n), 0, 1) @ Y
        return K

    def nonlinear_force(self, q):
        """f_nl (..., n) in modal coordinates at q (..., n): Bq^T g(Bq q), coupled elements included."""
        q = np.asarray(q, dtype=float)
        return self.elements.force(q @ self.Bq.T) @ self.Bq

    def curvature(self, q, j):
        """d^2 V_nl / dq_j^2 (...) at the modal states q (..., n), V_nl the elements' potential (the modal stiffness's
        diagonal entry j): sum over the springs of Bq[s, j]^2 g_s'(d_s) plus w^T T(d) w over the coupled elements (w
        their rows of Bq's column j, T their tangent blocks), d = Bq q.  O(n n_s) a state."""
        d = np.asarray(q, dtype=float) @ self.Bq.T
        b = self.Bq[:, j]
        c = self.elements.tangent(d) @ (b * b)
        for rows, T in self.elements.coupled_tangents(d):
            w = b[rows]                                                        # (G, m)
            c = c + np.einsum("ga,...gab,gb->...", w, T, w)
        return c

    def energy(self, q0, v0):
        """Energy (J) of the modal state (q0, v0): |v0|^2 / 2 + q0^T Omega^2 q0 / 2 + element potentials."""
        return float(0.5 * v0 @ v0 + 0.5 * q0 @ (self.omega2 * q0) + np.sum(self.elements.potential(self.Bq @ q0)))


_cache = weakref.WeakKeyDictionary()
_cache_lock = threading.Lock()


def modal_system(model):
    """The ModalSystem of a model, computed once per model object (the eigenproblem is O(n^3))."""
    with _cache_lock:
        ms = _cache.get(model)
        if ms is None:
            ms = _cache[model] = ModalSystem(model)
        return ms
