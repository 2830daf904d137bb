r"""A modal basis for large models whose nonlinearity is localized: the modes below a cutoff plus the
residual flexibility of all the others at the nonlinear elements (a Ritz basis).

For a model too large for the dense eigensolution (n above ``MAX_DENSE_DOF``), the modes with
w_k < w_cut are found by shift-invert Lanczos on the sparse (K, M) (``scipy.sparse.linalg.eigsh``
with one sparse factorisation of K), and the space they span is augmented by the static and the
first inertial attachment fields of the n_s element deformations,

    Psi0 = K^-1 B^T,      Psi1 = K^-1 M K^-1 B^T      (n, n_s each),

M-orthogonalised against the modes.  Rayleigh-Ritz on that space gives m + 2 n_s Ritz pairs: the m
modes below the cutoff exactly (the space holds them), and 2 n_s pairs above w_cut that carry the
flexibility of every mode left out.  The element receptance of the Ritz model,

    B (K - Omega^2 M)^-1 B^T  ~  sum_kept b b^T / (w^2 - Omega^2) + R0 + Omega^2 R1 + O(Omega^4),

matches the model's exactly at Omega = 0 and in its first derivative in Omega^2 (the residual
flexibility R0 = B K^-1 B^T - sum b b^T / w^2 and residual inertia R1 = B K^-1 M K^-1 B^T - sum b b^T / w^4
of the left-out modes, since the Krylov space K^-1 B^T, (K^-1 M) K^-1 B^T is in the basis); a left-out
mode k at the forcing frequency Omega is represented with the relative error of its term of order
(Omega / w_k)^4 / (1 - (Omega / w_k)^2).  With the cutoff at ``CUTOFF_FACTOR`` times the highest
harmonic's frequency that is below 1e-2 of the left-out modes' (already quasi-static) share at the
highest harmonic and below 1e-7 at the fundamental; docs/condensed_hb.md gives the measured effect.

``ritz_system(model, f_cut_hz)`` returns a ``ModalSystem`` in the Ritz coordinates (x = Phi q, Phi
(n, m + 2 n_s) M-orthonormal, Phi^T K Phi = diag(omega2)), cached per model and cutoff, so every
method works on it unchanged and orbits are rebuilt on all n DOFs.
"""
from __future__ import annotations

import math
import threading
import weakref

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import NNMInputError
from .modal import ModalSystem
from .model import MAX_DENSE_DOF
from .sparse import SparseSolver

__all__ = ["CUTOFF_FACTOR", "ritz_basis", "ritz_system", "cutoff_for"]

#: the basis keeps the modes below CUTOFF_FACTOR x (highest harmonic) x (the followed mode's frequency)
CUTOFF_FACTOR = 2.0

_cache = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def cutoff_for(f_mode_hz, harmonics):
    """The basis cutoff (Hz) for a branch of a mode at f_mode_hz with harmonics up to ``harmonics``."""
    return CUTOFF_FACTOR * max(int(harmonics), 1) * float(f_mode_hz)


def lowest_modes(K, M, count, solver=None):
    """The ``count`` lowest eigenpairs (lam ascending, Phi M-orthonormal) of K phi = lam M phi by
    shift-invert Lanczos about 0 (K must be positive definite: no rigid-body modes)."""
    n = K.shape[0]
    solver = solver or SparseSolver(K)
    op = spla.LinearOperator((n, n), matvec=solver.solve, dtype=float)
    k = int(min(count, n - 2))
    v0 = np.ones(n) / math.sqrt(n)                    # a fixed start: the same basis at every run
    lam, Phi = spla.eigsh(K, k=k, M=M, sigma=0.0, which="LM", OPinv=op, v0=v0, tol=1e-12)
    order = np.argsort(lam)
    return lam[order], Phi[:, order]


def ritz_basis(model, f_cut_hz=None, first=24, mode=None, harmonics=None):
    """(omega2 (n_r,), Phi (n, n_r), m, f_cut_hz): the Ritz basis of the module docstring for ``model`` (sparse
    or dense M and K_linear), m the number of exact modes below the cutoff (at least ``first`` modes, and
    mode + 8, when the model has them, so that low modes can be picked by number).  Without f_cut_hz the
    cutoff is ``cutoff_for`` the 1-based ``mode``'s frequency and ``harmonics``."""
    K, M = sp.csc_matrix(model.K_linear), sp.csc_matrix(model.M)
    n = model.n
    B = np.asarray(model.elements.B)
    try:
        solver = SparseSolver(K)
    except RuntimeError as exc:                       # splu: "Factor is exactly singular"
        raise NNMInputError(f"K is singular ({exc}): the model has rigid-body modes; ground the structure "
                            f"(a condensed basis needs K^-1)") from None
    count = max(int(first), 16, int(mode or 0) + 8)
    if n <= MAX_DENSE_DOF:                            # small enough for the dense eigensolution: every mode at once
        lam, Phi = (np.array(a) for a in model.eigensolution)
        count = n
    else:
        lam, Phi = lowest_modes(K, M, count, solver)
    if lam[0] <= 0:
        raise NNMInputError(f"K is not positive definite (lowest eigenvalue {lam[0]:.3g}): rigid-body modes or an "
                            f"unstable structure; ground the structure")
    if f_cut_hz is None:
        f_cut_hz = cutoff_for(math.sqrt(lam[int(mode) - 1]) / (2 * math.pi), harmonics)
    w_cut2 = (2 * math.pi * float(f_cut_hz)) ** 2
    while lam[-1] <= w_cut2 and count < n - 2:
        # more modes below the cutoff: the count N(lam) ~ lam^(d/2) of a d-dimensional body (Weyl), with the
        # exponent read off the modes found (between 1/2, a line, and 3/2, a solid), and a quarter more
        half = len(lam) // 2
        growth = math.log(lam[-1] / lam[half - 1]) if half >= 4 and lam[half - 1] > 0 else 0.0
        expo = min(max(math.log(len(lam) / half) / growth, 0.5), 1.5) if growth > 0 else 1.5
        count = int(min(max(count + 8, math.ceil(1.25 * len(lam) * (w_cut2 / lam[-1]) ** expo)), n - 2))
        lam, Phi = lowest_modes(K, M, count, solver)
    m = max(int(np.searchsorted(lam, w_cut2, side="right")), min(int(first), len(lam)))
    lam, Phi = lam[:m], Phi[:, :m]
    X = np.zeros((n, 0))
    if B.shape[0]:
        P0 = solver.solve(np.ascontiguousarray(B.T))
        X = np.hstack([P0, solver.solve(np.asarray(M @ P0))])
        for _ in range(2):                            # M-orthogonal to the modes (twice: round-off)
            X -= Phi @ (Phi.T @ (M @ X))
        X /= np.sqrt(np.maximum(np.einsum("ij,ij->j", X, M @ X), 1e-300))     # unit columns, then
        g, V = sla.eigh(X.T @ (M @ X))                # an M-orthonormal basis of what the modes do not hold
        keep = g > 1e-10 * max(g.max(), 1e-300)
        X = X @ (V[:, keep] / np.sqrt(g[keep]))
        X -= Phi @ (Phi.T @ (M @ X))
    # Rayleigh-Ritz on the whole space [Phi, X]: Phi^T M Phi = I and Phi^T K Phi = diag(lam) then hold for
    # the model's own matrices (the energies of x = Phi q are the modal ones) whatever the Lanczos accuracy
    X = np.hstack([Phi, X])
    Mx, Kx = X.T @ (M @ X), X.T @ (K @ X)
    lam, W = sla.eigh(0.5 * (Kx + Kx.T), 0.5 * (Mx + Mx.T))
    Phi = X @ W
    # the first m Ritz pairs are the modes kept: the others lie above lam_(m+1) (Courant-Fischer: they are
    # M-orthogonal to the first m eigenvectors)
    idx = np.argmax(np.abs(Phi), axis=0)            # the sign of Model.eigensolution: largest component positive
    Phi = Phi * np.sign(Phi[idx, np.arange(Phi.shape[1])])
    return lam, Phi, m, float(f_cut_hz)


def ritz_system(model, mode, harmonics, f_cut_hz=None):
    """The ModalSystem of ``model`` in its Ritz basis (module docstring) for a branch of the 1-based ``mode``
    with ``harmonics``: cutoff f_cut_hz, or ``cutoff_for`` the mode's frequency.  Cached per model: a cached
    basis whose cutoff is at least the one needed (and that holds the mode) is reused.  Its attributes
    ``exact_modes`` (the m modes below the cutoff) and ``cutoff_hz`` say what it holds."""
    with _lock:
        for system in _cache.get(model, ()):
            f_mode = math.sqrt(system.omega2[mode - 1]) / (2 * math.pi) if mode <= system.exact_modes else math.inf
            need = f_cut_hz if f_cut_hz is not None else cutoff_for(f_mode, harmonics)
            if mode <= system.exact_modes and system.cutoff_hz >= need * (1 - 1e-9):
                return system
    lam, Phi, m, cut = ritz_basis(model, f_cut_hz, mode=mode, harmonics=harmonics)
    if mode > m:
        raise NNMInputError(f"mode {mode} lies above the basis cutoff {cut:.4g} Hz ({m} modes below it)")
    system = ModalSystem(model, eigensolution=(lam, Phi))
    system.exact_modes = m
    system.cutoff_hz = cut
    with _lock:
        _cache.setdefault(model, []).append(system)
    return system
