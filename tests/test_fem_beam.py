"""3D beam element: closed-form frequencies, static deflection, rigid-body modes."""
import numpy as np
import pytest

from nnm_fem import FEModel, modes
from nnm_fem.beam import beam_matrices
from nnm_solver import NNMInputError

E, G, RHO = 70e9, 26e9, 2700.0


def _line(n, L, direction=(1.0, 0.0, 0.0)):
    fe = FEModel()
    d = np.asarray(direction) / np.linalg.norm(direction)
    nodes = fe.add_nodes(np.outer(np.linspace(0, L, n + 1), d))
    return fe, nodes


def _section(b=0.05, h=0.02):
    A = b * h
    Iy = b * h ** 3 / 12   # about local e2 ... used for w bending when orient = z
    Iz = h * b ** 3 / 12
    J = 0.2 * b * h ** 3
    return A, Iy, Iz, J


@pytest.mark.parametrize("direction", [(1, 0, 0), (0.3, -0.5, 0.8)])
def test_cantilever_bending_and_torsion(direction):
    L, n = 1.0, 40
    A, Iy, Iz, J = _section()
    fe, nodes = _line(n, L, direction)
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    orient = np.cross(d, [0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else [0, 0, 1.0]
    fe.add_beams("b", nodes[:-1], nodes[1:], orient, E, G, A, Iy, Iz, J, rho=RHO, shear_factor=0.0)
    K, M = fe.assemble()
    f, _ = modes(K, M, 6, fixed=np.arange(6))
    beta = np.array([1.8751, 4.6941, 7.8548])
    fb = lambda I: beta ** 2 / (2 * np.pi) * np.sqrt(E * I / (RHO * A * L ** 4))
    expected = np.sort(np.concatenate([fb(Iy), fb(Iz), [np.sqrt(G * J / (RHO * (Iy + Iz))) / (4 * L)],
                                       [np.sqrt(E / RHO) / (4 * L)]]))
    assert np.allclose(f, expected[:6], rtol=2e-3)


def test_static_tip_deflection_timoshenko():
    L, n, P = 0.5, 10, 1000.0
    b = h = 0.1
    A, I = b * h, b * h ** 3 / 12
    fe, nodes = _line(n, L)
    fe.add_beams("b", nodes[:-1], nodes[1:], [0, 1, 0], E, G, A, I, I, 0.14 * b ** 4, rho=RHO)
    K, _ = fe.assemble()
    free = np.arange(6, fe.n_dof)
    F = np.zeros(fe.n_dof)
    F[6 * nodes[-1] + 2] = P
    import scipy.sparse.linalg as spla
    u = spla.spsolve(K[free][:, free].tocsc(), F[free])
    w = u[6 * nodes[-1] + 2 - 6]
    exact = P * L ** 3 / (3 * E * I) + P * L / (5 / 6 * G * A)
    assert w == pytest.approx(exact, rel=1e-8)


def test_free_beam_has_six_rigid_body_modes():
    A, Iy, Iz, J = _section()
    fe, nodes = _line(10, 1.0, (1, 1, 1))
    fe.add_beams("b", nodes[:-1], nodes[1:], [0, 0, 1], E, G, A, Iy, Iz, J, rho=RHO)
    K, M = fe.assemble()
    f, _ = modes(K, M, 8)
    assert np.all(f[:6] < 1e-3 * f[6])


def test_bad_beam_raises():
    with pytest.raises(NNMInputError):
        beam_matrices([[0, 0, 0]], [[0, 0, 0]], [0, 0, 1], E, G, 1e-3, 1e-8, 1e-8, 1e-8, RHO)
