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


# ---------------------------------------------------------------------- rigid-body modes of fine FE meshes (issue 28)

#: steel-like 1 m beam, 20 mm x 28.32 mm section bending about the thin axis: cantilever f1 = 23.66 Hz; with
#: 300 elements the highest eigenvalue is 5.19e16 rad^2/s^2, 2.3e12 times the first
BEAM = dict(length=1.0, E=210e9, rho=7850.0, width=0.020, thickness=0.02832)
BEAM_EI = BEAM["E"] * BEAM["width"] * BEAM["thickness"] ** 3 / 12.0
BEAM_RHOA = BEAM["rho"] * BEAM["width"] * BEAM["thickness"]


def eb_beam(n_el, clamp, length=BEAM["length"], EI=BEAM_EI, rhoA=BEAM_RHOA):
    """Dense (M, K) of an Euler-Bernoulli beam of Hermite cubic elements, consistent mass.

    DOFs (w_0, theta_0, ..., w_n_el, theta_n_el); clamp="left" removes (w_0, theta_0) (clamped-free),
    clamp=None keeps all (free-free: two rigid-body modes)."""
    h = length / n_el
    ke = EI / h ** 3 * np.array([[12.0, 6 * h, -12.0, 6 * h],
                                 [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                                 [-12.0, -6 * h, 12.0, -6 * h],
                                 [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    me = rhoA * h / 420.0 * np.array([[156.0, 22 * h, 54.0, -13 * h],
                                      [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                      [54.0, 13 * h, 156.0, -22 * h],
                                      [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    N = 2 * (n_el + 1)
    K = np.zeros((N, N))
    M = np.zeros((N, N))
    for e in range(n_el):
        idx = np.arange(2 * e, 2 * e + 4)
        K[np.ix_(idx, idx)] += ke
        M[np.ix_(idx, idx)] += me
    keep = slice(2, N) if clamp == "left" else slice(0, N)
    return M[keep, keep].copy(), K[keep, keep].copy()


def beam_frequency_hz(beta_l, length=BEAM["length"], EI=BEAM_EI, rhoA=BEAM_RHOA):
    """Analytic Euler-Bernoulli frequency (Hz) for the root beta L of the frequency equation."""
    return beta_l ** 2 / (2 * np.pi) * np.sqrt(EI / (rhoA * length ** 4))


#: roots beta L of cos cosh = -1 (clamped-free) and of cos cosh = 1 (free-free, first elastic)
CANTILEVER_BL = (1.8751040687, 4.6940911330)
FREE_FREE_BL = 4.7300407449


def spring_chain(springs, masses=None):
    """(M, K) of masses on a line joined by springs k_i between masses i and i+1 (free-free)."""
    n = len(springs) + 1
    K = np.zeros((n, n))
    for i, k in enumerate(springs):
        K[i:i + 2, i:i + 2] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return np.diag(np.ones(n) if masses is None else np.asarray(masses, dtype=float)), K


def assert_refused_as_rigid(model, mode):
    with pytest.raises(NNMInputError, match="rigid-body") as err:
        model.check_mode(mode)
    assert "pick an elastic mode or ground the structure" in str(err.value)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("sparse", [False, True])
def test_fine_clamped_beam_low_modes_are_elastic(sparse):
    """Issue 28: a 300-element cantilever (600 DOF, lam_max / lam_1 = 2.3e12) lost its low modes as
    "rigid-body".  Modes 1 and 2 are accepted, with the clamped-free frequencies (1.8751^2 and 4.6941^2)
    / (2 pi) sqrt(EI / (rho A L^4)).  The discretisation error of 300 cubic elements is < 1e-9 here; what is
    left is the dense eigen-solver's round-off at this stiffness range: seen 5e-6 in f1, guaranteed below
    eta / (2 lam) ~ 1e-4 (Model._zero_frequency_bound), hence the 2e-4 tolerance (mode 2: 3e-7, 1e-5)."""
    M, K = eb_beam(300, "left")
    m = Model(sp.csr_matrix(M), sp.csr_matrix(K)) if sparse else Model(M, K)
    lam = m.eigensolution[0]
    assert lam[-1] / lam[0] > 1e12 and lam[-1] == pytest.approx(5.19e16, rel=1e-2)
    assert m.check_mode(1) == 0
    assert m.check_mode(2) == 1
    f, _ = m.linear_modes()
    assert f[0] == pytest.approx(23.66, abs=0.01)
    assert f[0] == pytest.approx(beam_frequency_hz(CANTILEVER_BL[0]), rel=2e-4)
    assert f[1] == pytest.approx(beam_frequency_hz(CANTILEVER_BL[1]), rel=2e-5)


@pytest.mark.parametrize("sparse", [False, True])
def test_free_free_beam_rigid_modes_refused(sparse):
    """The same beam unsupported (602 DOF): translation and rotation (modes 1, 2) are refused, the first
    elastic mode (3) is accepted at the free-free frequency 4.7300^2 / (2 pi) sqrt(EI / (rho A L^4))."""
    M, K = eb_beam(300, None)
    m = Model(sp.csr_matrix(M), sp.csr_matrix(K)) if sparse else Model(M, K)
    assert_refused_as_rigid(m, 1)
    assert_refused_as_rigid(m, 2)
    assert m.check_mode(3) == 2
    assert m.linear_modes()[0][2] == pytest.approx(beam_frequency_hz(FREE_FREE_BL), rel=1e-4)


def test_free_free_spring_chain_rigid_mode_refused():
    """Ten unit masses joined by unit springs: mode 1 (translation) refused, mode 2 accepted at
    2 sin(pi / 20) rad/s."""
    m = Model(*spring_chain([1.0] * 9), CubicSpring(dof=0, other=1, k3=1.0))
    assert_refused_as_rigid(m, 1)
    with pytest.raises(NNMInputError, match="rigid-body"):
        nnm.continue_nnm(m, mode=1, energy_max=1.0)
    assert m.check_mode(2) == 1
    assert m.linear_modes()[0][1] * 2 * np.pi == pytest.approx(2 * np.sin(np.pi / 20), rel=1e-12)


def test_free_chain_with_a_stiff_link():
    """A free chain whose first two masses are joined by a 1e13 N/m link (a stiff part moving as one 2 kg
    mass) and five unit springs: the translation (mode 1) is refused, the soft modes (2, 3), 1e-14 and 4e-14
    of the highest eigenvalue, are elastic: mode 2 is that of the chain with masses (2, 1, 1, 1, 1, 1) (seen to
    2e-14; the eigen-solver's round-off bound at this stiffness range is 4e-3, hence the tolerance)."""
    m = Model(*spring_chain([1e13] + [1.0] * 5))
    lam = m.eigensolution[0]
    assert lam[1] / lam[-1] < 2e-14
    assert_refused_as_rigid(m, 1)
    assert m.check_mode(2) == 1
    assert m.check_mode(3) == 2
    Mr, Kr = spring_chain([1.0] * 5, masses=[2.0] + [1.0] * 5)
    lam_r = np.sort(np.linalg.eigvals(np.linalg.solve(Mr, Kr)).real)
    assert lam[1] == pytest.approx(lam_r[1], rel=5e-3)


def test_free_part_of_a_stiff_mesh_refused():
    """A stiff part and a free part: the clamped 300-element beam plus three unit masses on unit springs
    that are attached to nothing, with the DOFs interleaved as an FE numbering may leave them.  The dense
    eigen-solver's error (~0.1 eps lam_max ~ 1 rad^2/s^2) is the size of the free part's own eigenvalues,
    so its rigid mode comes out at lam ~ 0.1, far above eps times its own stiffness: refused all the same
    (its error bound is larger).  The beam's first mode (the 5th) is accepted at the cantilever frequency (seen
    to 2e-5, bound 3e-4)."""
    Mb, Kb = eb_beam(300, "left")
    Mc, Kc = spring_chain([1.0] * 3)
    M = np.block([[Mb, np.zeros((600, 4))], [np.zeros((4, 600)), Mc]])
    K = np.block([[Kb, np.zeros((600, 4))], [np.zeros((4, 600)), Kc]])
    p = np.random.default_rng(0).permutation(604)
    m = Model(M[np.ix_(p, p)], K[np.ix_(p, p)])
    assert_refused_as_rigid(m, 1)
    assert m.check_mode(5) == 4
    assert m.linear_modes()[0][4] == pytest.approx(beam_frequency_hz(CANTILEVER_BL[0]), rel=5e-4)
