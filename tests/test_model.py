"""Model construction, validation messages, linear modes and energy."""
import numpy as np
import pytest
import scipy.sparse as sp

import nnm_solver as nnm
from nnm_solver import CubicSpring, Model, NNMInputError

K2 = np.array([[2.0, -1.0], [-1.0, 2.0]])


def test_linear_modes_two_dof():
    m = Model(np.eye(2), K2)
    f, shapes = m.linear_modes()
    assert np.allclose(f * 2 * np.pi, [1.0, np.sqrt(3.0)])
    assert np.allclose(shapes.T @ shapes, np.eye(2))          # mass-normalised (M = I)
    assert np.allclose(np.abs(shapes[:, 0]), 1 / np.sqrt(2))  # in-phase first


def test_sparse_and_dense_agree():
    M = np.diag([1.0, 2.0, 3.0])
    K = np.array([[4.0, -1, 0], [-1, 5, -2], [0, -2, 6]])
    fd, _ = Model(M, K).linear_modes()
    fs, _ = Model(sp.csr_matrix(M), sp.csr_matrix(K)).linear_modes()
    assert np.allclose(fd, fs)


def test_energy_terms():
    m = Model(np.eye(2), K2, [CubicSpring(dof=0, other=1, k3=2.0)])
    x = np.array([0.3, -0.1])
    v = np.array([1.0, 2.0])
    expected = 0.5 * v @ v + 0.5 * x @ K2 @ x + 2.0 * (0.4 ** 4) / 4
    assert m.energy(x, v) == pytest.approx(expected)
    assert np.allclose(m.energy(np.stack([x, x]), np.stack([v, v])), expected)


def test_relative_spring_force():
    m = Model(np.eye(3), np.eye(3), [CubicSpring(dof=0, other=2, k3=3.0)])
    f = m.nonlinear_force(np.array([0.5, 0.0, 0.2]))
    assert np.allclose(f, [3 * 0.3 ** 3, 0, -3 * 0.3 ** 3])


@pytest.mark.parametrize("M, K, springs, fragment", [
    (np.eye(2), np.eye(3), [], "must match"),
    (np.ones((2, 3)), np.eye(2), [], "square"),
    (np.array([[1.0, 0.5], [0.0, 1.0]]), K2, [], "M is not symmetric"),
    (np.eye(2), np.array([[2.0, -1.0], [0.0, 2.0]]), [], "K is not symmetric"),
    (np.array([[1.0, np.nan], [np.nan, 1.0]]), K2, [], "NaN"),
    (np.eye(2), K2, [CubicSpring(dof=2, k3=1.0)], "dof=2 is not a DOF"),
    (np.eye(2), K2, [CubicSpring(dof=0, other=5, k3=1.0)], "other=5 is not a DOF"),
    (np.eye(2), K2, [CubicSpring(dof=0, k3=float("nan"))], "not finite"),
    (np.eye(2), K2, [(0, 1.0)], "expected nnm_solver.CubicSpring"),
    (np.array([[1.0, 0.5j], [-0.5j, 1.0]]), K2, [], "complex"),
    (np.eye(2), K2, 5, "springs must be a list"),
])
def test_bad_input_one_line(M, K, springs, fragment):
    with pytest.raises(NNMInputError) as err:
        Model(M, K, springs)
    assert fragment in str(err.value)
    assert "\n" not in str(err.value)


def test_indefinite_mass():
    m = Model(np.diag([1.0, -1.0]), K2)
    with pytest.raises(NNMInputError, match="M is not positive definite"):
        m.linear_modes()


def test_unstable_stiffness():
    m = Model(np.eye(2), np.diag([1.0, -1.0]))
    with pytest.raises(NNMInputError, match="K is not positive semi-definite"):
        m.linear_modes()


def test_mode_checks():
    m = Model(np.eye(2), np.array([[1.0, -1.0], [-1.0, 1.0]]), [CubicSpring(dof=0, k3=1.0)])
    with pytest.raises(NNMInputError, match="rigid-body"):
        nnm.continue_nnm(m, mode=1, energy_max=1.0)
    with pytest.raises(NNMInputError, match="out of range"):
        nnm.continue_nnm(m, mode=3, energy_max=1.0)
    with pytest.raises(NNMInputError, match="out of range"):
        nnm.continue_nnm(m, mode=0, energy_max=1.0)


def test_soft_mode_next_to_a_very_stiff_link_is_elastic():
    """A 1e13 stiffness contrast puts the first eigenvalue 1e-13 below the highest: an elastic mode (f = 1/(2 pi)
    Hz to 1e-13), not a rigid-body one (zero to the eigen-solver's round-off); a single element is also accepted
    without a list."""
    K = np.array([[1e13, -1.0], [-1.0, 1.0]])
    m = Model(np.eye(2), K, CubicSpring(dof=1, k3=1.0))
    b = nnm.continue_nnm(m, mode=1, energy_max=0.1, max_points=10)
    assert abs(b.frequency_hz[0] * 2 * np.pi - np.sqrt(np.linalg.eigvalsh(K)[0])) < 1e-3


@pytest.mark.parametrize("kwargs, fragment", [
    (dict(energy_max=-1.0), "energy_max"),
    (dict(energy_max=float("nan")), "energy_max"),
    (dict(energy_max=1.0, tol=0.0), "tol"),
    (dict(energy_max=1.0, steps_per_period=4), "steps_per_period"),
    (dict(energy_max=1.0, energy_min=2.0), "energy_min"),
])
def test_bad_continuation_arguments(kwargs, fragment):
    m = Model(np.eye(2), K2, [CubicSpring(dof=0, k3=1.0)])
    with pytest.raises(NNMInputError, match=fragment):
        nnm.continue_nnm(m, mode=1, **kwargs)


def test_scaled_model():
    m = Model(np.eye(2), K2, [CubicSpring(dof=0, k3=1.0)])
    assert m.scaled(3.0).k3[0] == 3.0
    assert m.k3[0] == 1.0
