"""Flat MITC4 shell: plate frequencies, patch tests, rigid-body modes of a curved shell."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from nnm_fem import FEModel, modes
from nnm_fem.shell import shell_matrices
from nnm_solver import NNMInputError

E, NU, RHO = 70e9, 0.3, 2700.0


def _grid(fe, nx, ny, a, b, jitter=0.0, seed=0):
    x, y = np.meshgrid(np.linspace(0, a, nx + 1), np.linspace(0, b, ny + 1), indexing="ij")
    if jitter:
        rng = np.random.default_rng(seed)
        inner = (slice(1, -1), slice(1, -1))
        x[inner] += jitter * a / nx * rng.uniform(-1, 1, x[inner].shape)
        y[inner] += jitter * b / ny * rng.uniform(-1, 1, y[inner].shape)
    ids = fe.add_nodes(np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])).reshape(nx + 1, ny + 1)
    q = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 4)
    return ids, q


def _solve(K, F, fixed):
    n = K.shape[0]
    free = np.setdiff1d(np.arange(n), fixed)
    u = np.zeros(n)
    u[free] = spla.spsolve(K[free][:, free].tocsc(), F[free] - K[free][:, fixed] @ np.zeros(len(fixed)))
    return u


def test_simply_supported_plate_frequencies():
    a, b, t = 1.0, 0.6, 0.005
    fe = FEModel()
    ids, q = _grid(fe, 24, 16, a, b)
    fe.add_shells("p", q, E, NU, t, rho=RHO)
    K, M = fe.assemble()
    edge = np.unique(np.concatenate([ids[0], ids[-1], ids[:, 0], ids[:, -1]]))
    fixed = np.concatenate([6 * edge + 2, 6 * np.arange(fe.n_nodes), 6 * np.arange(fe.n_nodes) + 1,
                            6 * np.arange(fe.n_nodes) + 5])
    f, _ = modes(K, M, 3, fixed=np.unique(fixed))
    D = E * t ** 3 / (12 * (1 - NU ** 2))
    ex = sorted(np.pi / 2 * np.sqrt(D / (RHO * t)) * ((m / a) ** 2 + (n / b) ** 2)
                for m in range(1, 4) for n in range(1, 4))[:3]
    assert np.allclose(f, ex, rtol=0.01)


def test_membrane_patch_test_distorted():
    fe = FEModel()
    ids, q = _grid(fe, 4, 4, 1.0, 1.0, jitter=0.3)
    fe.add_shells("p", q, E, NU, 0.01)
    K, _ = fe.assemble()
    X = fe.nodes
    ex, ey, gxy = 1e-3, -4e-4, 6e-4
    u_exact = np.zeros(fe.n_dof)
    u_exact[0::6] = ex * X[:, 0] + 0.5 * gxy * X[:, 1]
    u_exact[1::6] = ey * X[:, 1] + 0.5 * gxy * X[:, 0]
    u_exact[5::6] = 0.0
    boundary = np.unique(np.concatenate([ids[0], ids[-1], ids[:, 0], ids[:, -1]]))
    interior = np.setdiff1d(np.arange(fe.n_nodes), boundary)
    # interior in-plane residual of the exact linear field is zero
    r = K @ u_exact
    assert np.max(np.abs(r[6 * interior])) < 1e-6 * np.max(np.abs(K @ u_exact))
    assert np.max(np.abs(r[6 * interior + 1])) < 1e-6 * np.max(np.abs(K @ u_exact))


def test_bending_patch_test_distorted():
    fe = FEModel()
    ids, q = _grid(fe, 4, 4, 1.0, 1.0, jitter=0.3, seed=1)
    fe.add_shells("p", q, E, NU, 0.01)
    K, _ = fe.assemble()
    X = fe.nodes
    kx, ky, kxy = 1e-2, -3e-3, 4e-3
    w = 0.5 * kx * X[:, 0] ** 2 + 0.5 * ky * X[:, 1] ** 2 + 0.5 * kxy * X[:, 0] * X[:, 1]
    u = np.zeros(fe.n_dof)
    u[2::6] = w
    u[4::6] = -(kx * X[:, 0] + 0.5 * kxy * X[:, 1])     # theta_y = -dw/dx
    u[3::6] = ky * X[:, 1] + 0.5 * kxy * X[:, 0]        # theta_x = dw/dy
    boundary = np.unique(np.concatenate([ids[0], ids[-1], ids[:, 0], ids[:, -1]]))
    interior = np.setdiff1d(np.arange(fe.n_nodes), boundary)
    r = K @ u
    ri = np.concatenate([r[6 * interior + c] for c in (2, 3, 4)])
    assert np.max(np.abs(ri)) < 1e-6 * np.max(np.abs(r))


def test_curved_free_shell_has_six_rigid_body_modes():
    fe = FEModel()
    th, z = np.meshgrid(np.linspace(0, np.pi, 9), np.linspace(0, 1.0, 6), indexing="ij")
    ids = fe.add_nodes(np.column_stack([0.5 * np.cos(th.ravel()), 0.5 * np.sin(th.ravel()), z.ravel()]))
    ids = ids.reshape(th.shape)
    q = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 4)
    fe.add_shells("c", q, E, NU, 0.003, rho=RHO)
    K, M = fe.assemble()
    f, _ = modes(K, M, 8)
    assert np.all(f[:6] < 1e-3 * f[6])
    assert fe.total_mass(M) == pytest.approx(RHO * 0.003 * np.pi * 0.5 * 1.0, rel=0.02)


def test_bad_shell_raises():
    with pytest.raises(NNMInputError):
        shell_matrices(np.zeros((1, 3, 3)), E, NU, 0.01)
    X = np.array([[[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]]], float)  # bow-tie
    with pytest.raises(NNMInputError):
        shell_matrices(X, E, NU, 0.01)
