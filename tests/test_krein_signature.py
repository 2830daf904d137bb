"""Krein signatures of a reversible orbit's collision coordinates c from a few eigenvectors (stability/krein_signature.py,
ShootingStability.local_eigenpairs / krein_form, Integrator.directional), checked against what they stand for: the
symplectic form -i z^H J z of the dense half-period map's eigenvectors (an independent eigen-solver on the full 2n x 2n
map), the linear modes' sign(sin(w T / 2)), a same-signature pair passing through each other (stable on both sides) and
an opposite-signature pair colliding (a Krein collision: complex coordinates, the orbit unstable)."""
import dataclasses

import numpy as np
import pytest
from scipy.stats import ortho_group

import nnm_solver as nnm
from nnm_solver.continuation.engine import ContinuationSettings, correct
from nnm_solver.integrators import gauss, gauss_monodromy
from nnm_solver.integrators.registry import get_integrator
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits import shooting_stability
from nnm_solver.orbits.shooting import ShootingProblem
from nnm_solver.stability.krein_signature import opposite_neighbours, signatures

from test_bifurcation import _combination_resonance_model
from test_gauss_monodromy import _system


def _rotated(w, k3=1.0, seed=0):
    """M = I, linear frequencies w (rad/s) mixed by a fixed rotation, a cubic spring on DOF 0."""
    Phi = ortho_group.rvs(len(w), random_state=seed)
    return nnm.Model(M=np.eye(len(w)), K=Phi @ np.diag(np.asarray(w) ** 2) @ Phi.T,
                     springs=[nnm.CubicSpring(dof=0, k3=k3)])


def _orbit(ms, amp, u0=None, all_columns=False, integrator="gauss6"):
    """NNM 1's orbit with the first modal amplitude amp (quarter-period shooting, 100 steps), accepted."""
    prob = ShootingProblem(ms, 0, 100, symmetric=True, integrator=integrator)
    prob.all_columns = all_columns
    if u0 is None:
        q0 = np.zeros(ms.n)
        q0[0] = amp
        u0 = prob.pack(q0, np.zeros(ms.n), prob.T_r)
    else:
        q, v, T = prob.unpack(u0)
        u0 = prob.pack(q * amp / q[0], v, T)
    p = np.zeros(len(u0))
    p[0] = 1.0
    u, J, _, _ = correct(prob, u0, p, ContinuationSettings(step=0.1, step_min=1e-9, step_max=1.0, max_iter=40), 1e-13)
    prob.accept(u, J)
    return prob, u


def _scan(model, amps):
    """Per amplitude: (frequency (rad/s), c (n,), signatures, the dense J-form's signatures: -i z^H J z of the
    eigenvectors of the half-period map (at lambda) and of the monodromy (at mu = lambda^2), 9 where those two
    disagree, 0 where c is complex or the trivial -1)."""
    ms = modal_system(model)
    n, u, out = ms.n, None, []
    Jf = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
    for amp in amps:
        prob, u = _orbit(ms, amp, u)
        c, X = prob.local_eigenpairs(0.0, k=n)
        kappa = signatures(c, prob.krein_form(X))
        full, _ = _orbit(ms, amp, u, all_columns=True)
        lam, Z = np.linalg.eig(full.accepted_map)                  # the half-period map, 2n x 2n
        mu, V = np.linalg.eig(full.monodromy())                     # the monodromy, its square
        dense = np.zeros(n, dtype=int)
        for i, ci in enumerate(c):
            if abs(ci.imag) > 1e-9 or abs(ci + 1) < 1e-6:
                continue
            lam_i = ci.real + 1j * np.sqrt(1 - ci.real ** 2)
            z = Z[:, np.argmin(np.abs(lam - lam_i))]
            v = V[:, np.argmin(np.abs(mu - lam_i ** 2))]             # the multiplier lambda^2: the same eigenvector
            half, mono = (int(np.sign(np.real(-1j * y.conj() @ Jf @ y))) for y in (z, v))
            dense[i] = half if half == mono else 9
        out.append((2 * np.pi / prob.unpack(u)[2], c, kappa, dense))
    return out


def test_directional_derivatives_equal_the_full_sensitivity(monkeypatch):
    """gauss.sweep_directional's dq_N/dq0 X and dv_N/dq0 X equal sweep_sensitivity's blocks times X (also by blocks of
    the triangular solve, and the registry's default from the full sensitivity for Newmark)."""
    system = _system()
    rng = np.random.default_rng(0)
    q0, v0, X = rng.normal(size=system.n), 0.3 * rng.normal(size=system.n), rng.normal(size=(system.n, 3))
    for N in (1, 7, 40):
        _, _, Sq, Sv, _, _, ok = gauss.sweep_sensitivity(q0, v0, 0.07, N, system.kernel, 3, False, True)
        _, _, SqX, SvX, ok_x = gauss.sweep_directional(q0, v0, 0.07, N, system.kernel, 3, X)
        assert ok and ok_x
        assert np.allclose(SqX, Sq @ X, rtol=0, atol=1e-12) and np.allclose(SvX, Sv @ X, rtol=0, atol=1e-12)
    monkeypatch.setattr(gauss_monodromy, "KERNELS", dataclasses.replace(gauss_monodromy.KERNELS, volterra_block=5))
    _, _, SqX, SvX, _ = gauss.sweep_directional(q0, v0, 0.07, 40, system.kernel, 3, X)
    assert np.allclose(SqX, Sq @ X, atol=1e-12) and np.allclose(SvX, Sv @ X, atol=1e-12)
    nm = get_integrator("newmark")
    _, _, Sq, Sv, _, _, _ = nm.sensitivity(system, q0, v0, 0.07, 40, False, True)
    SqX, SvX, ok = nm.directional(system, q0, v0, 0.07, 40, X)
    assert ok and np.allclose(SvX, Sv @ X) and np.allclose(SqX, Sq @ X)


def test_linear_modes_carry_the_sign_of_sin_wT2():
    """At a small amplitude (nearly linear) the signature of mode j's coordinate c_j = cos(w_j T / 2) is sign(sin(w_j T
    / 2)), and the dense map's J-form says the same."""
    w = np.array([1.0, 1.5, 2.3, 3.6])
    ((om, c, kappa, dense),) = _scan(_rotated(w), [1e-3])
    T = 2 * np.pi / om
    expected = {round(float(np.cos(wj * T / 2)), 6): int(np.sign(np.sin(wj * T / 2))) for wj in w[1:]}
    for ci, ki, di in zip(c, kappa, dense):
        if abs(ci + 1) < 1e-6:
            continue                                     # the trivial coordinate (the family's Jordan block)
        assert ki == expected[round(float(ci.real), 6)] == di


def test_a_same_signature_pair_passes_through():
    """Frequencies 1, 1.5, 3.6 rad/s: NNM 1 hardens through the difference resonance w3 - w2 = 2 w (about 1.034
    rad/s): modes 2 and 3's coordinates meet and pass through each other with the same signature (no complex pair,
    stable on both sides); the signatures equal the dense J-form's at every point."""
    scan = _scan(_rotated([1.0, 1.5, 3.6]), np.linspace(0.8, 1.05, 6))
    order = []
    for om, c, kappa, dense in scan:
        inner = np.abs(c + 1) > 1e-6
        assert np.all(np.abs(c.imag) < 1e-12)                             # stable throughout
        assert np.array_equal(kappa[inner], dense[inner]) and np.all(kappa[inner] != 0)
        assert len(set(kappa[inner])) == 1                                # the two carry one signature ...
        assert not opposite_neighbours(c[inner], kappa[inner])            # ... so they cannot collide
        order.append(np.argsort(c[inner].real))
    # they did pass each other: the coordinate of the mode that was left is right at the end (modes follow their
    # signature-definite eigenvectors; here by continuity of c: the ends' sorted order of the two tracked values)
    first, last = scan[0][1], scan[-1][1]
    assert np.sign(first[0].real - first[1].real) != np.sign(last[0].real - last[1].real)


def test_an_opposite_signature_pair_collides_and_leaves_in_the_other_order():
    """The 3-DOF combination resonance (4 w = w2 + w3): before the torus the two coordinates are neighbours of opposite
    signatures (opposite_neighbours finds them), then a complex pair (the orbit unstable, no signature), and back on
    the axis past the torus in the other order of signatures (+ then - from the left before, - then + after): a
    collision undone between two points shows in their signature order.  The signatures equal the dense J-form's at
    every stable point."""
    scan = _scan(_combination_resonance_model(), np.linspace(1.5, 2.4, 10))
    cplx = [bool(np.any(np.abs(c.imag) > 1e-9)) for _, c, _, _ in scan]
    assert not cplx[0] and any(cplx) and not cplx[-1]
    for (om, c, kappa, dense), unstable in zip(scan, cplx):
        inner = np.abs(c + 1) > 1e-6
        if unstable:
            assert np.all(kappa[np.abs(c.imag) > 1e-9] == 0)               # neutral: no signature
            continue
        assert np.array_equal(kappa[inner], dense[inner]) and np.all(kappa[inner] != 0)
        assert len(opposite_neighbours(c[inner], kappa[inner])) == 1

    def order(c, kappa):
        inner = np.flatnonzero(np.abs(c + 1) > 1e-6)
        return list(kappa[inner][np.argsort(c[inner].real)])
    assert order(*scan[0][1:3]) == [1, -1] and order(*scan[-1][1:3]) == [-1, 1]


def test_a_cluster_gets_its_inertia():
    """Nearly equal coordinates (a symmetric pair: eigenvectors any basis of their plane) take the signature of the
    form's restriction to the cluster when it is definite, 0 when it is mixed."""
    c = np.array([0.1, 0.1 + 1e-12, 0.5])
    F = np.array([[2.0, 1.9, 0], [1.9, 2.0, 0], [0, 0, -1.0]])            # definite on the cluster: both -1
    assert list(signatures(c, F)) == [-1, -1, 1]
    F[0, 1] = F[1, 0] = 3.0                                               # indefinite: undetermined
    assert list(signatures(c, F)) == [0, 0, 1]
    assert [p[:2] for p in opposite_neighbours(c, signatures(c, F))] == [(0, 1), (1, 2)]


def test_a_window_of_a_larger_model_by_shift_invert(monkeypatch):
    """A 50-DOF chain (the shift-invert Arnoldi path of local_eigenpairs: the coupled block is larger than 8 k): the
    6 coordinates nearest a shift are the dense spectrum's 6 nearest, and their signatures equal those of the dense
    half map's eigenvectors' J-form."""
    n = 50
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    model = nnm.Model(M=np.eye(n), K=K, springs=[nnm.CubicSpring(dof=0, k3=1.0)])
    ms = modal_system(model)
    prob, u = _orbit(ms, 0.5)
    full, _ = _orbit(ms, 0.5, u, all_columns=True)
    lam, Z = np.linalg.eig(full.accepted_map)
    c_all = np.linalg.eigvals(prob.stability_maps()[0][:, :n])
    Jf = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
    arnoldi, eigs = [], shooting_stability.eigs

    def counted(*a, **k):
        arnoldi.append(k["sigma"])
        return eigs(*a, **k)
    monkeypatch.setattr(shooting_stability, "eigs", counted)
    for shift in (0.31, -0.52):
        c, X = prob.local_eigenpairs(shift, 6)
        nearest = c_all[np.argsort(np.abs(c_all - shift))[:6]]
        assert np.allclose(np.sort(c.real), np.sort(nearest.real), atol=1e-10)
        assert np.allclose(np.abs(prob.stability_maps()[0][:, :n] @ X - X * c), 0, atol=1e-9)
        kappa = signatures(c, prob.krein_form(X))
        for ci, ki in zip(c, kappa):
            z = Z[:, np.argmin(np.abs(lam - (ci.real + 1j * np.sqrt(1 - ci.real ** 2))))]
            assert ki == int(np.sign(np.real(-1j * z.conj() @ Jf @ z))) != 0
    assert arnoldi == [0.31, -0.52]                           # (not the dense fallback)
