"""The sparse direct solvers of model/sparse.py (CHOLMOD by scikit-sparse or cholespy, SuperLU) on a mid-size shell
model: the same solutions to their backward error, the same Ritz basis (modes and residual vectors) whichever
factorises K, equal to the dense eigensolution; refinement where a solve's backward error is too large; the fallbacks
(not symmetric, not positive definite)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import nnm_solver as nnm
from nnm_fem.assembly import FEModel
from nnm_solver.model import ritz, sparse
from nnm_solver.model.sparse import SparseSolver, backward_error, cholespy_available, cholmod_available

LANCZOS_TOL = ritz.MODEL.lanczos_tol          # the block Lanczos's convergence: a floor of the eigenvalue tolerances

BACKENDS = ["superlu"] + (["cholespy"] if cholespy_available() else []) + (["cholmod"] if cholmod_available() else [])


def shell_plate(nx=24, ny=12):
    """A 1.2 m x 0.6 m aluminium plate of nx x ny flat shells (2 mm), its edge x = 0 held by stiff bushings (1e9 N/m,
    1e7 N m/rad: a stiffness range like the aircraft's gear and attachments), two cubic springs between the free
    corners' out-of-plane DOFs and the ground: 6 (nx + 1) (ny + 1) DOFs, sparse M and K."""
    fe = FEModel()
    x, y = np.meshgrid(np.linspace(0, 1.2, nx + 1), np.linspace(0, 0.6, ny + 1), indexing="ij")
    nodes = fe.add_nodes(np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)]))
    grid = nodes.reshape(nx + 1, ny + 1)
    quads = np.column_stack([grid[:-1, :-1].ravel(), grid[1:, :-1].ravel(), grid[1:, 1:].ravel(),
                             grid[:-1, 1:].ravel()])
    fe.add_shells("plate", quads, E=70e9, nu=0.33, t=2e-3, rho=2700.0)
    for node in grid[0]:
        fe.add_bushing("clamp", int(node), None, [1e9, 1e9, 1e9, 1e7, 1e7, 1e7])
    K, M = fe.assemble()
    springs = [nnm.CubicSpring(dof=6 * int(grid[-1, 0]) + 2, k3=1e8),
               nnm.CubicSpring(dof=6 * int(grid[-1, -1]) + 2, other=6 * int(grid[nx // 2, -1]) + 2, k3=1e8)]
    return nnm.Model(sp.csr_matrix(M), sp.csr_matrix(K), springs)


def cancellation(K, Phi):
    """|phi|^T |K| |phi| / phi^T K phi of each column of Phi: the relative round-off of its Rayleigh quotient / eps."""
    P = np.abs(Phi)
    return np.einsum("ij,ij->j", P, abs(K) @ P) / np.einsum("ij,ij->j", Phi, K @ Phi)


@pytest.fixture(scope="module")
def plate():
    return shell_plate()


def test_every_back_end_solves_to_a_small_backward_error_and_auto_takes_cholmod(plate):
    """Each back end's solution of K x = b (2-D and 1-D b) has a componentwise backward error below 1e-14 (refined
    where its probe asked for it) and equals the dense solve to the conditioning of K; "auto" takes CHOLMOD (scikit-
    sparse first, then cholespy) when installed."""
    K = sp.csc_matrix(plate.K_linear)
    b = np.random.default_rng(3).standard_normal((K.shape[0], 4))
    ref = np.linalg.solve(K.toarray(), b)
    for be in BACKENDS:
        s = SparseSolver(K, backend=be)
        assert s.backend == be and s.refined == (s.backward_error > sparse.MODEL.solve_backward_error)
        x = s.solve(b)
        assert backward_error(K, x, b) < 1e-14, be
        assert np.max(np.abs(x - ref)) < 1e-7 * np.max(np.abs(ref)), be
        x1 = s.solve(b[:, 1])
        assert x1.shape == (K.shape[0],) and backward_error(K, x1, b[:, 1]) < 1e-14, be
    assert SparseSolver(K).backend == BACKENDS[-1]


def test_refinement_brings_the_backward_error_down(plate, monkeypatch):
    """With refinement forced on (the threshold at 0), a solve's backward error is at most the unrefined one's and
    at round-off (1e-15), whatever the back end."""
    K = sp.csc_matrix(plate.K_linear)
    b = np.random.default_rng(4).standard_normal((K.shape[0], 3))
    for be in BACKENDS:
        plain = SparseSolver(K, backend=be)
        e0 = backward_error(K, plain._solve(b), b)
        monkeypatch.setattr(sparse, "MODEL", dataclasses.replace(sparse.MODEL, solve_backward_error=0.0))
        s = SparseSolver(K, backend=be)
        monkeypatch.undo()
        assert s.refined
        e1 = backward_error(K, s.solve(b), b)
        assert e1 <= max(e0, 1e-16) and e1 < 2e-15, (be, e0, e1)


def test_matrices_cholesky_cannot_take_go_to_superlu(plate):
    """A matrix that is not symmetric, or symmetric but indefinite, is factorised by SuperLU under "auto" and solved
    exactly; a Cholesky back end asked for by name refuses the indefinite one."""
    K = sp.csc_matrix(plate.K_linear)
    n = K.shape[0]
    b = np.random.default_rng(5).standard_normal(n)
    skew = (K + sp.csc_matrix(([1e3], ([0], [7])), shape=(n, n))).tocsc()
    lam1 = plate.eigensolution[0][0]
    indefinite = (K - 1.5 * lam1 * sp.csc_matrix(plate.M)).tocsc()
    for A in (skew, indefinite):
        s = SparseSolver(A)
        assert s.backend == "superlu"
        assert backward_error(A, s.solve(b), b) < 1e-14
    if cholespy_available():
        with pytest.raises(ValueError, match="positive definite"):
            SparseSolver(indefinite, backend="cholespy")


def test_the_ritz_basis_is_the_same_whichever_solver_factorises_k(plate, monkeypatch):
    """ritz_basis on the sparse path (block Lanczos + the springs' residual fields), cutoff 300 Hz, with each back end:
    the same eigenvalues (the modes' to their round-off, the residual fields' to 1e-8), the modes below the cutoff all there (the dense eigensolution's count), equal to its eigenvalues and ARPACK's
    to their round-off (10 eps times the cancellation in each Rayleigh quotient: 7e-7 on the first mode, 1e-9 on
    most); the same basis (each Ritz vector
    of one back end M-orthogonal to all but its counterpart of the other: |Phi_a^T M Phi_b| = I to 1e-7); M- and
    K-orthonormal."""
    monkeypatch.setattr(ritz, "MODEL", dataclasses.replace(ritz.MODEL, max_dense_dof=100))     # the sparse path
    M, K = sp.csc_matrix(plate.M), sp.csc_matrix(plate.K_linear)
    dense = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    arpack = np.sort(spla.eigsh(K, k=60, M=M, sigma=0.0, which="LM", tol=1e-14, return_eigenvectors=False))
    bases = {}
    for be in BACKENDS:
        lam, Phi, m, cut = ritz.ritz_basis(plate, f_cut_hz=300.0, backend=be)
        assert m == np.sum(dense <= (2 * np.pi * 300.0) ** 2) > 24          # every mode below the cutoff, no more
        # an eigenvalue of this pencil is known to ~eps |phi|^T |K| |phi| / phi^T K phi relative (the cancellation
        # in its Rayleigh quotient: 3e8 for the first mode here, held by the stiff clamp): the tolerances below
        tol = 10 * np.finfo(float).eps * cancellation(K, Phi[:, :m]) + LANCZOS_TOL
        assert np.all(np.abs(lam[:m] / arpack[:m] - 1) < tol), be        # ARPACK about 0 on scipy's own LU
        assert np.all(np.abs(lam[:m] / dense[:m] - 1) < 10 * tol), be    # the dense one errs by ~eps lam_max more
        assert len(lam) == m + 2 * len(plate.springs)
        assert np.allclose(Phi.T @ (M @ Phi), np.eye(len(lam)), atol=1e-9)
        assert np.allclose(Phi.T @ (K @ Phi), np.diag(lam), atol=1e-9 * lam.max())
        bases[be] = (lam, Phi)
    lam0, Phi0 = bases[BACKENDS[0]]
    for be in BACKENDS[1:]:
        lam, Phi = bases[be]
        m = len(lam) - 2 * len(plate.springs)
        tol = 10 * np.finfo(float).eps * cancellation(K, Phi[:, :m]) + LANCZOS_TOL
        assert np.all(np.abs(lam[:m] / lam0[:m] - 1) < tol), be
        # the residual fields' Ritz values: to the solves' forward error (~1e-9 here, the condition of K)
        assert np.allclose(lam[m:], lam0[m:], rtol=1e-8), be
        assert np.allclose(np.abs(Phi0.T @ (M @ Phi)), np.eye(len(lam)), atol=1e-7), be


def test_a_stored_basis_serves_a_branch_whose_cutoff_it_reaches_to_the_eigenvalues_round_off():
    """ritz._holds: a basis whose cutoff was set from the Lanczos value of the mode serves a branch whose cutoff comes
    from the stored Rayleigh-Ritz value, 1.7e-6 apart on the unreduced aircraft's mode 20 (it was refused at 1e-6 and
    the basis computed again); a cutoff short by 1e-4, or a mode above the exact ones, is refused."""
    omega2 = (2 * np.pi * np.array([10.0, 20.0, 35.544661378])) ** 2
    need = ritz.cutoff_for(35.544661378, 9)
    assert ritz._holds(omega2, 3, need * (1 - 1.7e-6), 3, 9, None)
    assert not ritz._holds(omega2, 3, need * (1 - 1e-4), 3, 9, None)
    assert not ritz._holds(omega2, 2, 2 * need, 3, 9, None)
