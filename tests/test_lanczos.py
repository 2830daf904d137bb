"""The block Lanczos's output and the Ritz basis's Gram matrices (model/lanczos.py, model/ritz.py; issue 52): the modes
returned stop one past the cutoff (the pairs converged beyond it only show that none is missing), mass-normalised,
with the exact eigenvalues of a lattice whose spectrum is known in closed form; the Gram matrix built from its upper
blocks equals the dense product."""
import math

import numpy as np
import pytest
import scipy.sparse as sp

from nnm_solver.model import lanczos, ritz
from nnm_solver.model.sparse import SparseSolver


def lattice(N, k=1e4, m=0.5):
    """(K, M, exact eigenvalues ascending) of N x N unit masses m (kg) on springs k (N/m) to their four neighbours
    and the frame: (k / m) (4 sin^2(p pi / (2 (N + 1))) + 4 sin^2(q pi / (2 (N + 1)))), double where p != q."""
    T = sp.diags([-np.ones(N - 1), 2 * np.ones(N), -np.ones(N - 1)], [-1, 0, 1])
    I = sp.identity(N)
    K = (k * (sp.kron(T, I) + sp.kron(I, T))).tocsc()
    M = (m * sp.identity(N * N)).tocsc()
    p, q = np.meshgrid(np.arange(1, N + 1), np.arange(1, N + 1))
    s2 = lambda j: np.sin(j * np.pi / (2 * (N + 1))) ** 2                                          # noqa: E731
    return K, M, np.sort((k / m * 4 * (s2(p) + s2(q))).ravel())


@pytest.mark.parametrize("f_cut", [20.0, 30.0])
def test_the_modes_stop_one_past_the_cutoff_normalised_and_exact(f_cut):
    K, M, exact = lattice(40)
    w2 = (2 * math.pi * f_cut) ** 2
    lam, Phi = lanczos.modes_below(K, M, SparseSolver(K), 10, lambda found: w2)
    below = int(np.sum(exact <= w2))
    assert below > 90
    assert len(lam) == below + 1 and Phi.shape == (K.shape[0], below + 1)     # every mode below, one above
    assert lam[-1] > w2 and np.all(lam[:-1] <= w2)
    assert np.allclose(lam, exact[:len(lam)], rtol=1e-10)
    assert np.allclose(np.einsum("ij,ij->j", Phi, M @ Phi), 1.0, atol=1e-12)   # the chunked normalisation
    assert np.allclose(Phi.T @ (M @ Phi), np.eye(len(lam)), atol=1e-9)


def test_at_least_the_modes_asked_for_when_the_cutoff_is_low():
    K, M, exact = lattice(40)
    lam, Phi = lanczos.modes_below(K, M, SparseSolver(K), 30, lambda found: exact[2])
    assert len(lam) == 31 and np.allclose(lam, exact[:31], rtol=1e-10)


def test_kept_counts():
    lam = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    assert lanczos._kept(lam, 2, lambda found: 3.5) == 4          # three below 3.5, one above
    assert lanczos._kept(lam, 4, lambda found: 3.5) == 5          # at least need + 1
    assert lanczos._kept(lam, 2, lambda found: None) == 6         # no cutoff known: all
    assert lanczos._kept(lam, 2, lambda found: 10.0) == 6         # never more than converged


def test_the_gram_matrix_from_its_upper_blocks_equals_the_dense_product():
    rng = np.random.default_rng(3)
    K, M, _ = lattice(15)
    X = rng.standard_normal((K.shape[0], 201))                    # 201 columns: blocks of 128 and a partial one
    for A in (K, M):
        G = ritz._gram(X, A, cols=128)
        ref = X.T @ (A @ X)
        assert np.allclose(G, ref, rtol=1e-12, atol=1e-9 * np.abs(ref).max())
        assert np.array_equal(G, G.T)
