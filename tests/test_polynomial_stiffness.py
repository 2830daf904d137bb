"""PolynomialStiffness (issue 55): a polynomial force in several coordinates, NLvib's convention, in every method.

Checks: the tangent and the potential against finite differences (with d_j = 0 and zero exponents), the numba
kernel against numpy, the exact monodromy of the general kernels against finite differences, energy conservation
along a shooting orbit, springs written as PolynomialStiffness give the same backbones to round-off (shooting, HB,
condensed HB), NLvib's example 06 (two orthogonal springs in large deflection) by shooting vs HB and its orbit
against DOP853, even terms, a reduced-order model on a subset of coordinates, grouping, bad input, files.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nnm_solver as nnm
from nnm_solver.integrators import general
from nnm_solver.integrators.registry import get_integrator
from nnm_solver.model.modal import ModalSystem

OM1, OM2 = 1.13, 2.0


def example06():
    """NLvib's EXAMPLES/06_twoSprings_geometricNonlinearity, undamped: q'' + diag(om^2) q + E^T z(q) = 0."""
    c3 = (OM1 ** 2 + OM2 ** 2) / 2
    p = [[2, 0], [1, 1], [0, 2], [3, 0], [2, 1], [1, 2], [0, 3]]
    E = [[3 * OM1 ** 2 / 2, OM2 ** 2 / 2], [OM2 ** 2, OM1 ** 2], [OM1 ** 2 / 2, 3 * OM2 ** 2 / 2],
         [c3, 0], [0, c3], [c3, 0], [0, c3]]
    return nnm.Model(np.eye(2), np.diag([OM1 ** 2, OM2 ** 2]), springs=[nnm.PolynomialStiffness(p, E)])


def example06_rhs(t, y):
    q1, q2, v1, v2 = y
    c3 = (OM1 ** 2 + OM2 ** 2) / 2
    f1 = OM1 ** 2 * q1 + OM1 ** 2 / 2 * (3 * q1 ** 2 + q2 ** 2) + OM2 ** 2 * q1 * q2 + c3 * q1 * (q1 ** 2 + q2 ** 2)
    f2 = OM2 ** 2 * q2 + OM2 ** 2 / 2 * (3 * q2 ** 2 + q1 ** 2) + OM1 ** 2 * q1 * q2 + c3 * q2 * (q1 ** 2 + q2 ** 2)
    return [v1, v2, -f1, -f2]


# a conservative quartic-potential law in 3 coordinates with zero exponents and mixed degrees:
# V = d1^2 d2 + d2^3 d3 / 2 + d1^4 / 4 + d3^3 / 3  ->  g = (2 d1 d2 + d1^3, d1^2 + 3/2 d2^2 d3, d2^3 / 2 + d3^2)
EX3 = [[1, 1, 0], [2, 0, 0], [0, 2, 1], [0, 3, 0], [3, 0, 0], [0, 0, 2]]
CO3 = [[2, 0, 0], [0, 1, 0], [0, 1.5, 0], [0, 0, 0.5], [1, 0, 0], [0, 0, 1]]


def test_force_tangent_potential_by_finite_differences():
    e = nnm.PolynomialStiffness(EX3, CO3)
    rng = np.random.default_rng(1)
    pts = np.vstack([rng.normal(size=(4, 3)), [[0.0, 0.7, -0.4], [0.3, 0.0, 0.0], [0.0, 0.0, 0.0]]])
    h = 1e-6
    for d in pts:
        d1, d2, d3 = d
        np.testing.assert_allclose(e.force(d), [2 * d1 * d2 + d1 ** 3, d1 ** 2 + 1.5 * d2 ** 2 * d3,
                                                d2 ** 3 / 2 + d3 ** 2], rtol=1e-13, atol=1e-15)
        V = d1 ** 2 * d2 + d2 ** 3 * d3 / 2 + d1 ** 4 / 4 + d3 ** 3 / 3
        assert e.potential(d) == pytest.approx(V, rel=1e-13, abs=1e-15)
        fd = np.column_stack([(e.force(d + h * u) - e.force(d - h * u)) / (2 * h) for u in np.eye(3)])
        np.testing.assert_allclose(e.tangent(d), fd, rtol=1e-7, atol=1e-8)
        grad = [(e.potential(d + h * u) - e.potential(d - h * u)) / (2 * h) for u in np.eye(3)]
        np.testing.assert_allclose(e.force(d), grad, rtol=1e-7, atol=1e-8)
    assert not e.odd


def test_numba_kernel_matches_numpy_and_finite_differences():
    """Model force and modal stiffness of a mixed model (springs + two coupled elements on DOF subsets with
    directions) by the integrators' numba kernel, numpy and finite differences."""
    rng = np.random.default_rng(2)
    A = rng.normal(size=(4, 4))
    K = A @ A.T + 4 * np.eye(4)
    springs = [nnm.CubicSpring(dof=0, k3=0.4), nnm.PolynomialStiffness(EX3, CO3, dofs=[1, 2, 3]),
               nnm.PolynomialStiffness([[3, 0], [1, 2], [2, 1], [0, 3]], [[1, 0], [1, 0], [0, 1], [0, 1]],
                                       dofs=[0, 2, 3], directions=[[1, -1, 0], [0, 0.5, 2]]),
               nnm.PiecewiseLinearSpring(dof=3, other=1, stiffnesses=[0.0, 2.0], breakpoints=[0.1])]
    m = nnm.Model(np.diag([1.0, 2.0, 1.5, 0.5]), K, springs)
    s = ModalSystem(m)
    args = general.kernel_args(s)[1:]
    h = 1e-6
    for q in rng.normal(size=(3, 4)):
        f, Kq = general.force_stiffness(q, *args)
        np.testing.assert_allclose(f, s.nonlinear_force(q), rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(f, s.Phi.T @ m.nonlinear_force(s.Phi @ q), rtol=1e-10, atol=1e-12)
        d = s.Bq @ q
        Knp = s.coupled_stiffness(d) + s.Bq.T @ (s.tangent(d)[:, None] * s.Bq)
        np.testing.assert_allclose(Kq, Knp, rtol=1e-12, atol=1e-12)
        fd = np.column_stack([(s.nonlinear_force(q + h * u) - s.nonlinear_force(q - h * u)) / (2 * h)
                              for u in np.eye(4)])
        np.testing.assert_allclose(Kq, fd, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("name", ["newmark", "gauss4", "gauss6"])
def test_exact_monodromy_against_finite_differences(name):
    m = nnm.Model(np.diag([1.0, 2.0]), np.array([[3.0, -1.0], [-1.0, 2.0]]),
                  [nnm.PolynomialStiffness([[3, 0], [2, 1], [1, 2], [0, 3], [2, 0], [1, 1], [0, 2]],
                                           [[1, 0], [0, 1], [1, 0], [0, 1], [0.3, 0.2], [0.4, 0], [0, 0.2]]),
                   nnm.CubicSpring(dof=0, k3=0.7)])
    s, it = ModalSystem(m), get_integrator(name)
    q0, v0, h, N, eps = np.array([0.3, -0.2]), np.array([0.1, 0.4]), 0.05, 40, 1e-6
    q, v, Sq, Sv, sqh, svh, ok = it.sensitivity(s, q0, v0, h, N)
    assert ok
    z0 = np.concatenate([q0, v0])
    fd = np.zeros((4, 4))
    for j in range(4):
        e = eps * np.eye(4)[j]
        a, b = it.state(s, *np.split(z0 + e, 2), h, N), it.state(s, *np.split(z0 - e, 2), h, N)
        fd[:, j] = (np.concatenate(a[:2]) - np.concatenate(b[:2])) / (2 * eps)
    np.testing.assert_allclose(np.vstack([Sq, Sv]), fd, atol=1e-8)
    a, b = it.state(s, q0, v0, h + eps, N), it.state(s, q0, v0, h - eps, N)
    np.testing.assert_allclose(np.concatenate([sqh, svh]), (np.concatenate(a[:2]) - np.concatenate(b[:2])) / (2 * eps),
                               rtol=1e-7, atol=1e-8)
    q2, v2, Sq2, Sv2, *_ = it.sensitivity(s, q0, v0, h, N, all_columns=False, velocities=False)
    np.testing.assert_allclose(Sq2, Sq[:, :2], rtol=1e-13, atol=1e-15)
    assert Sv2 is None


def _same_backbone(a, b, method, **kw):
    ba = nnm.continue_nnm(a, 1, 0.5, method, max_points=10, energy_min=1e-3, **kw)
    bb = nnm.continue_nnm(b, 1, 0.5, method, max_points=10, energy_min=1e-3, **kw)
    assert len(ba) == len(bb) == 10
    np.testing.assert_allclose(bb.energy, ba.energy, rtol=1e-9)
    np.testing.assert_allclose(bb.frequency_hz, ba.frequency_hz, rtol=1e-9)
    np.testing.assert_allclose(bb.x0, ba.x0, rtol=1e-9, atol=1e-9 * np.abs(ba.x0).max())
    assert list(ba.stable) == list(bb.stable)
    return ba, bb


@pytest.mark.parametrize("method, kw", [("shooting", {}), ("shooting", dict(integrator="newmark")), ("hb", {}),
                                        ("hb", dict(condensed=True))])
def test_springs_as_polynomial_stiffness_give_the_same_backbone(method, kw):
    """A 2-DOF model with a grounded cubic and a relative quadratic + cubic spring, and the same forces as two
    PolynomialStiffness elements (one on a DOF, one on the difference of the DOFs by ``directions``)."""
    M, K = np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]])
    a = nnm.Model(M, K, [nnm.CubicSpring(dof=0, k3=0.5),
                         nnm.PolynomialSpring(dof=1, other=0, coefficients={2: 0.3, 3: 0.2})])
    b = nnm.Model(M, K, [nnm.PolynomialStiffness([[3]], [[0.5]], dofs=[0]),
                         nnm.PolynomialStiffness([[2], [3]], [[0.3], [0.2]], dofs=[0, 1], directions=[[-1, 1]])])
    assert not b.elements.odd and b.elements.coupled
    ba, bb = _same_backbone(a, b, method, **kw)
    if method == "shooting":
        assert not bb.settings.symmetric                       # even terms: full-period shooting
    else:
        assert bb.settings.basis == "full"


def test_one_dof_duffing_as_polynomial_stiffness():
    """Odd: half-period shooting and the odd HB basis are chosen, the backbone is the cubic spring's."""
    a = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=0.5)])
    b = nnm.Model(np.eye(1), np.eye(1), [nnm.PolynomialStiffness([[3]], [[0.5]])])
    assert b.elements.odd
    ba, bb = _same_backbone(a, b, "shooting")
    assert bb.settings.symmetric
    ba, bb = _same_backbone(a, b, "hb")
    assert bb.settings.basis == "odd"


@pytest.fixture(scope="module")
def ex06_branches():
    model = example06()
    sh = nnm.continue_nnm(model, 1, 0.03, "shooting", max_points=40, energy_min=1e-4, tol=1e-11)
    hb = nnm.continue_nnm(model, 1, 0.03, "hb", harmonics=9, max_points=60, energy_min=1e-4, max_rel_step=0.1,
                          tol=1e-11)
    return model, sh, hb


def test_example06_shooting_and_hb_agree_within_their_error_estimates(ex06_branches):
    from scipy.interpolate import CubicSpline

    model, sh, hb = ex06_branches
    assert sh.status == "done" and hb.status == "done"
    assert not sh.settings.symmetric and hb.settings.basis == "full"        # quadratic terms: not odd
    err_sh = np.array([sh.point(i).freq_error for i in range(len(sh))])
    err_hb = np.array([hb.point(i).freq_error for i in range(len(hb))])
    assert np.all(err_sh < 1e-7) and np.all(err_hb < 1e-7)
    # HB's frequency at shooting's energies by a cubic spline in E (its interpolation error, measured by leaving
    # out every other point, stays below 1e-8 up to 0.015 J and 1e-7 at 0.03 J where HB steps are longest;
    # measured deviations: at most 3.6e-9)
    f_hb = CubicSpline(hb.energy, hb.frequency_hz)(sh.energy)
    inside = (sh.energy >= hb.energy[0]) & (sh.energy <= hb.energy[-1])
    bound = err_sh + np.interp(sh.energy, hb.energy, err_hb) + 1e-8
    assert np.all(np.abs(sh.frequency_hz / f_hb - 1)[inside] < bound[inside])
    assert sh.frequency_hz[-1] < OM1 / (2 * np.pi) * (1 - 1e-3)              # softening: the check resolves it


def test_example06_orbit_against_dop853_and_energy(ex06_branches):
    """The shooting orbit closes when integrated by DOP853 from its initial state over its period, and its
    energy (PolynomialStiffness.potential) is conserved along the DOP853 solution and equals the point's."""
    model, sh, _ = ex06_branches
    i = len(sh) - 1
    y0 = np.concatenate([sh.x0[i], sh.v0[i]])
    sol = solve_ivp(example06_rhs, (0, sh.period[i]), y0, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    assert np.abs(sol.y[:, -1] - y0).max() < 1e-7 * np.abs(y0).max()
    Y = sol.sol(np.linspace(0, sh.period[i], 50))
    E = model.energy(Y[:2].T, Y[2:].T)
    assert np.ptp(E) < 1e-10 * E.mean()
    assert E[0] == pytest.approx(sh.energy[i], rel=1e-12)
    t, x, v = sh.orbit(i, 64)                                            # the solver's own discrete orbit
    E = model.energy(x, v)
    assert np.ptp(E) < 1e-8 * E.mean()


def test_example06_stability_hill_and_floquet_agree(ex06_branches):
    _, sh, hb = ex06_branches
    assert np.all(sh.stable) and np.all(hb.stable)
    mu = hb.floquet[-1]
    assert np.all(np.abs(np.abs(mu) - 1) < 1e-6)


def test_reduced_order_model_on_a_subset_of_coordinates():
    """A ROM Model(I, diag(omega^2), [PolynomialStiffness]) with the element on two of three modal coordinates
    (dofs) and one with directions: the same backbone as the equivalent element on all coordinates, and the
    uncoupled third mode stays linear."""
    w2 = np.array([1.0, 3.1, 7.3])
    ex, co = [[3, 0], [1, 2], [2, 1], [0, 3]], [[0.2, 0.0], [0.3, 0.0], [0.0, 0.3], [0.0, 0.1]]
    sub = nnm.Model(np.eye(3), np.diag(w2), [nnm.PolynomialStiffness(ex, co, dofs=[0, 2])])
    ex3 = [[3, 0, 0], [1, 0, 2], [2, 0, 1], [0, 0, 3]]
    co3 = [[0.2, 0, 0], [0.3, 0, 0], [0, 0, 0.3], [0, 0, 0.1]]
    full = nnm.Model(np.eye(3), np.diag(w2), [nnm.PolynomialStiffness(ex3, co3)])
    _same_backbone(full, sub, "shooting")
    rows = nnm.Model(np.eye(3), np.diag(w2), [nnm.PolynomialStiffness(ex, co, directions=[[1, 0, 0], [0, 0, 1]])])
    ba, bb = _same_backbone(full, rows, "hb")
    assert np.abs(bb.x0[:, 1]).max() < 1e-12 * np.abs(bb.x0).max()


def test_elements_of_equal_exponents_are_one_group():
    """200 elements with the same exponents: one vectorised group, the same force and potential as their sum."""
    rng = np.random.default_rng(4)
    n = 101
    ex = [[1, 2], [0, 3], [2, 1], [3, 0]]
    els = []
    for k in range(200):
        a, b = rng.uniform(0.5, 2.0, size=2)
        # V = a d1^2 d2^2 / 2 + b d2^4 / 4: g = (a d1 d2^2, a d1^2 d2 + b d2^3)
        els.append(nnm.PolynomialStiffness(ex, [[a, 0], [0, b], [0, a], [0, 0]], dofs=[k % 100, k % 100 + 1],
                                           directions=[[1, 0], [-1, 1]]))
    m = nnm.Model(np.eye(n), np.eye(n), els)
    assert len(m.elements.groups) == 1 and m.elements.groups[0].rows.shape == (200, 2)
    x = rng.normal(size=(3, n))
    f = sum(e.matrix(n).T @ e.force(x @ e.matrix(n).T).T for e in els).T
    np.testing.assert_allclose(m.nonlinear_force(x), f, rtol=1e-12, atol=1e-12)
    V = sum(e.potential(x @ e.matrix(n).T) for e in els)
    np.testing.assert_allclose(m.energy(x, 0 * x) - 0.5 * np.sum(x * x, axis=1), V, rtol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    (dict(exponents=[[3, 0]], coefficients=[[1.0]]), "shape"),
    (dict(exponents=[[3, -1]], coefficients=[[1.0, 0]]), "non-negative integers"),
    (dict(exponents=[[2.5, 0]], coefficients=[[1.0, 0]]), "non-negative integers"),
    (dict(exponents=[[3, 0]], coefficients=[[np.nan, 0]]), "NaN or infinite"),
    (dict(exponents=[[1, 0]], coefficients=[[1.0, 0]]), "degree 1 < 2"),
    (dict(exponents=[[3, 0], [0, 3]], coefficients=[[0, 1.0], [1.0, 0]]), "not conservative"),
    (dict(exponents=[[3, 0]], coefficients=[[1.0, 0]], dofs=[0, 0]), "distinct"),
    (dict(exponents=[[3, 0]], coefficients=[[1.0, 0]], dofs=[0, 1, 2]), "3 dofs for 2 coordinates"),
    (dict(exponents=[[3, 0]], coefficients=[[1.0, 0]], directions=[[1, 0, 0]]), "directions have 1 rows"),
    (dict(exponents="x", coefficients=[[1.0]]), "numeric"),
])
def test_bad_input_one_line(kwargs, match):
    with pytest.raises(nnm.NNMInputError, match=match) as exc:
        nnm.PolynomialStiffness(**kwargs)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("element, match", [
    (nnm.PolynomialStiffness([[3, 0]], [[1.0, 0]], dofs=[0, 5]), "dof 5 is not a DOF"),
    (nnm.PolynomialStiffness([[3, 0, 0]], [[1.0, 0, 0]]), "has 3 coordinates and no dofs"),
])
def test_bad_element_for_the_model(element, match):
    with pytest.raises(nnm.NNMInputError, match=match):
        nnm.Model(np.eye(2), np.eye(2), [element])


def test_scaled_and_with_springs():
    m = example06()
    x = np.array([0.2, -0.1])
    np.testing.assert_allclose(m.scaled(2.0).nonlinear_force(x), 2 * m.nonlinear_force(x), rtol=1e-14)
    assert not m.elements.cubic_only


def test_model_and_branch_round_trip_through_the_file(tmp_path):
    """Coupled elements among springs (their order kept), on subsets with and without directions."""
    springs = [nnm.CubicSpring(dof=0, k3=0.4), nnm.PolynomialStiffness(EX3, CO3, dofs=[1, 2, 3]),
               nnm.PolynomialSpring(dof=2, other=1, coefficients={2: 0.1, 3: 0.3}),
               nnm.PolynomialStiffness([[3, 0], [1, 2], [2, 1], [0, 3]], [[1, 0], [1, 0], [0, 1], [0, 1]],
                                       dofs=[0, 2, 3], directions=[[1, -1, 0], [0, 0.5, 2]]),
               nnm.PolynomialStiffness([[3, 0, 0, 0]], [[2.0, 0, 0, 0]])]
    m = nnm.Model(np.eye(4), np.diag([1.0, 2.3, 3.7, 5.9]), springs, name="coupled")
    path = tmp_path / "m.h5"
    nnm.save_model(path, m)
    back = nnm.load_model(path)
    assert [type(s) for s in back.springs] == [type(s) for s in springs]
    for a, b in zip(springs, back.springs):
        if isinstance(a, nnm.PolynomialStiffness):
            assert a.dofs == b.dofs and np.array_equal(a.exponents, b.exponents)
            assert np.array_equal(a.coefficients, b.coefficients)
            assert (a.directions is None and b.directions is None) or np.array_equal(a.directions, b.directions)
    x = np.random.default_rng(5).normal(size=4)
    np.testing.assert_array_equal(back.nonlinear_force(x), m.nonlinear_force(x))
    path = tmp_path / "ex06.h5"
    br = nnm.continue_nnm(example06(), 1, 1e-3, max_points=4, energy_min=1e-5)
    nnm.save_model(path, br.model)
    nnm.save_branch(path, br)
    (b2,) = nnm.load_branches(path)
    np.testing.assert_array_equal(b2.frequency_hz, br.frequency_hz)
    assert isinstance(b2.model.springs[0], nnm.PolynomialStiffness)


def test_a_reader_without_coupled_elements_refuses_the_file(tmp_path):
    """The marker entry in /model/springs has a type older readers do not know: they refuse the file."""
    import json

    import h5py

    path = tmp_path / "m.h5"
    nnm.save_model(path, example06())
    with h5py.File(path, "r") as f:
        laws = json.loads(f["model/springs"].attrs["laws_json"])
    assert laws == [{"type": "polynomial_stiffness", "group": "/model/coupled"}]
    from nnm_solver.files.io import spring_from_json
    with pytest.raises(nnm.NNMFileError, match="unknown spring type 'polynomial_stiffness'"):
        spring_from_json(-1, None, laws[0])                # what a reader without /model/coupled does with it


def test_hb_and_condensed_jacobians_against_finite_differences():
    """The analytic Jacobians of HB (full Galerkin matrix of the coupled tangent) and of condensed HB (its full
    tangent blocks) on a model with springs and coupled elements, at a random orbit of the full basis."""
    from nnm_solver.orbits.condensed_hb import CondensedHBProblem
    from nnm_solver.orbits.harmonic_balance import HBProblem
    from nnm_solver.orbits.hb_basis import HBBasis

    springs = [nnm.CubicSpring(dof=0, k3=0.4), nnm.PolynomialStiffness(EX3, CO3, dofs=[1, 2, 3]),
               nnm.PolynomialStiffness([[3, 0], [1, 2], [2, 1], [0, 3]], [[1, 0], [1, 0], [0, 1], [0, 1]],
                                       dofs=[0, 2, 3], directions=[[1, -1, 0], [0, 0.5, 2]])]
    s = ModalSystem(nnm.Model(np.eye(4), np.diag([1.0, 5.3, 17.9, 45.1]), springs))
    rng = np.random.default_rng(0)
    for P in (HBProblem(s, 0, HBBasis(3, "full")), CondensedHBProblem(s, 0, HBBasis(3, "full"))):
        A = 0.1 * rng.normal(size=(len(P.basis), P._width))
        u = P.pack(A, 0.3, 1.05 * P.w_r) if isinstance(P, CondensedHBProblem) else P.pack(A, 1.05 * P.w_r)
        r, J = P.jacobian(u)
        h = 1e-7
        fd = np.column_stack([(P.residual(u + h * e) - P.residual(u - h * e)) / (2 * h) for e in np.eye(len(u))])
        assert np.abs(J - fd).max() < 1e-6 * np.abs(J).max()


def test_hill_multipliers_against_the_variational_equations(ex06_branches):
    """Hill's multipliers (dense route with the coupled Galerkin matrix) of the last HB point of example 06 against
    the monodromy of the variational equations integrated by DOP853 along the orbit."""
    model, _, hb = ex06_branches
    i = len(hb) - 1
    T = hb.period[i]

    def rhs(t, y):
        z, Phi = y[:4], y[4:].reshape(4, 4)
        h = 1e-6
        Jz = np.column_stack([(np.array(example06_rhs(t, z + h * e)) - example06_rhs(t, z - h * e)) / (2 * h)
                              for e in np.eye(4)])
        return np.concatenate([example06_rhs(t, z), (Jz @ Phi).ravel()])

    y0 = np.concatenate([hb.x0[i], hb.v0[i], np.eye(4).ravel()])
    sol = solve_ivp(rhs, (0, T), y0, method="DOP853", rtol=1e-11, atol=1e-13)
    mu_ref = np.linalg.eigvals(sol.y[4:, -1].reshape(4, 4))
    mu = hb.floquet[i]
    assert np.all(np.abs(np.abs(mu) - 1) < 1e-6)
    # the non-trivial pair (the trivial pair at +1 is a Jordan block: its computed split is the square root of the
    # integration error, 1.5e-5 here)
    pair, pair_ref = (m[np.argsort(-np.abs(np.angle(m)))[:2]] for m in (mu, mu_ref))
    assert np.abs(np.angle(pair[0])) > 0.1
    np.testing.assert_allclose(np.sort(np.angle(pair)), np.sort(np.angle(pair_ref)), atol=1e-7)
    np.testing.assert_allclose(np.abs(pair_ref), 1.0, atol=1e-7)


def test_forced_response_condensed_and_full_agree():
    """Forced HB of example 06 (NLvib's damping and forcing, 3e-4 [1, 1] cos): the condensed equations (full tangent
    blocks of the coupled element) and the uncondensed ones (its Galerkin matrix) give the same curve."""
    model = example06()
    f_range = (1.10 / (2 * np.pi), 1.15 / (2 * np.pi))
    kw = dict(harmonics=5, max_points=12, damping=[1e-3, 5e-3])
    a = nnm.forced_response(model, [3e-4, 3e-4], f_range, condensed=False, **kw)
    b = nnm.forced_response(model, [3e-4, 3e-4], f_range, condensed=True, **kw)
    from scipy.interpolate import CubicSpline

    assert len(a.frequency_hz) == len(b.frequency_hz) == 12
    np.testing.assert_allclose(b.frequency_hz[:6], a.frequency_hz[:6], rtol=1e-9)        # the same first steps
    np.testing.assert_allclose(b.amplitude(0)[:6], a.amplitude(0)[:6], rtol=1e-8)
    assert np.all(np.diff(a.frequency_hz) > 0) and np.all(np.diff(b.frequency_hz) > 0)
    inside = b.frequency_hz <= a.frequency_hz[-1]                  # then other steps: the same curve
    amp = CubicSpline(a.frequency_hz, a.amplitude(0))(b.frequency_hz[inside])
    np.testing.assert_allclose(b.amplitude(0)[inside], amp, rtol=1e-4)    # (the spline's error: 1.1e-5 measured)
