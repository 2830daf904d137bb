"""Craig-Bampton on a small plate-and-beam structure; MAC."""
import numpy as np
import pytest
import scipy.linalg as sla

from nnm_fem import FEModel
from nnm_solver import NNMInputError
from nnm_solver.model.reduction import craig_bampton, mac


@pytest.fixture(scope="module")
def structure():
    fe = FEModel()
    x, y = np.meshgrid(np.linspace(0, 1.0, 9), np.linspace(0, 0.5, 5), indexing="ij")
    ids = fe.add_nodes(np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])).reshape(x.shape)
    q = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 4)
    fe.add_shells("plate", q, 70e9, 0.3, 0.004, rho=2700.0)
    tip = fe.add_nodes([[1.2, 0.25, 0.0]])[0]
    fe.add_beams("arm", [ids[-1, 2]], [tip], [0, 0, 1], 70e9, 26e9, 1e-4, 1e-8, 1e-8, 2e-8, rho=2700.0)
    fe.add_point_mass("tip", tip, 0.5, (1e-4, 1e-4, 1e-4))
    for node in ids[0]:
        fe.add_bushing("support", node, None, [1e6, 1e6, 1e6, 1e2, 1e2, 1e2])
    K, M = fe.assemble()
    lam = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    return K, M, np.sqrt(lam) / (2 * np.pi), np.concatenate([6 * ids[-1, 2] + np.arange(6), 6 * tip + np.arange(6)])


def test_reduced_frequencies_are_converging_upper_bounds(structure):
    K, M, f_full, b = structure
    errs = []
    for m in (5, 15, 40):
        Mr, Kr, R, fi = craig_bampton(M, K, b, m)
        assert Mr.shape == (len(b) + m,) * 2 and R.shape == (K.shape[0], len(b) + m)
        fr = np.sqrt(np.abs(sla.eigh(Kr, Mr, eigvals_only=True))) / (2 * np.pi)
        assert np.all(fr[:8] >= f_full[:8] * (1 - 1e-9))
        errs.append(np.max(fr[:8] / f_full[:8] - 1))
        assert np.all(np.diff(fi) >= 0)
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-3


def test_modal_block_mass_orthonormal_and_r_consistent(structure):
    K, M, _, b = structure
    Mr, Kr, R, fi = craig_bampton(M, K, b, 10)
    nb = len(b)
    assert np.allclose((R.T @ (M @ R))[nb:, nb:], np.eye(10), atol=1e-8)
    assert np.allclose(np.diag(Kr)[nb:], (2 * np.pi * fi) ** 2, rtol=1e-8)
    assert np.allclose(R[b], np.eye(len(b), len(b) + 10))
    assert np.allclose(Mr, R.T @ (M @ R), atol=1e-8 * np.abs(Mr).max())


def test_mac():
    rng = np.random.default_rng(0)
    a = rng.standard_normal((50, 4))
    m = mac(a, -3.0 * a)
    assert np.allclose(np.diag(m), 1.0)
    q, _ = np.linalg.qr(a)
    assert np.allclose(mac(q, q), np.eye(4), atol=1e-12)
    with pytest.raises(NNMInputError):
        mac(a, a[:10])


def test_bad_input(structure):
    K, M, _, b = structure
    with pytest.raises(NNMInputError):
        craig_bampton(M, K, [0, 0], 3)
    with pytest.raises(NNMInputError):
        craig_bampton(M, K, b, -1)


def test_reduction_is_the_same_at_every_run(structure):
    """Two reductions of the same model give bit-identical reduced matrices (a fixed Lanczos start and a fixed sign
    for each fixed-interface mode: its largest entry positive), so that branches saved in the reduced coordinates of
    one build are valid on a rebuild; before, ARPACK's random start flipped the signs of some modes between runs."""
    K, M, _, b = structure
    Mr1, Kr1, R1, _ = craig_bampton(M, K, b, 30)
    Mr2, Kr2, R2, _ = craig_bampton(M, K, b, 30)
    assert np.array_equal(Mr1, Mr2) and np.array_equal(Kr1, Kr2) and np.array_equal(R1, R2)
    modes = R1[:, len(b):]
    assert np.all(modes[np.argmax(np.abs(modes), axis=0), np.arange(modes.shape[1])] > 0)
