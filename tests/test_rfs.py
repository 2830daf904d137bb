"""The restoring force surface (seed §4.1.3, eq. 20-22) on simulated tests of a connection whose law is known:
a 2-DOF system ground -k1- m1 -[connection]- m2, a swept sine on m1 (or on m2 with its force measured),
integrated by solve_ivp (DOP853, rtol 1e-10) independently of nnm; the accelerations are what a test lab
would measure on both sides of the connection."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nnm_solver as nnm
from nnm_solver.errors import NNMInputError

K, K3, C, M1, M2, K1 = 2e5, -2e10, 20.0, 10.0, 1.0, 1e5


def simulate(law=None, force=200.0, shaker_on_m2=False, f0=40.0, f1=110.0, T=4.0, fs=2000.0):
    """(t, a1, a2, F2, d, dv): accelerations of m1 and m2 (m/s^2), the force on m2 (N), the connection's true
    relative displacement d = x2 - x1 and velocity; the connection's force is law(d) + C dv."""
    law = law or (lambda d: K * d + K3 * d ** 3)
    rate = (f1 - f0) / T

    def load(t):
        return force * np.sin(2 * np.pi * (f0 * t + 0.5 * rate * t * t)) * np.minimum(t / 0.2, 1.0)

    def rhs(t, y):
        x1, x2, v1, v2 = y
        fc = law(x2 - x1) + C * (v2 - v1)
        p = load(t)
        return [v1, v2, (-K1 * x1 + fc + (0.0 if shaker_on_m2 else p)) / M1, (-fc + (p if shaker_on_m2 else 0.0)) / M2]

    t = np.arange(0.0, T, 1.0 / fs)
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0] * 4, t_eval=t, method="DOP853", rtol=1e-10, atol=1e-14)
    acc = np.array([rhs(ti, yi) for ti, yi in zip(sol.t, sol.y.T)])
    F2 = load(t) if shaker_on_m2 else np.zeros_like(t)
    return t, acc[:, 2], acc[:, 3], F2, sol.y[1] - sol.y[0], sol.y[3] - sol.y[2]


@pytest.fixture(scope="module")
def cubic_test():
    return simulate()


def test_exact_data_give_the_relative_motion_and_the_cubic_law(cubic_test):
    t, a1, a2, _, d, dv = cubic_test
    assert K3 * np.max(np.abs(d)) ** 2 / K < -0.2                    # strongly softening at the peak
    s = nnm.rfs(t, a2, a1, M2)
    v = s.valid
    assert v.sum() > 0.8 * len(t)
    assert np.max(np.abs(s.displacement - d)[v]) < 3e-3 * np.max(np.abs(d))
    assert np.max(np.abs(s.velocity - dv)[v]) < 1e-3 * np.max(np.abs(dv))
    np.testing.assert_allclose(s.force, -M2 * a2)                    # eq. 21
    law = s.fit("cubic")
    assert law.k == pytest.approx(K, rel=1e-3)
    assert law.k3 == pytest.approx(K3, rel=3e-3)
    assert law.c == pytest.approx(C, rel=1e-2)
    assert law.residual < 5e-3
    lin = s.fit("linear")
    assert lin.k3 is None and lin.residual > 5 * law.residual      # the cubic term is needed


def test_a_measured_force_at_the_point_enters_the_restoring_force():
    t, a1, a2, F2, d, _ = simulate(force=20.0, shaker_on_m2=True)
    law = nnm.rfs(t, a2, a1, M2, force=F2).fit("cubic")
    assert law.k == pytest.approx(K, rel=1e-3) and law.k3 == pytest.approx(K3, rel=3e-3)
    assert nnm.rfs(t, a2, a1, M2).fit("cubic").residual > 0.1     # the shaker's force left out: no law fits


def test_noisy_accelerations_still_give_k_and_k3(cubic_test):
    t, a1, a2, _, _, _ = cubic_test
    rng = np.random.default_rng(7)
    noisy = [a + 0.02 * np.std(a) * rng.standard_normal(len(a)) for a in (a1, a2)]
    law = nnm.rfs(t, noisy[1], noisy[0], M2).fit("cubic")
    assert law.k == pytest.approx(K, rel=5e-3)                     # target with noise: 2 %
    assert law.k3 == pytest.approx(K3, rel=2.5e-2)                 # target with noise: 5 %
    assert law.stderr["k3"] > 0


def test_a_piecewise_linear_connection_is_found_with_its_breakpoint():
    spring = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[K, 0.4 * K], breakpoints=[0.8e-3])
    t, a1, a2, _, d, _ = simulate(law=spring.exact_force, force=150.0)
    assert np.max(np.abs(d)) > 1.2e-3
    s = nnm.rfs(t, a2, a1, M2)
    law = s.fit("piecewise_linear")
    np.testing.assert_allclose(law.stiffnesses, [K, 0.4 * K], rtol=5e-3)
    assert law.breakpoints[0] == pytest.approx(0.8e-3, rel=2e-3)
    given = s.fit("piecewise_linear", breakpoints=[0.8e-3])
    np.testing.assert_allclose(given.stiffnesses, [K, 0.4 * K], rtol=5e-3)
    assert s.fit("cubic").residual > 5 * law.residual
    x, f = s.stiffness_curve()
    assert np.all(np.diff(x) >= 0)
    np.testing.assert_allclose(f, spring.exact_force(x) + law.offset, atol=0.02 * np.max(np.abs(f)))


def test_the_fitted_law_goes_into_a_model_as_its_spring(cubic_test):
    t, a1, a2, _, _, _ = cubic_test
    law = nnm.rfs(t, a2, a1, M2).fit("cubic")
    base = nnm.Model(np.diag([M1, M2]), np.array([[K1, 0.0], [0.0, 0.0]]))
    model = law.add_to(base, dof=1, other=0)
    assert isinstance(model.springs[0], nnm.CubicSpring) and model.springs[0].k3 == law.k3
    np.testing.assert_allclose(model.K, [[K1 + law.k, -law.k], [-law.k, law.k]])
    # the model's connection force is the fitted elastic law: K x + f_nl(x) at m2 against x2 - x1
    x = np.array([0.3e-3, -0.9e-3])
    f2 = (model.K @ x + model.nonlinear_force(x))[1]
    assert f2 == pytest.approx(law.elastic_force(x[1] - x[0]), rel=1e-12)
    # linear frequencies of the identified model: those of the true linear system
    truth = nnm.Model(np.diag([M1, M2]), np.array([[K1 + K, -K], [-K, K]]))
    np.testing.assert_allclose(model.linear_modes()[0], truth.linear_modes()[0], rtol=1e-3)


def test_a_piecewise_linear_law_keeps_its_slope_in_k_and_its_kinks_in_the_element():
    law = nnm.FittedLaw(kind="piecewise_linear", k=K, c=0.0, offset=0.0, residual=0.0, samples=100,
                        stiffnesses=(K, 0.4 * K), breakpoints=(0.8e-3,))
    model = law.add_to(nnm.Model(np.eye(2), np.zeros((2, 2))), dof=1, other=0)
    spring = model.springs[0]
    assert spring.stiffnesses == (0.0, -0.6 * K) and spring.breakpoints == (0.8e-3,)
    x = np.array([0.0, 2e-3])                          # far past the breakpoint: the smoothing is negligible
    assert (model.K_linear @ x + model.nonlinear_force(x))[1] == pytest.approx(law.elastic_force(2e-3), rel=1e-6)


def test_plots_of_the_surface_and_the_stiffness_curve(cubic_test, tmp_path):
    t, a1, a2, _, _, _ = cubic_test
    s = nnm.rfs(t, a2, a1, M2)
    fig = s.plot(s.fit("cubic"), path=tmp_path / "rfs.png")
    assert (tmp_path / "rfs.png").stat().st_size > 10000 and len(fig.axes) >= 2


@pytest.mark.parametrize("change, message", [
    (dict(acceleration=np.r_[np.nan, np.zeros(799)]), "NaN"),
    (dict(acceleration=np.zeros(10)), "10 samples, t has 800"),
    (dict(t=np.r_[np.arange(799) * 1e-3, 2.0]), "not uniformly sampled"),
    (dict(mass=0.0), "mass 0.0 must be positive"),
    (dict(acceleration_other="x"), "array of numbers"),
    (dict(acceleration_other=np.sin(np.arange(800) * 0.3)), "equal at every sample"),
    (dict(highpass_hz=0.5), "shorter than 10 periods"),
])
def test_bad_data_give_one_line(change, message):
    args = dict(t=np.arange(800) * 1e-3, acceleration=np.sin(np.arange(800) * 0.3),
                acceleration_other=np.zeros(800), mass=1.0)
    args.update(change)
    with pytest.raises(NNMInputError, match=message) as err:
        nnm.rfs(args.pop("t"), args.pop("acceleration"), args.pop("acceleration_other"), args.pop("mass"), **args)
    assert "\n" not in str(err.value)


def test_bad_fit_requests_give_one_line(cubic_test):
    t, a1, a2, _, _, _ = cubic_test
    s = nnm.rfs(t, a2, a1, M2)
    for args, message in ((("quintic",), "not one of"), (("cubic",), "unknown option"),
                          (("piecewise_linear",), "must be increasing")):
        opts = {"powers": (1, 3)} if message == "unknown option" else {}
        if message == "must be increasing":
            opts = {"breakpoints": [1.0]}
        with pytest.raises(NNMInputError, match=message) as err:
            s.fit(*args, **opts)
        assert "\n" not in str(err.value)
    with pytest.raises(NNMInputError, match="no nonlinear term"):
        s.fit("linear").spring(0)
