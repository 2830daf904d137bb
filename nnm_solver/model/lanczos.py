r"""Linear modes of large sparse models: the lowest eigenpairs of K phi = lam M phi by shift-invert Lanczos.

``modes_below``: a block Lanczos (blocks of MODEL.lanczos_block vectors, full re-orthogonalisation) on one sparse
factorisation of K, grown until the modes up to one above a cutoff have converged (the Ritz basis's modes, ritz.py);
``lowest_modes``: ARPACK's ``scipy.sparse.linalg.eigsh`` for a given count (where the block Lanczos cannot
converge them within its vectors); ``sparse_modes``: a model's lowest linear modes about a small negative shift
(rigid-body modes at ~0 Hz), for models too large for the dense eigensolution.  Every start vector is fixed, so
the same model gives the same modes at every run.
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
from .settings import MODEL
from .sparse import SparseSolver

__all__ = ["BLOCK", "LANCZOS_TOL", "LanczosStall", "lowest_modes", "modes_below", "sparse_modes"]

_lock = threading.Lock()


def lowest_modes(K, M, count, solver=None, found=None):
    """The ``count`` lowest eigenpairs (lam ascending, Phi M-orthonormal) of K phi = lam M phi by
    shift-invert Lanczos about 0 (ARPACK; K must be positive definite: no rigid-body modes).

    found = (lam0, Phi0), modes already known: the ``count`` lowest modes above them, by the same Lanczos on the
    operator deflated by them (K^-1 followed by the M-projection off Phi0, which maps the known modes to zero),
    so that a basis is extended without computing its modes again; returned are the known and the new modes
    together, sorted."""
    n = K.shape[0]
    solver = solver or SparseSolver(K)
    known = 0 if found is None else len(found[0])
    k = int(min(count, n - 2 - known))
    if found is None or known == 0:
        solve = solver.solve
    else:
        Phi0 = np.asarray(found[1])
        MPhi0 = np.asarray(M @ Phi0)

        def solve(b):
            y = solver.solve(b)
            return y - Phi0 @ (MPhi0.T @ y)
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    v0 = np.ones(n) / math.sqrt(n)                    # a fixed start: the same basis at every run
    if known:
        v0 = v0 - Phi0 @ (MPhi0.T @ v0)
    # ncv: Lanczos vectors kept between restarts; k + max(100, 2k/5) is ~20 % faster than ARPACK's 2k + 1 here
    # (the restarts' dense work on n x ncv grows as ncv^2; Craig-Bampton, reduction.py, uses the same)
    ncv = int(min(n - known - 1, k + max(100, (2 * k) // 5), max(2 * k + 1, 20)))
    lam, Phi = spla.eigsh(K, k=k, M=M, sigma=0.0, which="LM", OPinv=op, v0=v0, tol=1e-12, ncv=ncv)
    if known:
        lam, Phi = np.concatenate([found[0], lam]), np.hstack([Phi0, Phi])
    order = np.argsort(lam)
    return lam[order], Phi[:, order]


#: the block Lanczos's block size and convergence tolerance (aliases of settings.py's MODEL.lanczos_block, lanczos_tol)
BLOCK = MODEL.lanczos_block
LANCZOS_TOL = MODEL.lanczos_tol


class LanczosStall(RuntimeError):
    """modes_below could not converge the modes needed within its vectors (ritz_basis then uses lowest_modes)."""


def _m_orthonormal(W, M, scale, MW=None):
    """(Wn, M Wn, R) with W = Wn R, Wn^T M Wn = I, dropping the directions of W whose M-norm is below 1e-10 sqrt(scale)
    (W lies in the space already spanned there); MW: M W when known."""
    MW = np.asarray(M @ W) if MW is None else MW
    g, V = sla.eigh(0.5 * (W.T @ MW + MW.T @ W))
    keep = g > 1e-20 * scale
    C = V[:, keep] / np.sqrt(g[keep])
    return W @ C, MW @ C, (V[:, keep] * np.sqrt(g[keep])).T


def _orthogonalise(Q, W, MW, M, recent=0):
    """(W - Q H, M (W - Q H), H) with H making W (M-image MW) M-orthogonal to the M-orthonormal columns of Q: first
    against the columns from ``recent`` on (the last two blocks: the three-term recurrence, where W has its large
    components), then classical block Gram-Schmidt against all of Q, repeated once where that pass cancelled much of
    what was left (a column's M-norm reduced below 1/sqrt(2): Kahan and Parlett's "twice is enough"), which leaves W
    orthogonal to Q to round-off.  Without the first step the full pass cancelled at nearly every block, so that every
    block took two passes over all of Q (2 n J b flops each: most of the Lanczos on the unreduced aircraft)."""
    Hl = None
    if 0 < Q.shape[1] - recent < Q.shape[1]:
        Qr = Q[:, recent:]
        Hl = Qr.T @ MW
        W -= Qr @ Hl
        MW = np.asarray(M @ W)
    before = np.einsum("ij,ij->j", W, MW)
    H = Q.T @ MW
    W -= Q @ H
    MW = np.asarray(M @ W)
    if np.any(np.einsum("ij,ij->j", W, MW) < 0.5 * before):
        H2 = Q.T @ MW
        W -= Q @ H2
        H += H2
        MW = np.asarray(M @ W)
    if Hl is not None:
        H[recent:] += Hl
    return W, MW, H


def _band_eigenvalues(T, j1, width):
    """The eigenvalues (descending) of the symmetric part of T[:j1, :j1] within ``width`` of its diagonal (the block
    tridiagonal Lanczos matrix without the round-off-sized coefficients of the full re-orthogonalisation): LAPACK's
    band reduction, O(j1^2 width) against O(j1^3) for the dense matrix (0.2 s against 2 s at j1 = 2,048, width 32)."""
    width = int(min(width, j1 - 1))
    ab = np.zeros((width + 1, j1))
    for k in range(width + 1):                    # upper band storage: ab[width - k, k:] = the k-th superdiagonal
        ab[width - k, k:] = 0.5 * (np.diagonal(T[:j1, :j1], k) + np.diagonal(T[:j1, :j1], -k))
    return sla.eig_banded(ab, eigvals_only=True, check_finite=False)[::-1]


def _ritz_pairs(T, R, j0, j1, invariant, top):
    """(theta descending, Y, residuals) of the ``top`` largest eigenpairs of the block tridiagonal T (j1 x j1) whose
    last block row is coupled to the next block by R: the Ritz pairs of K^-1 M in the space nearest the shift (the
    lowest modes) and their residual norms ||R y_last||.  LAPACK's MRRR (evr) on the subset: the tridiagonal
    reduction of T is most of its cost (measured at j1 = 1,984: all 1,984 pairs 16.6 s, the top 700 7.3 s, the
    eigenvalues alone 7.0 s, under a load of 12)."""
    top = int(min(top, j1))
    th, Y = sla.eigh(T, driver="evr", subset_by_index=[j1 - top, j1 - 1], overwrite_a=True, check_finite=False)
    th, Y = th[::-1], np.ascontiguousarray(Y[:, ::-1])     # contiguous: numpy's products on reversed strides skip BLAS
    res = np.zeros(len(th)) if invariant else np.linalg.norm(R @ Y[j0:j1], axis=0)
    return th, Y, res


def modes_below(K, M, solver, need, w2_of, block=MODEL.lanczos_block, tol=MODEL.lanczos_tol):
    """(lam ascending, Phi M-orthonormal): the lowest eigenpairs of K phi = lam M phi, K positive definite, until one
    above the cutoff: at least ``need`` + 1 pairs, and every one with lam <= w2_of(lam found) and the next (w2_of
    returns None while it cannot tell yet, e.g. before the followed mode is found).  Converged are 5 % and a block
    more past the cutoff, to show that none is missing below it; those are not returned (``_kept``).

    Block shift-invert Lanczos about 0: the Krylov space of K^-1 M from a fixed random block of ``block`` vectors,
    M-orthonormal with full re-orthogonalisation (block Gram-Schmidt, a second pass where the first cancelled),
    no restart; the block tridiagonal projection T = Q^T M K^-1 M Q from the recurrence, its eigenpairs (theta, y)
    Ritz pairs of 1 / lam with residual ||R_last y_last||.  The space grows until the Ritz values from the largest
    theta down to the ones needed have residual / theta below ``tol``.  Against ARPACK's single-vector Lanczos
    (lowest_modes) the solves are block solves and the orthogonalisation is matrix-matrix work.

    Memory: the Lanczos vectors Q only (their M-images are formed block by block), in one column-major array whose
    columns take memory as they are written (np.empty's pages are mapped when first touched), so that the space
    grows without being copied: n x (vectors) x 8 bytes, at most MODEL.lanczos_bytes.  LanczosStall when the modes
    needed have not converged within MODEL.lanczos_max_vectors (a stiffness range so wide that the residuals stall
    at round-off) or that memory."""
    n = K.shape[0]
    b = int(max(1, min(block, n // 8)))
    j_max = int(min(n - b, MODEL.lanczos_max_vectors, MODEL.lanczos_bytes / (8 * n)))
    definite = getattr(solver, "backend", "") in ("cholmod", "cholespy")     # a Cholesky factor: K is positive definite
    X = np.random.default_rng(0).standard_normal((n, b))     # a fixed start: the same basis at every run
    scale0 = float(np.max(np.einsum("ij,ij->j", X, np.asarray(M @ X))))
    Qb, MQb, _ = _m_orthonormal(X, M, scale0)
    cap = j_max + b
    Q = np.empty((n, cap), order="F")             # column-major: unwritten columns hold no memory
    T = np.zeros((cap, cap), order="F")
    kb = Qb.shape[1]
    Q[:, :kb] = Qb
    j0, j1, J = 0, kb, kb                         # the newest block Q[:, j0:j1]; J columns in all
    p0 = 0                                        # where the block before it starts
    next_check = min(max(2 * need, 4 * b), j_max)
    before = None                                 # the band eigenvalues of the last check

    def enough(th):
        # converged well past the cutoff (5 % and a block more): a mode that Lanczos has not found yet would lie
        # at the end of the converged run, never inside it (Ritz values converge from the end of the spectrum)
        # th : the converged Ritz values (descending), the run from the top
        lam = 1.0 / th
        w2 = w2_of(lam) if len(th) else None
        below = int(np.searchsorted(lam, w2, side="right")) if w2 is not None else len(th)
        return len(th) > need and w2 is not None and len(th) >= below + max(b, below // 20) and lam[-1] > w2
    while True:
        W = np.asarray(solver.solve(np.ascontiguousarray(MQb)), dtype=float).reshape(n, -1)
        MW = np.asarray(M @ W)
        scale = float(np.max(np.einsum("ij,ij->j", W, MW)))
        W, MW, H = _orthogonalise(Q[:, :J], W, MW, M, recent=p0)
        Wn, MWn, R = _m_orthonormal(W, M, scale, MW)
        kn = min(Wn.shape[1] if J < n else 0, cap - J)
        Wn, MWn, R = Wn[:, :kn], MWn[:, :kn], R[:kn]
        T[:J, j0:j1] = H
        Q[:, J:J + kn] = Wn
        T[J:J + kn, j0:j1] = R
        MQb = MWn
        invariant = kn == 0                       # the space is invariant: its Ritz pairs are exact
        full = J + kn >= j_max                     # no room to grow the space further
        check = J + kn >= next_check or invariant or full
        if check and not (invariant or full) and definite:
            # first the eigenvalues alone, from the band (0.2 s): the Ritz pairs' residuals (a dense eigenproblem of
            # the whole matrix, seconds at 2,000 vectors: 80 s of the aircraft's basis in 14 checks) only when the
            # values that have settled since the last check (moved by less than tol: a converged value's error is of
            # order its residual squared) reach past the cutoff as ``enough`` asks
            th = _band_eigenvalues(T, j1, 2 * b)
            if before is not None:
                k = min(len(before), len(th))
                settled = (th[:k] - before[:k]) <= tol * np.abs(th[:k])
                run = int(np.argmin(settled)) if not settled.all() else k
                check = enough(th[:run]) if run and th[run - 1] > 0 else False
            before = th
            if not check:
                next_check = min(J + kn + max(4 * b, (J + kn) // 8), j_max)
        if check:
            # the Ritz pairs of the space whose images are known (columns up to j1)
            # the top half of the Ritz pairs (the converged ones are the top third or so: a run of pairs converged
            # to the end of the subset means that more may be: then all of them)
            # (all of them where K is not known to be positive definite: a negative eigenvalue is at the other end)
            Tj = T[:j1, :j1]
            top = max(2 * need, j1 // 2 + b) if definite else j1
            th, Y, res = _ritz_pairs(0.5 * (Tj + Tj.T), R, j0, j1, invariant, top)
            if len(th) < j1 and np.all(res <= tol * np.abs(th)):
                th, Y, res = _ritz_pairs(0.5 * (Tj + Tj.T), R, j0, j1, invariant, j1)
            conv = res <= tol * np.abs(th)
            if np.any(conv & (th < 0)):
                raise NNMInputError(f"K is not positive definite (an eigenvalue {1 / th[conv & (th < 0)][-1]:.3g} of "
                                    f"K x = w^2 M x): rigid-body modes or an unstable structure; ground the structure")
            ok = conv & (th > 0)
            c = int(np.argmin(ok)) if not ok.all() else len(ok)
            lam = 1.0 / th[:c]
            if invariant or enough(th[:c]):
                del T, Wn, MWn, MQb, W, MW
                keep = _kept(lam, need, w2_of)
                return lam[:keep], _ritz_vectors(Q, j1, Y[:, :keep], M)
            if full:
                raise LanczosStall(f"{J + kn} vectors of {n}: {c} modes converged, not yet past the cutoff")
            next_check = min(J + kn + max(4 * b, (J + kn) // 8), j_max)
        p0, j0, j1, J = j0, J, J + kn, J + kn


def _kept(lam, need, w2_of):
    """How many of the converged eigenvalues lam (ascending) modes_below returns: at least ``need`` + 1, and those up
    to the cutoff w2_of(lam) and one above it (the others, converged only to show that none is missing below the
    cutoff, would be Ritz vectors computed and dropped by ritz_basis: 141 of 803 on the unreduced aircraft)."""
    w2 = w2_of(lam) if len(lam) else None
    below = len(lam) if w2 is None else int(np.searchsorted(lam, w2, side="right"))
    return int(min(len(lam), max(need + 1, below + 1)))


def _ritz_vectors(Q, j, Y, M, cols=64):
    """Phi = Q[:, :j] Y (n x c), M-normalised: one BLAS product on the column-major block (its M-image formed
    ``cols`` columns at a time for the norms: no second n x c array, 0.4 GB on the unreduced aircraft)."""
    Phi = Q[:, :j] @ np.ascontiguousarray(Y)
    for c in range(0, Phi.shape[1], cols):
        P = Phi[:, c:c + cols]
        P /= np.sqrt(np.einsum("ij,ij->j", P, np.asarray(M @ P)))
    return Phi


_modes_cache = weakref.WeakKeyDictionary()


def sparse_modes(model, count):
    """(freqs_hz (k,), shapes (n, k)): the ``count`` lowest linear modes of ``model`` (k = min(count, n - 2)),
    mass-normalised, signs as ``Model.eigensolution``'s (largest component positive), by shift-invert Lanczos on
    the sparse (K_linear, M) about a small negative shift (rigid-body modes come out at ~0 Hz): for models too large
    for the dense eigensolution (``Model.linear_modes``).  Cached per model (the most modes asked for so far)."""
    with _lock:
        done = _modes_cache.get(model)
    if done is not None and done[0].size >= min(count, model.n - 2):
        return done[0][:count].copy(), done[1][:, :count].copy()
    K, M = sp.csc_matrix(model.K_linear), sp.csc_matrix(model.M)
    n = K.shape[0]
    k = int(min(count, n - 2))
    sigma = -1e-9 * abs(K.diagonal()).max() / max(abs(M.diagonal()).max(), 1e-300)
    solver = SparseSolver((K - sigma * M).tocsc())
    op = spla.LinearOperator((n, n), matvec=solver.solve, dtype=float)
    lam, Phi = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=op, v0=np.ones(n) / math.sqrt(n), tol=1e-12)
    order = np.argsort(lam)
    lam, Phi = np.maximum(lam[order], 0.0), Phi[:, order]
    Phi = Phi / np.sqrt(np.einsum("ik,ik->k", Phi, np.asarray(M @ Phi)))
    idx = np.argmax(np.abs(Phi), axis=0)
    Phi = Phi * np.sign(Phi[idx, np.arange(k)])
    freqs = np.sqrt(lam) / (2 * math.pi)
    with _lock:
        _modes_cache[model] = (freqs, Phi)
    return freqs.copy(), Phi.copy()
