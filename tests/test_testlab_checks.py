"""Issue 54's checks on systems built here (the issue's own checks use others): the restoring force surface of a
softening connection between a shaken tank and a wing-like 2-DOF structure (solve_ivp, 2 % noise on both
accelerations and the force), and the factor on a model's cubic springs from a backbone computed by an independent
shooting (solve_ivp + scipy root on x(T/4) = 0), 1 % amplitude noise."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import root

import nnm_solver as nnm

# wing m1 (grounded by k1, to m3 by k2), m3 grounded by kg3, tank mc hung on m1 by f = k d + k3 d^3 + c d'
M1, M3, MC = 5.0, 3.0, 2.0
K1, K2, KG3, C1 = 2e5, 1e5, 1.5e5, 8.0
K, K3, C = 5e4, -1.5e9, 10.0


def shaken_tank(amplitude=6.0, f0=10.0, f1=40.0, duration=12.0, fs=4000.0):
    """(t, tank acceleration, wing acceleration, shaker force, relative displacement) of a swept sine on the tank."""
    rate = (f1 - f0) / duration

    def force(t):
        return amplitude * np.sin(2 * np.pi * (f0 * t + 0.5 * rate * t ** 2))

    def rhs(t, y):
        x1, x3, xc, v1, v3, vc = y
        fc = K * (xc - x1) + K3 * (xc - x1) ** 3 + C * (vc - v1)
        return [v1, v3, vc, (-K1 * x1 - K2 * (x1 - x3) - C1 * v1 + fc) / M1, (-KG3 * x3 - K2 * (x3 - x1)) / M3,
                (force(t) - fc) / MC]

    t = np.arange(0.0, duration, 1.0 / fs)
    sol = solve_ivp(rhs, (0.0, duration), np.zeros(6), t_eval=t, method="DOP853", rtol=1e-10, atol=1e-13,
                    max_step=1.0 / fs)
    acc = np.array([rhs(ti, yi) for ti, yi in zip(t, sol.y.T)])
    return t, acc[:, 5], acc[:, 3], force(t), sol.y[2] - sol.y[0]


def test_rfs_of_a_shaken_tank_with_two_percent_noise():
    t, ac, a1, F, d = shaken_tank()
    assert 2e-3 < np.max(np.abs(d)) < 4e-3                     # k3 d^2 / k reaches -0.2: a clear softening
    exact = nnm.rfs(t, ac, a1, mass=MC, force=F).fit("cubic")
    assert exact.k == pytest.approx(K, rel=1e-3) and exact.k3 == pytest.approx(K3, rel=2e-3)
    rng = np.random.default_rng(1)
    noisy = [s + 0.02 * np.std(s) * rng.standard_normal(len(s)) for s in (ac, a1, F)]
    law = nnm.rfs(t, noisy[0], noisy[1], mass=MC, force=noisy[2]).fit("cubic")
    assert law.k == pytest.approx(K, rel=0.02) and law.k3 == pytest.approx(K3, rel=0.05)
    assert law.c == pytest.approx(C, rel=0.05)
    # the force left out: the shaker's force then counts as the connection's, and the fit shows it
    blind = nnm.rfs(t, noisy[0], noisy[1], mass=MC).fit("cubic")
    assert blind.residual > 5 * law.residual


MM = np.diag([1.0, 2.0])
KK = np.array([[3e4, -1e4], [-1e4, 2e4]])
SPRINGS = [(0, None, 4e9), (0, 1, 1.5e9)]


def shooting_backbone(factor, amplitudes):
    """Frequencies (Hz) of NNM 1 at peak amplitudes of DOF 0, by solve_ivp and root: the orbit starts at rest at
    x = (a, x2) and all coordinates cross zero at T/4 (a symmetric, synchronous mode)."""
    Minv = np.linalg.inv(MM)

    def rhs(t, y):
        x, v = y[:2], y[2:]
        f = KK @ x
        for dof, other, k3 in SPRINGS:
            dd = x[dof] - (0.0 if other is None else x[other])
            f[dof] += factor * k3 * dd ** 3
            if other is not None:
                f[other] -= factor * k3 * dd ** 3
        return np.concatenate([v, -Minv @ f])

    lam, phi = np.linalg.eig(np.linalg.solve(MM, KK))
    i = int(np.argmin(lam))
    guess = np.array([phi[1, i] / phi[0, i] * amplitudes[0], 2 * np.pi / np.sqrt(lam[i])])
    out = []
    for a in amplitudes:
        def res(z):
            s = solve_ivp(rhs, (0.0, z[1] / 4), [a, z[0], 0.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-15)
            return s.y[:2, -1] / a

        z = root(res, guess, tol=1e-13).x
        assert np.max(np.abs(res(z))) < 1e-9
        out.append(1.0 / z[1])
        guess = z
    return np.array(out)


def test_fit_backbone_recovers_the_factor_of_an_independent_backbone_with_one_percent_noise():
    amplitudes = np.linspace(0.2e-3, 2.0e-3, 30)
    true = 1.3
    frequency = shooting_backbone(true, amplitudes)
    assert frequency[-1] / frequency[0] > 1.1                  # hardening: the backbone bends by 10 %
    model = nnm.Model(MM, KK, [nnm.CubicSpring(dof=d, other=o, k3=k3) for d, o, k3 in SPRINGS])
    noisy = amplitudes * (1 + 0.01 * np.random.default_rng(0).standard_normal(len(amplitudes)))
    fit = nnm.fit_backbone(model, 1, 0, noisy, frequency)
    assert fit.k3_factor == pytest.approx(true, rel=0.01)
    assert fit.confidence[0] < true < fit.confidence[1] and fit.covered
    exact = nnm.fit_backbone(model, 1, 0, amplitudes, frequency)
    assert exact.k3_factor == pytest.approx(true, rel=1e-3)
