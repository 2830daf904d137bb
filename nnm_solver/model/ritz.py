r"""A modal basis for large models whose nonlinearity is localized: the modes below a cutoff plus the
residual flexibility of all the others at the nonlinear elements (a Ritz basis).

For a model too large for the dense eigensolution (n above ``MODEL.max_dense_dof``), the modes with
w_k < w_cut are found by shift-invert Lanczos on the sparse (K, M) with one sparse factorisation of K
(``modes_below``: a block Lanczos, blocks of 32 vectors, full re-orthogonalisation, grown until the modes
up to one above the cutoff have converged; ARPACK's ``scipy.sparse.linalg.eigsh``, ``lowest_modes``, where
it cannot converge them within its vectors), and the space they span is augmented by the static and the
first inertial attachment fields of the n_s element deformations,

    Psi0 = K^-1 B^T,      Psi1 = K^-1 M K^-1 B^T      (n, n_s each),

M-orthogonal to the modes (each solved for the part of its load the modes do not take, ``_residual_fields``, so
that round-off of K^-1 does not stand in for the small part left).  Rayleigh-Ritz on that space gives m + 2 n_s Ritz pairs: the m
modes below the cutoff exactly (the space holds them), and 2 n_s pairs above w_cut that carry the
flexibility of every mode left out.  The element receptance of the Ritz model,

    B (K - Omega^2 M)^-1 B^T  ~  sum_kept b b^T / (w^2 - Omega^2) + R0 + Omega^2 R1 + O(Omega^4),

matches the model's exactly at Omega = 0 and in its first derivative in Omega^2 (the residual
flexibility R0 = B K^-1 B^T - sum b b^T / w^2 and residual inertia R1 = B K^-1 M K^-1 B^T - sum b b^T / w^4
of the left-out modes, since the Krylov space K^-1 B^T, (K^-1 M) K^-1 B^T is in the basis); a left-out
mode k at the forcing frequency Omega is represented with the relative error of its term of order
(Omega / w_k)^4 / (1 - (Omega / w_k)^2).  With the cutoff at ``MODEL.cutoff_factor`` times the highest
harmonic's frequency that is below 1e-2 of the left-out modes' (already quasi-static) share at the
highest harmonic and below 1e-7 at the fundamental; docs/condensed_hb.md gives the measured effect.

``ritz_system(model, f_cut_hz)`` returns a ``ModalSystem`` in the Ritz coordinates (x = Phi q, Phi
(n, m + 2 n_s) M-orthonormal, Phi^T K Phi = diag(omega2)), cached per model and cutoff, so every
method works on it unchanged and orbits are rebuilt on all n DOFs.

A basis can be stored in the model's file (``nnm_solver.store_ritz_basis``, files/ritz_store.py): reading the file
registers it here (``register_stored_basis``) under the ``linear_fingerprint`` of the model, which says what the
basis depends on (M, K_linear, the elements' deformation matrix B; not the force laws' coefficients), and
``ritz_system`` takes a stored basis that holds the mode and the cutoff before computing one.
"""
from __future__ import annotations

import hashlib
import math
import threading
import weakref
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import NNMInputError
from .modal import ModalSystem
from .lanczos import BLOCK, LANCZOS_TOL, LanczosStall, lowest_modes, modes_below, sparse_modes  # noqa: F401
from .settings import MODEL
from .sparse import SparseSolver

__all__ = ["CUTOFF_FACTOR", "modes_below", "ritz_basis", "ritz_system", "cutoff_for", "linear_fingerprint",
           "register_stored_basis", "StoredBasis", "sparse_modes", "LanczosStall"]

#: the basis keeps the modes below CUTOFF_FACTOR x (highest harmonic) x (the followed mode's frequency): an alias
#: of settings.py's MODEL.cutoff_factor
CUTOFF_FACTOR = MODEL.cutoff_factor

_cache = weakref.WeakKeyDictionary()
_lock = threading.Lock()


@dataclass
class StoredBasis:
    """A Ritz basis kept outside the process (a model file's /ritz_basis): its eigenvalues and what it holds, and
    ``load()`` giving Phi (n, len(omega2)), or None when the source no longer holds this basis."""

    fingerprint: str
    omega2: np.ndarray
    exact_modes: int
    cutoff_hz: float
    load: Callable
    source: str = ""


#: linear_fingerprint -> the stored bases registered for models of that linear part
_stored = {}


def cutoff_for(f_mode_hz, harmonics):
    """The basis cutoff (Hz) for a branch of a mode at f_mode_hz with harmonics up to ``harmonics``."""
    return MODEL.cutoff_factor * max(int(harmonics), 1) * float(f_mode_hz)


def ritz_basis(model, f_cut_hz=None, first=24, mode=None, harmonics=None, backend="auto"):
    """(omega2 (n_r,), Phi (n, n_r), m, f_cut_hz): the Ritz basis of the module docstring for ``model`` (sparse
    or dense M and K_linear), m the number of exact modes below the cutoff (at least ``first`` modes, and
    mode + 8, when the model has them, so that low modes can be picked by number).  Without f_cut_hz the
    cutoff is ``cutoff_for`` the 1-based ``mode``'s frequency and ``harmonics``.  ``backend``: the sparse
    factorisation of K (sparse.py's SparseSolver)."""
    K, M = sp.csc_matrix(model.K_linear), sp.csc_matrix(model.M)
    n = model.n
    B = np.asarray(model.elements.B)
    try:
        solver = SparseSolver(K, backend=backend)
    except RuntimeError as exc:                       # splu: "Factor is exactly singular"
        raise NNMInputError(f"K is singular ({exc}): the model has rigid-body modes; ground the structure "
                            f"(a condensed basis needs K^-1)") from None
    count = max(int(first), 16, int(mode or 0) + 8)
    if n <= MODEL.max_dense_dof:                      # small enough for the dense eigensolution: every mode at once
        lam, Phi = (np.array(a) for a in model.eigensolution)
        count = n
    else:                                             # block Lanczos up to the cutoff (and past it)
        def w2_of(found):
            if f_cut_hz is not None:
                return (2 * math.pi * float(f_cut_hz)) ** 2
            if len(found) < int(mode):
                return None
            return (2 * math.pi * cutoff_for(math.sqrt(found[int(mode) - 1]) / (2 * math.pi), harmonics)) ** 2
        try:
            lam, Phi = modes_below(K, M, solver, count, w2_of)
            count = len(lam)
        except LanczosStall:                          # ARPACK's restarted Lanczos, grown below by the Weyl estimate
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
        # the modes found are kept: the next ones by the deflated Lanczos (no mode is computed twice)
        lam, Phi = lowest_modes(K, M, count - len(lam), solver, found=(lam, Phi))
        count = len(lam)
    m = max(int(np.searchsorted(lam, w_cut2, side="right")), min(int(first), len(lam)))
    lam, Phi = lam[:m], Phi[:, :m]
    X = np.zeros((n, 0))
    if B.shape[0]:
        X = _residual_fields(solver, M, Phi, B)
        X /= np.sqrt(np.maximum(np.einsum("ij,ij->j", X, M @ X), 1e-300))     # unit columns, then
        g, V = sla.eigh(X.T @ (M @ X))                # an M-orthonormal basis of what the modes do not hold
        keep = g > 1e-10 * max(g.max(), 1e-300)
        X = X @ (V[:, keep] / np.sqrt(g[keep]))
        X -= Phi @ (Phi.T @ (M @ X))
    del solver                                        # the factor's memory, before the n x (m + 2 n_s) work below
    # Rayleigh-Ritz on the whole space [Phi, X]: Phi^T M Phi = I and Phi^T K Phi = diag(lam) then hold for
    # the model's own matrices (the energies of x = Phi q are the modal ones) whatever the Lanczos accuracy
    X = np.hstack([Phi, X])
    del Phi
    Mx, Kx = _gram(X, M), _gram(X, K)
    lam, W = sla.eigh(0.5 * (Kx + Kx.T), 0.5 * (Mx + Mx.T))
    Phi = _times_in_place(X, W)
    # the first m Ritz pairs are the modes kept: the others lie above lam_(m+1) (Courant-Fischer: they are
    # M-orthogonal to the first m eigenvectors)
    idx = np.argmax(np.abs(Phi), axis=0)            # the sign of Model.eigensolution: largest component positive
    Phi *= np.sign(Phi[idx, np.arange(Phi.shape[1])])
    return lam, Phi, m, float(f_cut_hz)


def _residual_fields(solver, M, Phi, B):
    """[Psi0, Psi1] (n, 2 n_s) with the modes Phi taken out: Psi0 = (I - Phi Phi^T M) K^-1 B^T and Psi1 = (I - Phi
    Phi^T M) K^-1 M Psi0, each solved for the part of its right-hand side the modes do not hold (K^-1 commutes with
    the projection, Phi being eigenvectors), then projected again.  Solving K^-1 B^T whole and projecting after
    would cancel: on the aircraft the static fields outside the modes are ~1e-4 of the fields and the inertial ones
    ~1e-9, at and below the round-off of K^-1 (1e-9 to 1e-6 of a solution, its condition), so that those fields would
    be noise, different for every sparse solver; solved this way their round-off is relative to themselves."""
    def project(X, twice=True):
        for _ in range(2 if twice else 1):                    # M-orthogonal to the modes (twice: round-off)
            X -= Phi @ (Phi.T @ np.asarray(M @ X))
        return X

    def project_load(F):                                      # F - M Phi Phi^T F: the load the modes do not take
        for _ in range(2):
            F -= np.asarray(M @ (Phi @ (Phi.T @ F)))
        return F

    P0 = project(solver.solve(project_load(np.array(B.T, dtype=float))))
    P1 = project(solver.solve(project_load(np.asarray(M @ P0, dtype=float))))
    return np.hstack([P0, P1])


def _gram(X, A, cols=128):
    """X^T A X (k x k) for X (n, k), A sparse symmetric (n, n): ``cols`` columns of A X at a time (no n x k
    temporary), the blocks on and above the diagonal only (half the products), the lower triangle their mirror."""
    k = X.shape[1]
    G = np.empty((k, k))
    for c in range(0, k, cols):
        G[:c + cols, c:c + cols] = X[:, :c + cols].T @ np.asarray(A @ np.ascontiguousarray(X[:, c:c + cols]))
    lower = np.tril_indices(k, -1)
    G[lower] = G.T[lower]
    return G


def _times_in_place(X, W, rows=4096):
    """X W for X (n, k) C-ordered and W (k, k), written over X ``rows`` rows at a time (no second n x k array)."""
    for r in range(0, X.shape[0], rows):
        X[r:r + rows] = X[r:r + rows] @ W
    return X


def linear_fingerprint(model):
    """SHA-256 (hex) of what a Ritz basis of ``model`` depends on: n, M, K_linear and the elements' deformation
    matrix B, as stored (dense or CSR), not the force laws' coefficients (k3 scaled: the same basis)."""
    h = hashlib.sha256(f"ritz basis of n={model.n}".encode())
    for A in (model.M, model.K_linear):
        if sp.issparse(A):
            A = sp.csr_matrix(A, copy=True)
            A.sum_duplicates()
            A.eliminate_zeros()
            h.update(b"csr")
            for a in (A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data.astype(float)):
                h.update(np.ascontiguousarray(a).tobytes())
        else:
            h.update(b"dense")
            h.update(np.ascontiguousarray(A, dtype=float).tobytes())
    h.update(b"B")
    h.update(np.ascontiguousarray(model.elements.B, dtype=float).tobytes())
    return h.hexdigest()


def register_stored_basis(basis):
    """Make a StoredBasis available to ``ritz_system`` for every model of its fingerprint (once per source and
    cutoff: registering the same again replaces it)."""
    with _lock:
        entries = [b for b in _stored.get(basis.fingerprint, ())
                   if not (b.source == basis.source and b.cutoff_hz == basis.cutoff_hz)]
        _stored[basis.fingerprint] = entries + [basis]


def _holds(omega2, exact_modes, cutoff_hz, mode, harmonics, f_cut_hz):
    """True if a basis (eigenvalues omega2, exact_modes below cutoff_hz) serves a branch of ``mode``."""
    f_mode = math.sqrt(omega2[mode - 1]) / (2 * math.pi) if mode <= exact_modes else math.inf
    need = f_cut_hz if f_cut_hz is not None else cutoff_for(f_mode, harmonics)
    # 1e-5: the cutoff was set from the Lanczos value of the mode, omega2 holds the Rayleigh-Ritz one; they agree to
    # the round-off of this pencil's eigenvalues (eps times the cancellation in a Rayleigh quotient: 1.7e-6 on the
    # unreduced aircraft's mode 20 with cholespy, whose basis a 1e-6 tolerance refused to reuse), 6 mHz at 640 Hz
    return mode <= exact_modes and cutoff_hz >= need * (1 - 1e-5)


def _from_stored(model, mode, harmonics, f_cut_hz):
    """The ModalSystem of a registered stored basis of ``model``'s fingerprint that serves the branch, or None."""
    with _lock:
        if not _stored:
            return None
    fingerprint = linear_fingerprint(model)
    with _lock:
        entries = list(_stored.get(fingerprint, ()))
    for b in sorted(entries, key=lambda b: b.cutoff_hz):
        if not _holds(b.omega2, b.exact_modes, b.cutoff_hz, mode, harmonics, f_cut_hz):
            continue
        Phi = b.load()
        if Phi is None or Phi.shape != (model.n, len(b.omega2)):
            continue
        system = ModalSystem(model, eigensolution=(np.array(b.omega2, dtype=float), Phi))
        system.exact_modes = int(b.exact_modes)
        system.cutoff_hz = float(b.cutoff_hz)
        system.stored = b.source
        return system
    return None


def ritz_system(model, mode, harmonics, f_cut_hz=None):
    """The ModalSystem of ``model`` in its Ritz basis (module docstring) for a branch of the 1-based ``mode``
    with ``harmonics``: cutoff f_cut_hz, or ``cutoff_for`` the mode's frequency.  Cached per model: a cached
    basis whose cutoff is at least the one needed (and that holds the mode) is reused, then a stored basis of the
    model's ``linear_fingerprint`` (register_stored_basis; the lowest cutoff that serves), before one is computed.
    Its attributes ``exact_modes`` (the m modes below the cutoff) and ``cutoff_hz`` say what it holds, ``stored``
    where it was read from ('' when computed)."""
    with _lock:
        for system in _cache.get(model, ()):
            if _holds(system.omega2, system.exact_modes, system.cutoff_hz, mode, harmonics, f_cut_hz):
                return system
    system = _from_stored(model, mode, harmonics, f_cut_hz)     # a basis stored in the model's file
    if system is None:
        lam, Phi, m, cut = ritz_basis(model, f_cut_hz, mode=mode, harmonics=harmonics)
        if mode > m:
            raise NNMInputError(f"mode {mode} lies above the basis cutoff {cut:.4g} Hz ({m} modes below it)")
        system = ModalSystem(model, eigensolution=(lam, Phi))
        system.exact_modes = m
        system.cutoff_hz = cut
        system.stored = ""
    with _lock:
        _cache.setdefault(model, []).append(system)
    return system
