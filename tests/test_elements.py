"""Nonlinear elements beyond the cubic spring (issue 18, polynomial part): force laws, the automatic
full-period shooting for even powers, an independent DOP853 period, harmonic balance, files."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nnm_solver as nnm


def test_polynomial_force_tangent_potential_by_finite_differences():
    m = nnm.Model(np.eye(3), np.diag([1.0, 2.0, 3.0]),
                  [nnm.PolynomialSpring(dof=0, coefficients={2: 0.7, 3: -0.2, 5: 0.05}),
                   nnm.PolynomialSpring(dof=2, other=1, coefficients={4: 1.5})])
    el, h = m.elements, 1e-6
    d = np.random.default_rng(3).normal(size=(6, 2))
    np.testing.assert_allclose(el.tangent(d), (el.force(d + h) - el.force(d - h)) / (2 * h), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(el.force(d), (el.potential(d + h) - el.potential(d - h)) / (2 * h), rtol=1e-6,
                               atol=1e-9)
    assert not el.odd
    x = np.array([0.3, -0.2, 0.5])
    np.testing.assert_allclose(m.nonlinear_force(x), [0.7 * 0.09 - 0.2 * 0.027 + 0.05 * 0.3 ** 5,
                                                      -1.5 * 0.7 ** 4, 1.5 * 0.7 ** 4], rtol=1e-12)


@pytest.mark.parametrize("bad, match", [({1: 2.0}, "power 1 < 2"), ({2.5: 1.0}, "not an integer"),
                                        ({3: float("nan")}, "not finite"), ({}, "at least one")])
def test_polynomial_bad_input(bad, match):
    with pytest.raises(nnm.NNMInputError, match=match):
        nnm.PolynomialSpring(dof=0, coefficients=bad)


def test_quadratic_cubic_oscillator_period_against_dop853():
    """x'' + x + k2 x^2 + k3 x^3 = 0: not odd, so the solver shoots over the full period (orbits from
    rest); its period converges to the DOP853 one as N^-2."""
    k2, k3 = 0.3, 0.5
    m = nnm.Model(np.eye(1), np.eye(1), [nnm.PolynomialSpring(dof=0, coefficients={2: k2, 3: k3})])
    b = nnm.continue_nnm(m, 1, 2.0, steps_per_period=1000)
    assert b.status == "done" and not b.settings.symmetric and b.settings.reversible
    i = len(b) // 2

    def rhs(t, y):
        return [y[1], -y[0] - k2 * y[0] ** 2 - k3 * y[0] ** 3]

    down = lambda t, y: y[1]
    down.direction = -1                                   # back at the starting turning point
    sol = solve_ivp(rhs, [0, 3 * b.period[i]], [b.x0[i, 0], 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    events=down)
    T_ref = sol.t_events[0][sol.t_events[0] > 1e-3][0]
    assert b.period[i] == pytest.approx(T_ref, rel=1e-5)   # Newmark at 1000 steps: ~3e-6
    hb = nnm.continue_nnm(m, 1, 2.0, method="hb", harmonics=15)
    assert hb.settings.basis == "full"
    assert np.interp(b.energy[i], hb.energy, hb.frequency_hz) == pytest.approx(b.frequency_hz[i], rel=1e-5)
    t, x, v = b.orbit(i, 128)
    E = m.energy(x, v)
    assert np.ptp(E) < 1e-4 * E.mean()                     # energy conserved along the orbit (O(h^2))


def test_polynomial_springs_survive_the_file(tmp_path):
    springs = [nnm.PolynomialSpring(dof=0, coefficients={2: 0.3, 3: 0.5}), nnm.CubicSpring(dof=1, other=0, k3=2.0)]
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs)
    nnm.save_model(tmp_path / "m.h5", m)
    assert nnm.load_model(tmp_path / "m.h5").springs == springs
    b = nnm.continue_nnm(m, 1, 1.0, max_points=8)
    with pytest.raises(nnm.NNMInputError, match="cubic springs only"):
        b.scaled(2.0)


# ---------------------------------------------------------------------- PiecewiseLinearSpring (issue 18)
def _bilinear_period(A, k, k0, k1, d1):
    """Exact period of x'' + k x + f(x) = 0, f bilinear (slope k0 for |x| < d1, k1 beyond), amplitude A.

    |x| < d1: harmonic with w0^2 = k + k0.  x >= d1: the restoring force (k + k0) d1 + (k + k1)(x - d1)
    = (k + k1)(x - c), harmonic with w1^2 = k + k1 about the shifted centre c = d1 (k1 - k0) / (k + k1).
    From rest at A: t1 = arccos((d1 - c) / (A - c)) / w1 to reach d1 with speed v = w1 sqrt((A - c)^2
    - (d1 - c)^2); then the inner arc of amplitude B = sqrt(d1^2 + v^2 / w0^2) takes t0 = arcsin(d1 / B)
    / w0 to reach 0.  By symmetry T = 4 (t0 + t1).
    """
    w0, w1 = np.sqrt(k + k0), np.sqrt(k + k1)
    if A <= d1:
        return 2 * np.pi / w0
    c = d1 * (k1 - k0) / (k + k1)
    t1 = np.arccos((d1 - c) / (A - c)) / w1
    B = np.sqrt(d1 ** 2 + (w1 / w0) ** 2 * ((A - c) ** 2 - (d1 - c) ** 2))
    return 4 * (np.arcsin(d1 / B) / w0 + t1)


def test_piecewise_force_tangent_potential_and_kernels():
    pw = nnm.PiecewiseLinearSpring(dof=1, other=0, stiffnesses=[2.0, 0.5, 3.0], breakpoints=[0.1, 0.25], eps=0.05)
    m = nnm.Model(np.eye(3), np.diag([1.0, 2.0, 3.0]),
                  [nnm.PolynomialSpring(dof=0, coefficients={3: 0.4}), pw,
                   nnm.PiecewiseLinearSpring(dof=2, stiffnesses=[0.0, 1.0], breakpoints=[0.05])])
    el, h = m.elements, 1e-7
    assert el.kinks.shape == (3, 2, 3) and el.odd and not el.cubic_only
    d = np.random.default_rng(5).normal(scale=0.2, size=(200, 3))
    np.testing.assert_allclose(el.tangent(d), (el.force(d + h) - el.force(d - h)) / (2 * h), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(el.force(d), (el.potential(d + h) - el.potential(d - h)) / (2 * h), rtol=1e-6,
                               atol=1e-8)
    np.testing.assert_allclose(el.force(-d), -el.force(d), atol=1e-15)                     # odd
    _kernels_match(el, d[:20])
    # the regularised nonlinear part + k0 d is the exact law away from the kinks (within ~w = eps d1)
    s = np.array([0.03, -0.05, 0.2, -0.4, 1.0])
    exact = pw.exact_force(s)
    np.testing.assert_allclose(el.force(np.c_[0 * s, s, 0 * s])[:, 1] + 2.0 * s, exact, atol=1e-6)
    assert pw.exact_force(0.3) == pytest.approx(2.0 * 0.1 + 0.5 * 0.15 + 3.0 * 0.05)
    # the linear model carries k0: K_linear = K + k0 b^T b; the energy is exact (potential of the whole force)
    np.testing.assert_allclose(m.K_linear, np.diag([1.0, 2.0, 3.0]) + 2.0 * np.array([[1, -1, 0], [-1, 1, 0], [0, 0, 0]]))
    x = np.array([0.02, -0.03, 0.3])
    P_exact = 0.5 * x @ np.diag([1.0, 2.0, 3.0]) @ x + 0.1 * 0.02 ** 4 + 0.5 * 2.0 * 0.05 ** 2 + 0.5 * 0.25 ** 2
    assert m.energy(x, np.zeros(3)) == pytest.approx(P_exact, rel=1e-5)
    one = nnm.Model(np.eye(1), np.eye(1), [nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.5, 2.0], breakpoints=[0.1])])
    assert one.linear_modes()[0][0] == pytest.approx(np.sqrt(1.5) / (2 * np.pi), rel=1e-14)
    assert one.elements.tangent(np.zeros(1))[0] == 0.0                                  # nothing below d1


@pytest.mark.parametrize("kw, match", [
    (dict(stiffnesses=[1.0, 2.0, 3.0], breakpoints=[0.2, 0.1]), "not strictly increasing"),
    (dict(stiffnesses=[1.0, 2.0], breakpoints=[-0.1]), "not positive"),
    (dict(stiffnesses=[1.0, 2.0], breakpoints=[0.0]), "not positive"),
    (dict(stiffnesses=[1.0, 2.0], breakpoints=[0.1, 0.2]), "one more stiffness"),
    (dict(stiffnesses=[1.0, float("nan")], breakpoints=[0.1]), "NaN"),
    (dict(stiffnesses=[1.0, 2.0], breakpoints=[float("nan")]), "NaN"),
    (dict(stiffnesses=[1.0], breakpoints=[]), "at least one breakpoint"),
    (dict(stiffnesses=[1.0, 2.0], breakpoints=[0.1], eps=0.0), "eps"),
])
def test_piecewise_bad_input(kw, match):
    with pytest.raises(nnm.NNMInputError, match=match) as exc:
        nnm.PiecewiseLinearSpring(dof=0, **kw)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("k1", [2.0, -0.5])                       # hardening, softening past d1
def test_bilinear_oscillator_period_converges_with_the_regularisation(k1):
    """x'' + x + f(x) = 0 with a bilinear spring (k0 = 0.5, k1, d1 = 0.1) against the closed-form period:
    the regularisation error falls as eps^2 (3e-4, 3e-5, <1e-6 at eps = 3e-2, 1e-2, 1e-3), and at the
    smallest eps the remaining error is Newmark's O(h^2)."""
    k, k0, d1 = 1.0, 0.5, 0.1

    def max_error(eps, spp):
        m = nnm.Model(np.eye(1), k * np.eye(1),
                      [nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[k0, k1], breakpoints=[d1], eps=eps)])
        b = nnm.continue_nnm(m, 1, 0.2, energy_min=0.5 * (k + k0) * (1.5 * d1) ** 2, steps_per_period=spp,
                             max_points=12, integrator="newmark")        # Newmark's O(h^2) is what is measured
        assert len(b) >= 8 and b.settings.symmetric
        A = np.abs(b.x0[:, 0])
        assert A.min() > d1
        T = np.array([_bilinear_period(a, k, k0, k1, d1) for a in A])
        t, x, v = b.orbit(len(b) - 1, 128)                               # energy conserved along an orbit
        E = m.energy(x, v)
        assert np.ptp(E) < 1e-4 * E.mean()                               # O(h^2): ~2e-5
        return np.max(np.abs(b.period / T - 1))

    errors = [max_error(eps, 2000) for eps in (3e-2, 1e-2, 1e-3)]
    assert errors[0] > 3 * errors[1] > 3 * errors[2]
    assert errors[2] < 1e-5
    assert max_error(1e-3, 500) > 5 * errors[2]                          # the rest is the time step's


def test_piecewise_springs_survive_the_file_and_refuse_the_scaling_law(tmp_path):
    springs = [nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.5, -0.2, 1.0], breakpoints=[0.1, 0.3], eps=2e-3),
               nnm.CubicSpring(dof=1, other=0, k3=2.0), nnm.PolynomialSpring(dof=1, coefficients={3: 0.1, 5: 0.2})]
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs)
    nnm.save_model(tmp_path / "m.h5", m)
    back = nnm.load_model(tmp_path / "m.h5")
    assert back.springs == springs
    np.testing.assert_array_equal(back.K, m.K)                            # K is saved as given, without k0
    b = nnm.continue_nnm(m, 1, 0.5, max_points=6)
    assert b.status in ("done", "max_points")
    with pytest.raises(nnm.NNMInputError, match="cubic springs only"):
        b.scaled(2.0)


def test_piecewise_shooting_agrees_with_harmonic_balance_on_the_2dof():
    pw = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.5, 2.0], breakpoints=[0.1], eps=1e-2)
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [pw])
    b = nnm.continue_nnm(m, 1, 0.3, steps_per_period=400, max_points=40)
    hb = nnm.continue_nnm(m, 1, 0.3, method="hb", harmonics=25, max_points=60)
    assert b.status == hb.status == "done" and hb.settings.basis == "odd"
    assert b.frequency_hz[-1] > 1.05 * b.frequency_hz[0]                # hardening past the kink (~10 %)
    sel = b.energy <= hb.energy.max()
    np.testing.assert_allclose(np.interp(b.energy[sel], hb.energy, hb.frequency_hz), b.frequency_hz[sel], rtol=1e-4)


def test_laws_json_type_key(tmp_path):
    import h5py
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]),
                  [nnm.PolynomialSpring(dof=0, coefficients={2: 0.3, 3: 0.5}),
                   nnm.PiecewiseLinearSpring(dof=1, stiffnesses=[1.0, 0.2], breakpoints=[0.1])])
    path = tmp_path / "m.h5"
    nnm.save_model(path, m)
    with h5py.File(path, "r+") as f:
        a = f["model/springs"].attrs
        laws = __import__("json").loads(a["laws_json"])
        assert laws[1]["type"] == "piecewise_linear" and "type" not in laws[0]    # polynomial entries unchanged
        laws[0]["type"] = "polynomial"
        del laws[1]["eps"]                                                        # optional: default 1e-3
        a["laws_json"] = __import__("json").dumps(laws)
    assert nnm.load_model(path).springs == m.springs
    with h5py.File(path, "r+") as f:
        f["model/springs"].attrs["laws_json"] = '[{"3": 1.0}, {"type": "gap"}]'
    with pytest.raises(nnm.NNMFileError, match="unknown spring type 'gap'"):
        nnm.load_model(path)


# ------------------------------------------- monodromy, energy and periods across the kinks (issue 18)
def _monodromy_and_fd(model, branch, i, mode=1, delta=1e-7):
    """Exact monodromy (2n, 2n) of point i (ShootingProblem: square of the half-period sensitivity
    of newmark.sweep_sensitivity) and central finite differences of the full-period discrete map, in
    modal coordinates [q; v]."""
    from nnm_solver.model.modal import modal_system
    from nnm_solver.integrators.newmark import sweep_state
    from nnm_solver.orbits.shooting import ShootingProblem
    ms = modal_system(model)
    N = branch.settings.steps_per_period
    q0, v0, T = ms.to_modal(branch.x0[i]), ms.to_modal(branch.v0[i]), branch.period[i]
    prob = ShootingProblem(ms, mode - 1, N, symmetric=True)
    prob.all_columns = True
    u = prob.pack(q0, v0, T)
    prob.jacobian(u)
    prob.accept(u, None)
    z0, n = np.concatenate([q0, v0]), len(q0)
    cols = []
    for dz in delta * np.eye(2 * n):
        qp, vp, okp = sweep_state(*np.split(z0 + dz, 2), T / N, N, *ms.kernel)
        qm, vm, okm = sweep_state(*np.split(z0 - dz, 2), T / N, N, *ms.kernel)
        assert okp and okm
        cols.append(np.concatenate([qp - qm, vp - vm]) / (2 * delta))
    return prob.monodromy(), np.column_stack(cols)


@pytest.mark.parametrize("eps, rel", [(1e-2, 1e-3), (1e-3, 1e-4)])
def test_monodromy_across_a_kink_single_dof(eps, rel):
    """x'' + x + f(x) = 0, bilinear f (k0 = 0.5, k1 = 2, d1 = 0.1), an orbit of amplitude A ~ 1.65 d1
    that crosses the kink four times per period.  (i) The exact monodromy of the discrete map equals
    its central finite differences (step 1e-7 < kink width eps d1).  (ii) Independent physics: the
    bilinear force is continuous, so the switching instants carry no saltation jump and the monodromy
    of the nonsmooth flow is [[1, 0], [T'(A) F(A), 1]] for an orbit from rest at x = A (F(A) = A +
    f(A) the restoring force, T(A) the closed-form period); the regularised one converges to it."""
    k, k0, k1, d1 = 1.0, 0.5, 2.0, 0.1
    pw = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[k0, k1], breakpoints=[d1], eps=eps)
    m = nnm.Model(np.eye(1), k * np.eye(1), [pw])
    b = nnm.continue_nnm(m, 1, 0.2, energy_min=0.5 * (k + k0) * (1.5 * d1) ** 2, steps_per_period=2000,
                         max_points=12)
    i = len(b) // 2
    A = b.x0[i, 0]
    assert 1.5 * d1 < A < 2 * d1
    Mo, fd = _monodromy_and_fd(m, b, i)
    np.testing.assert_allclose(Mo, fd, rtol=1e-6, atol=1e-6 * np.abs(Mo).max())
    dT = (_bilinear_period(A + 1e-6, k, k0, k1, d1) - _bilinear_period(A - 1e-6, k, k0, k1, d1)) / 2e-6
    assert Mo[1, 0] == pytest.approx(dT * (k * A + float(pw.exact_force(A))), rel=rel)   # eps=1e-2: 4.5e-4
    np.testing.assert_allclose([Mo[0, 0], Mo[1, 1], Mo[0, 1]], [1.0, 1.0, 0.0], atol=1e-3)


def test_monodromy_and_energy_across_kinks_two_dof():
    """2-DOF benchmark (M = I, K = [[2, -1], [-1, 2]]) with a relative three-slope spring (k = 1, 0.2, 3;
    breakpoints 0.1, 0.3 m) between the masses and a grounded clearance (k0 = 0, gap 0.05 m) on DOF 0:
    an NNM2 orbit that crosses all three kinks.  Exact monodromy vs finite differences of the
    discrete map; its non-trivial multipliers are the stored ones; energy conserved along the orbit."""
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    springs = [nnm.PiecewiseLinearSpring(dof=1, other=0, stiffnesses=[1.0, 0.2, 3.0], breakpoints=[0.1, 0.3]),
               nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.0, 2.0], breakpoints=[0.05])]
    m = nnm.Model(np.eye(2), K, springs)
    b = nnm.continue_nnm(m, 2, 1.0, steps_per_period=400, max_points=30, integrator="newmark")   # _monodromy_and_fd's map
    i = len(b) - 1
    t, x, v = b.orbit(i, 256)
    assert np.abs(x[:, 1] - x[:, 0]).max() > 0.4 and np.abs(x[:, 0]).max() > 0.2      # past every breakpoint
    Mo, fd = _monodromy_and_fd(m, b, i, mode=2)
    np.testing.assert_allclose(Mo, fd, rtol=1e-6, atol=1e-6 * np.abs(Mo).max())
    mu = np.linalg.eigvals(Mo)
    nontrivial = np.sort_complex(mu[np.abs(mu.imag) > 1e-2])             # the trivial pair is real near 1
    stored = np.sort_complex(b.floquet[i][np.abs(b.floquet[i] - 1) > 1e-2])
    assert len(nontrivial) == 2 and np.allclose(nontrivial, stored, atol=1e-3)
    E = m.energy(x, v)
    assert np.ptp(E) < 1e-4 * E.mean()                                    # O(h^2): ~3e-5


def test_gap_oscillator_period_against_closed_form():
    """Clearance: x'' + x + f(x) = 0 with f = 0 for |x| < 0.1 m and slope 3 N/m beyond (k0 = 0): the
    linear frequency is K's alone and the period follows the closed form (harmonic arcs of w0 = 1
    inside the gap and w1 = 2 about the shifted centre outside) to Newmark's O(h^2)."""
    k, k1, d1 = 1.0, 3.0, 0.1
    m = nnm.Model(np.eye(1), k * np.eye(1), [nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.0, k1],
                                                                        breakpoints=[d1])])
    assert m.linear_modes()[0][0] == pytest.approx(1 / (2 * np.pi), rel=1e-14)
    b = nnm.continue_nnm(m, 1, 0.5, energy_min=0.5 * k * (1.2 * d1) ** 2, steps_per_period=2000, max_points=15,
                         max_period_step=0.05)
    assert len(b) >= 8 and b.settings.symmetric
    A = np.abs(b.x0[:, 0])
    assert A.min() > d1 and A.max() > 5 * d1
    T = np.array([_bilinear_period(a, k, 0.0, k1, d1) for a in A])
    np.testing.assert_allclose(b.period, T, rtol=5e-6)
    assert T[-1] < 0.7 * 2 * np.pi                                       # far into the stiff side
    t, x, v = b.orbit(len(b) - 1, 128)
    E = m.energy(x, v)
    assert np.ptp(E) < 1e-4 * E.mean()


# ------------------------------------------------ asymmetric piecewise-linear spring (tension != compression)
def _side_potential(A, k, k0, k1, d1):
    """Potential (J) of x'' + k x + f(x) = 0 at |x| = A on one side of a bilinear law (slopes k0, k1, kink d1)."""
    if A <= d1:
        return 0.5 * (k + k0) * A ** 2
    return 0.5 * (k + k0) * d1 ** 2 + (k + k0) * d1 * (A - d1) + 0.5 * (k + k1) * (A - d1) ** 2


def test_asymmetric_piecewise_force_tangent_potential_and_kernels():
    asym = nnm.PiecewiseLinearSpring(dof=1, other=0, stiffnesses=[2.0, 0.5, 3.0], breakpoints=[0.1, 0.25],
                                     stiffnesses_negative=[2.0, 6.0], breakpoints_negative=[0.05], eps=0.05)
    m = nnm.Model(np.eye(3), np.diag([1.0, 2.0, 3.0]),
                  [asym, nnm.PiecewiseLinearSpring(dof=2, stiffnesses=[0.0, 1.0], breakpoints=[0.05]),
                   nnm.CubicSpring(dof=0, k3=0.4)])
    el, h = m.elements, 1e-7
    assert el.kinks.shape == (3, 3, 4) and not el.odd and not asym.symmetric
    np.testing.assert_array_equal(el.kinks[0, :, 3], [1, 1, -1])
    np.testing.assert_array_equal(el.kinks[1, :, 3], [0, 0, 0])                         # odd rows stay two-sided
    d = np.random.default_rng(7).normal(scale=0.2, size=(200, 3))
    np.testing.assert_allclose(el.tangent(d), (el.force(d + h) - el.force(d - h)) / (2 * h), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(el.force(d), (el.potential(d + h) - el.potential(d - h)) / (2 * h), rtol=1e-6,
                               atol=1e-8)
    _kernels_match(el, d[:20])
    # exact law: tension 2 -> 0.5 at 0.1 -> 3 at 0.25; compression 2 -> 6 at 0.05
    assert asym.exact_force(0.3) == pytest.approx(2.0 * 0.1 + 0.5 * 0.15 + 3.0 * 0.05)
    assert asym.exact_force(-0.3) == pytest.approx(-(2.0 * 0.05 + 6.0 * 0.25))
    s = np.array([0.03, -0.01, 0.2, -0.2, 0.4, -0.4])               # >= 16 kink widths from the kinks
    np.testing.assert_allclose(el.force(np.c_[s, 0 * s, 0 * s])[:, 0] + 2.0 * s, asym.exact_force(s), atol=1e-6)
    P = m.energy(np.array([0.0, -0.2, 0.0]), np.zeros(3))                                 # d = -0.2: compression
    # exact 0.125 J; the smoothing adds dk w^2 pi^2 / 6 = 4.1e-5 J (w = eps d1' = 2.5e-3 m)
    assert P == pytest.approx(0.125 + 4.0 * 2.5e-3 ** 2 * np.pi ** 2 / 6, rel=1e-6)
    # the same law on both sides is the odd spring; a scaled spring scales both sides
    same = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[1.0, 2.0], breakpoints=[0.1],
                                     stiffnesses_negative=[1.0, 2.0], breakpoints_negative=[0.1])
    assert same == nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[1.0, 2.0], breakpoints=[0.1]) and same.symmetric
    assert asym.scaled(2.0).exact_force(-0.3) == pytest.approx(2 * asym.exact_force(-0.3))
    # a contact engaging in compression only: linear (k0) in tension, no breakpoint on that side
    contact = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[1.0], breakpoints=[], stiffnesses_negative=[1.0, 5.0],
                                        breakpoints_negative=[0.1])
    one = nnm.Model(np.eye(1), np.eye(1), [contact])
    assert one.elements.kinks.tolist() == [[[4.0, 0.1, 1e-4, -1.0]]] and not one.elements.odd
    np.testing.assert_allclose(contact.exact_force([0.5, -0.5]), [0.5, -(0.1 + 5.0 * 0.4)])
    np.testing.assert_allclose(one.elements.force(np.array([[0.5], [-0.5]]))[:, 0], [0.0, -4.0 * 0.4], atol=1e-12)


@pytest.mark.parametrize("kw, match", [
    (dict(stiffnesses_negative=[1.0, 3.0]), "give both stiffnesses_negative and breakpoints_negative"),
    (dict(breakpoints_negative=[0.1]), "give both"),
    (dict(stiffnesses_negative=[0.5, 3.0], breakpoints_negative=[0.1]), "slope k0 at d = 0 is shared"),
    (dict(stiffnesses_negative=[1.0, 3.0, 4.0], breakpoints_negative=[0.2, 0.1]), "breakpoints_negative .* not strictly"),
    (dict(stiffnesses_negative=[1.0, 3.0], breakpoints_negative=[-0.1]), "breakpoint_negative -0.1 is not positive"),
    (dict(stiffnesses_negative=[1.0, 3.0], breakpoints_negative=[0.1, 0.2]), "stiffnesses_negative for 2"),
    (dict(stiffnesses_negative=[1.0, float("nan")], breakpoints_negative=[0.1]), "NaN"),
    (dict(stiffnesses=[1.0], breakpoints=[], stiffnesses_negative=[1.0], breakpoints_negative=[]),
     "at least one breakpoint \\(on either side\\)"),
])
def test_asymmetric_piecewise_bad_input(kw, match):
    kw = {"stiffnesses": [1.0, 2.0], "breakpoints": [0.1], **kw}
    with pytest.raises(nnm.NNMInputError, match=match) as exc:
        nnm.PiecewiseLinearSpring(dof=0, **kw)
    assert "\n" not in str(exc.value)


def test_asymmetric_oscillator_period_against_closed_form():
    """x'' + x + f(x) = 0, f stiffening in tension (0.5 -> 2 N/m at 0.1 m) and softening in compression
    (0.5 -> 0.1 N/m at 0.05 m).  Not odd: the driver shoots over the full period from rest.  The period
    is half the period of the tension law at amplitude A+ plus half that of the compression law at A-,
    the two turning points having the same potential energy."""
    from scipy.optimize import brentq
    k, k0, kp, dp, kn, dn = 1.0, 0.5, 2.0, 0.1, 0.1, 0.05
    m = nnm.Model(np.eye(1), k * np.eye(1), [nnm.PiecewiseLinearSpring(
        dof=0, stiffnesses=[k0, kp], breakpoints=[dp], stiffnesses_negative=[k0, kn], breakpoints_negative=[dn])])
    b = nnm.continue_nnm(m, 1, 0.05, steps_per_period=2000, max_points=30, max_period_step=0.05)
    assert b.status == "done" and not b.settings.symmetric and b.settings.reversible
    T = []
    for x0 in b.x0[:, 0]:
        A, law, other = abs(x0), (kp, dp) if x0 > 0 else (kn, dn), (kn, dn) if x0 > 0 else (kp, dp)
        B = brentq(lambda a: _side_potential(a, k, k0, *other) - _side_potential(A, k, k0, *law), 0.0, 10.0)
        T.append(0.5 * _bilinear_period(A, k, k0, *law) + 0.5 * _bilinear_period(B, k, k0, *other))
    assert abs(b.x0[-1, 0]) > 2 * dp
    np.testing.assert_allclose(b.period, T, rtol=3e-6)                       # measured 1.1e-6
    t, x, v = b.orbit(len(b) - 1, 128)
    assert x[:, 0].max() > 2 * dp and x[:, 0].min() < -2 * dn and x[:, 0].max() + x[:, 0].min() < -dn  # A- > A+
    E = m.energy(x, v)
    assert np.ptp(E) < 1e-4 * E.mean()


def test_asymmetric_shooting_agrees_with_harmonic_balance_on_the_2dof():
    """2-DOF benchmark with an asymmetric bilinear spring on DOF 0: full-period shooting and harmonic
    balance on the full (odd + even harmonics) basis, both chosen automatically, give the same
    backbone (measured 1.0e-5 at 1000 steps per period; 400 steps: 2.9e-5, Newmark's O(h^2))."""
    from scipy.interpolate import CubicSpline
    pw = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.5, 2.0], breakpoints=[0.1], stiffnesses_negative=[0.5, 0.1],
                                   breakpoints_negative=[0.05], eps=1e-2)
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [pw])
    b = nnm.continue_nnm(m, 1, 0.3, steps_per_period=1000, max_points=40)
    hb = nnm.continue_nnm(m, 1, 0.3, method="hb", harmonics=25, max_points=300, max_period_step=0.001)
    assert b.status == hb.status == "done"
    assert not b.settings.symmetric and b.settings.reversible and hb.settings.basis == "full"
    t, x, v = b.orbit(len(b) - 1, 256)
    assert x[:, 0].max() > 0.3 and x[:, 0].min() < -0.3                       # both kinks crossed
    sel = b.energy <= hb.energy.max()
    np.testing.assert_allclose(CubicSpline(hb.energy, hb.frequency_hz)(b.energy[sel]), b.frequency_hz[sel], rtol=3e-5)
    with pytest.raises(nnm.NNMInputError, match="symmetric=True"):
        nnm.continue_nnm(m, 1, 0.3, symmetric=True)


def test_asymmetric_springs_survive_the_file(tmp_path):
    import json
    import h5py
    springs = [nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.5, 2.0], breakpoints=[0.1], eps=2e-3,
                                         stiffnesses_negative=[0.5, 0.1, 1.0], breakpoints_negative=[0.05, 0.2]),
               nnm.PiecewiseLinearSpring(dof=1, other=0, stiffnesses=[1.0, 0.2], breakpoints=[0.1]),
               nnm.PiecewiseLinearSpring(dof=1, stiffnesses=[0.3], breakpoints=[], stiffnesses_negative=[0.3, 4.0],
                                         breakpoints_negative=[0.02])]
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs)
    path = tmp_path / "m.h5"
    nnm.save_model(path, m)
    assert nnm.load_model(path).springs == springs
    with h5py.File(path, "r+") as f:
        laws = json.loads(f["model/springs"].attrs["laws_json"])
        assert laws[0]["type"] == "piecewise_linear_asymmetric" and laws[1]["type"] == "piecewise_linear"
        laws[1]["stiffnesses_negative"] = [1.0, 3.0]               # a key the odd type does not have
        f["model/springs"].attrs["laws_json"] = json.dumps(laws)
    with pytest.raises(nnm.NNMFileError, match="piecewise_linear spring with unknown key"):
        nnm.load_model(path)


@pytest.mark.parametrize("make, match", [
    (lambda: nnm.CubicSpring(dof=0, k3="stiff"), "CubicSpring k3='stiff' is not a number"),
    (lambda: nnm.CubicSpring(dof=0, k3=None), "CubicSpring k3=None is not a number"),
    (lambda: nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=float("nan"))]), "d\\^3 is nan, not finite"),
    (lambda: nnm.PolynomialSpring(dof=0, coefficients=[3, 1.0]), "coefficients must be a dict"),
    (lambda: nnm.PolynomialSpring(dof=0, coefficients={0: 1.0}), "power 0 < 2"),
    (lambda: nnm.PolynomialSpring(dof=0, coefficients={3: None}), "d\\^3 is None, not a number"),
    (lambda: nnm.PiecewiseLinearSpring(dof=0, stiffnesses=None, breakpoints=[0.1]), "must be a list of numbers"),
    (lambda: nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[1, float("inf")], breakpoints=[0.1]), "infinite"),
    (lambda: nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[1, 2, 3], breakpoints=[0.1, 0.1]), "not strictly"),
    (lambda: nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[1, 2], breakpoints=[0.1], eps=float("nan")), "eps=nan"),
    (lambda: nnm.Model(np.eye(1), np.eye(1), [nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[-2, 2], breakpoints=[0.1])])
     .linear_modes(), "K plus the piecewise-linear springs' slopes k0 is not positive semi-definite"),
])
def test_bad_element_input_is_one_line(make, match):
    """Every malformed element gives one NNMInputError line (no TypeError/ValueError from deep inside)."""
    with pytest.raises(nnm.NNMInputError, match=match) as exc:
        make()
    assert "\n" not in str(exc.value)


def _kernels_match(el, rows):
    """The numba kernels (law_force, law_force_tangent) give the element set's numpy force and tangent."""
    from nnm_solver.model.laws import law_force, law_force_tangent
    for row in rows:
        np.testing.assert_allclose(law_force(row, el.powers, el.coefficients, el.kinks), el.force(row), rtol=1e-12,
                                   atol=1e-15)
        g, t = law_force_tangent(row, el.powers, el.coefficients, el.kinks)
        np.testing.assert_allclose(g, el.force(row), rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(t, el.tangent(row), rtol=1e-12, atol=1e-15)
