"""The lean per-point path of condensed harmonic balance (issue 52): the energy gradient in closed form
(orbits/condensed_energy.py) against central differences of the energy, on complete and truncated linear parts,
polynomial, piecewise-linear and coupled elements, odd and full bases."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.condensed_hb import CondensedHBProblem, LinearPart
from nnm_solver.orbits.hb_basis import HBBasis


def chain(n=6, springs=None):
    """n masses (1.0 .. 1.5 kg) in a chain, grounded at both ends, with the given elements."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.diag(1.0 + 0.1 * np.arange(n)), K, springs)


MODELS = {
    "cubic": lambda: chain(springs=[nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=4, k3=-0.3)]),
    "polynomial": lambda: chain(springs=[nnm.PolynomialSpring(dof=1, coefficients={2: 0.4, 3: 0.9})]),
    "piecewise": lambda: chain(springs=[nnm.PiecewiseLinearSpring(dof=3, stiffnesses=[0.5, 2.0], breakpoints=[0.2])]),
    "coupled": lambda: chain(springs=[nnm.PolynomialStiffness([[1, 1, 0], [2, 0, 0], [0, 2, 1], [0, 3, 0], [3, 0, 0]],
                                                              [[2, 0, 0], [0, 1, 0], [0, 1.5, 0], [0, 0, .5], [1, 0, 0]],
                                                              dofs=[0, 2, 5])]),
}


def _perturbed(p, a0, seed):
    rng = np.random.default_rng(seed)
    u, _ = p.start(a0)
    u = u + 0.1 * rng.standard_normal(len(u)) * np.abs(u[:-1]).max()
    u[-1] = 1.04
    return u


def _check_gradient(p, u):
    g, g_fd = p.energy_gradient(u), p.energy_gradient_fd(u, h=1e-6)
    assert np.all(np.isfinite(g))
    assert np.max(np.abs(g - g_fd)) < 1e-6 * np.max(np.abs(g)), np.max(np.abs(g - g_fd)) / np.max(np.abs(g))


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("kind", ["odd", "full"])
def test_energy_gradient_is_the_derivative_of_the_condensed_energy(name, kind):
    model = MODELS[name]()
    system = modal_system(model)
    if kind == "odd" and not system.elements.odd:
        pytest.skip("an odd basis needs odd forces")
    p = CondensedHBProblem(system, 1, HBBasis(5, kind))
    for seed in (0, 1):
        _check_gradient(p, _perturbed(p, 0.6, seed))


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_energy_gradient_with_the_left_out_modes_residual_flexibility(kind):
    """A truncated LinearPart (the first 3 of 6 modes and residual flexibilities R0, R1, not symmetric here: the
    gradient must not assume it) and the followed mode r = 1."""
    system = modal_system(MODELS["cubic"]())
    rng = np.random.default_rng(5)
    R0, R1 = 0.05 * rng.standard_normal((2, 2, 2))
    lin = LinearPart(system.omega2[:3], system.Bq[:, :3], R0=R0, R1=R1)
    p = CondensedHBProblem(system, 1, HBBasis(5, kind), lin)
    for seed in (2, 3):
        _check_gradient(p, _perturbed(p, 0.6, seed))


def test_energy_is_unchanged_by_the_cache_of_the_last_orbit():
    """The problem keeps the last orbit's amplitudes: the energy, state and orbit of u after another orbit's are
    those computed afresh, and the kept arrays cannot be changed by a caller."""
    system = modal_system(MODELS["cubic"]())
    p = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
    u1, u2 = _perturbed(p, 0.6, 7), _perturbed(p, 0.4, 8)
    fresh = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
    E1 = fresh.energy(u1)
    for u in (u1, u2, u1):
        p.energy(u)
    assert p.energy(u1) == E1
    q0, v0, T = p.state(u1)
    f0 = fresh.state(u1)
    assert np.array_equal(q0, f0[0]) and np.array_equal(v0, f0[1]) and T == f0[2]
    with pytest.raises(ValueError):
        p.amplitudes(u1)[0][0, 0] = 1.0
