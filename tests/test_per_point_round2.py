"""The lean per-point path of condensed harmonic balance, round 2 (issue 52): each cut gives the numbers of the form it
replaced, checked against that form written here or kept in the package.

* the spring laws' polynomial part written out in the compiled _forces (and numba's integer power copied): the
  numbers of model/laws.law_scalar bit for bit;
* the restoring-force bound of spring models by a compiled pass: the numpy form's to round-off;
* the harmonic amplitudes of an HB orbit from its basis coefficients' row sums: those of its complex Fourier
  coefficients (np.linalg.norm) to round-off, the partners made when read the same array;
* the skeleton's frequency by Newton's steps on the spline's cubic piece: scipy's brentq on the spline to 1e-13;
* the condensed problem's kept energy and gradient: a fresh problem's numbers whatever orbits came before;
* the truncation estimate's embedding of several vectors at once: each embedded alone.
"""
import math

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.analysis.hb_series import basis_fourier_coefficients, basis_harmonic_amplitudes
from nnm_solver.backbone.content import content_of
from nnm_solver.driver.candidate import restoring_lower_bound
from nnm_solver.model.laws import law_scalar
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits import condensed_kernels as kernels
from nnm_solver.orbits.condensed_hb import CondensedHBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from nnm_solver.orbits.spring_kernels import int_power

needs_numba = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


def chain(n=5, springs=None):
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.diag(1.0 + 0.1 * np.arange(n)), K, springs)


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


@needs_numba
def test_forces_polynomial_part_is_law_scalars_bit_for_bit():
    """_forces' written-out polynomial laws against law_scalar (the form other kernels use) on random deformations
    of 8 decades and powers 0..13 (x ** -1 included), forces, stiffnesses and force coefficients identical."""
    import numba

    @numba.njit
    def by_law(d, powers, coeffs, kinks):
        g, t = np.empty_like(d), np.empty_like(d)
        for n in range(d.shape[0]):
            for s in range(d.shape[1]):
                g[n, s], t[n, s] = law_scalar(d[n, s], s, powers, coeffs, kinks)
        return g, t

    @numba.njit
    def powers_of(x, e):
        return int_power(x, e), x ** e

    rng = np.random.default_rng(3)
    for powers in (np.array([3]), np.array([2, 3]), np.array([0, 1, 2, 3, 4, 5, 7, 9, 13])):
        coeffs = rng.standard_normal((4, len(powers)))
        coeffs[1, 0] = 0.0
        kinks = np.zeros((4, 0, 3))
        for scale in (1e-6, 1e-2, 3.0):
            E, P, D = rng.standard_normal((40, 5)), rng.standard_normal((5, 40)), scale * rng.standard_normal((5, 4))
            d, F, tg = kernels._forces(D, E, P, powers, coeffs, kinks, True)
            g, t = by_law(d, powers, coeffs, kinks)
            F_ref = np.zeros((5, 4))
            for j in range(5):
                for n in range(40):
                    F_ref[j] += P[j, n] * g[n]
            assert np.array_equal(tg, t) and np.array_equal(F, F_ref)
    for x in rng.standard_normal(50) * 10 ** rng.uniform(-8, 3, 50):
        for e in range(-3, 20):
            a, b = powers_of(float(x), e)
            assert a == b or (math.isnan(a) and math.isnan(b))


@needs_numba
@pytest.mark.parametrize("law", ["cubic", "softening", "piecewise"])
def test_restoring_bound_kernel_is_the_numpy_forms(law, monkeypatch):
    springs = {"cubic": [nnm.CubicSpring(dof=0, k3=2.0), nnm.CubicSpring(dof=1, other=3, k3=1.0)],
               "softening": [nnm.CubicSpring(dof=0, k3=-0.5), nnm.PolynomialSpring(dof=2, coefficients={2: 0.3, 3: -1.0})],
               "piecewise": [nnm.PiecewiseLinearSpring(dof=3, stiffnesses=[0.5, 2.0], breakpoints=[0.2])]}[law]
    system = modal_system(chain(springs=springs))
    theta = 2 * np.pi * np.arange(40) / 40
    rng = np.random.default_rng(7)
    for scale in (0.05, 0.3, 1.0):
        Q = scale * (np.outer(np.cos(theta), rng.standard_normal(5)) + 0.2 * np.outer(np.cos(3 * theta),
                                                                                      rng.standard_normal(5)))
        compiled = restoring_lower_bound(system, Q)
        with monkeypatch.context() as m:
            m.setattr(kernels, "AVAILABLE", False)
            plain = restoring_lower_bound(system, Q)
        assert abs(compiled - plain) <= 1e-13 * max(1.0, abs(plain)), (compiled, plain)


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_harmonic_amplitudes_from_the_basis_coefficients(kind):
    """basis_harmonic_amplitudes against np.linalg.norm of the complex coefficients (all modes and all but r), and
    content_of's two routes: the same labels, orders, shares and (made when read) partners."""
    model = chain(springs=[nnm.CubicSpring(dof=0, k3=0.8)] if kind == "odd" else
                  [nnm.PolynomialSpring(dof=1, coefficients={2: 0.4, 3: 0.9})])
    system = modal_system(model)
    basis = HBBasis(7, kind)
    rng = np.random.default_rng(11)
    for trial in range(4):
        A = rng.standard_normal((len(basis), system.n)) * np.geomspace(1, 1e-3, len(basis))[:, None]
        r = trial % system.n
        c = basis_fourier_coefficients(basis, A, 9)
        others = c.copy()
        others[:, r] = 0.0
        amps, rest = basis_harmonic_amplitudes(basis, A, 9, r)
        np.testing.assert_allclose(amps, np.linalg.norm(c, axis=1), rtol=1e-14, atol=0)
        np.testing.assert_allclose(rest, np.linalg.norm(others, axis=1), rtol=1e-14, atol=0)
        Q = basis.functions(2 * np.pi * np.arange(32) / 32) @ A
        a, b = content_of(Q, r, 9, coefficients=c), content_of(Q, r, 9, series=(basis, A))
        assert (a.label, a.k, a.partner_k, a.order) == (b.label, b.k, b.partner_k, b.order)
        assert abs(a.fraction - b.fraction) < 1e-14 and abs(a.share - b.share) < 1e-14
        np.testing.assert_allclose(b.partners, a.partners, rtol=1e-14, atol=0)   # (over tot: to round-off)


def test_skeleton_frequency_by_newton_on_the_cubic_piece():
    """Skeleton.frequency_at against scipy's brentq on the same splines (the form before) at 2000 energies of the
    2-DOF benchmark's skeleton: within 1e-13 relative."""
    from scipy.optimize import brentq
    from nnm_solver.backbone.skeleton import compute_skeleton
    sk = compute_skeleton(modal_system(two_dof()), 1, 50.0)
    sk.frequency_at(sk.energy[1])                       # its sheets
    worst, n = 0.0, 0
    for E in np.geomspace(sk.energy[0], sk.energy[-1], 2002)[1:-1]:
        j, t = sk._pair(E)
        sheet = sk._interp.get(j)
        if sheet is None or sk._interp.get(j + 1) is not sheet or sk._gaps[j] or t < 0:
            continue
        lo, c, lnE, f = sheet
        a, b = c[j - lo], c[j + 1 - lo]
        g = lambda s: float(lnE(s)) - math.log(E)          # noqa: E731
        if g(a) == 0.0 or g(a) * g(b) > 0:
            continue
        ref = float(f(brentq(g, a, b, xtol=1e-14 * max(1.0, abs(b)))))
        worst = max(worst, abs(sk.frequency_at(E) / ref - 1.0))
        n += 1
    assert n > 1000 and worst < 1e-13, (n, worst)


@needs_numba
def test_kept_energy_and_gradient_are_a_fresh_problems():
    """Energy and gradient of interleaved orbits (each asked in turn, after the others) equal a fresh problem's; the
    gradient handed out is the caller's own (writing to it changes nothing kept)."""
    system = modal_system(chain(springs=[nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=4, k3=-0.3)]))
    p = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
    rng = np.random.default_rng(2)
    us = []
    for a0 in (0.3, 0.5, 0.7):
        u, _ = p.start(a0)
        us.append(u + 0.05 * rng.standard_normal(len(u)) * np.abs(u[:-1]).max())
    for u in us + us[::-1] + us:
        fresh = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
        E0, g0 = fresh.energy(u), fresh.energy_gradient(u)
        assert p.energy(u) == E0
        g = p.energy_gradient(u)
        assert np.array_equal(g, g0)
        g[:] = 0.0
        E, g2 = p.energy_and_gradient(u)
        assert E == E0 and np.array_equal(g2, g0) and p.energy(u) == E0


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_embedding_several_vectors_at_once(kind):
    system = modal_system(chain(springs=[nnm.CubicSpring(dof=0, k3=1.0), nnm.CubicSpring(dof=1, other=2, k3=0.3)]))
    p = CondensedHBProblem(system, 0, HBBasis(5, kind))
    big = p._larger()
    U = np.random.default_rng(0).standard_normal((2, p.nb * p.ns + 2))
    assert np.array_equal(p._embed(big, U), np.stack([p._embed(big, U[0]), p._embed(big, U[1])]))
