"""Continuation you can trust: stability without the trivial Floquet pair, balanced step control,
tongues not skipped, escape and closed loops (issue 10).  References are independent: solve_ivp
(DOP853) monodromies of refined continuous-time orbits, closed-form saddle energies."""
import numpy as np
import pytest

import nnm_solver as nnm
from conftest import duffing_model, two_dof_model
from nnm_solver.stability.floquet import deflate, nontrivial_multipliers, reversible_multipliers
from nnm_solver.results.stops import LoopDetector
from reference_models import (cantilever_beam, multipliers_ivp, periodic_orbit_ivp, softening_saddle_energy,
                              tip_dof)


def _nontrivial(mu):
    """Multipliers without the two nearest to +1."""
    mu = np.asarray(mu)
    return np.delete(mu, np.argsort(np.abs(mu - 1.0))[:2])


# ---------------------------------------------------------------------- Floquet
def test_deflation_recovers_multipliers_of_a_perturbed_jordan_block():
    rng = np.random.default_rng(0)
    # a 4x4 map with a Jordan block at 1 on span(f, w) and a rotation by 0.7 rad elsewhere
    T = rng.normal(size=(4, 4))
    core = np.zeros((4, 4))
    core[:2, :2] = [[1.0, 50.0], [0.0, 1.0]]
    core[2:, 2:] = [[np.cos(0.7), -np.sin(0.7)], [np.sin(0.7), np.cos(0.7)]]
    Phi = T @ core @ np.linalg.inv(T)
    Phi_eps = Phi + 1e-6 * rng.normal(size=(4, 4))      # a discretisation-like perturbation
    raw = np.linalg.eigvals(Phi_eps)
    assert np.abs(raw).max() > 1 + 1e-3                 # the Jordan pair splits by O(sqrt(eps))
    mu = nontrivial_multipliers(Phi_eps, T[:, 0], T[:, 1])
    assert np.abs(np.sort(np.angle(mu[:2])) - [-0.7, 0.7]).max() < 1e-4
    assert np.abs(np.abs(mu[:2]) - 1).max() < 1e-4 and np.all(mu[2:] == 1.0)
    C = deflate(Phi, T[:, :2])
    assert np.allclose(sorted(np.angle(np.linalg.eigvals(C))), [-0.7, 0.7])


def test_reversible_multipliers_of_the_trivial_direction():
    A11 = np.diag([-1.0 - 1e-7, np.cos(0.4)])          # trivial c = -1 (perturbed), one oscillation
    mu = reversible_multipliers(A11, np.array([1.0, 0.0]))
    assert np.abs(np.abs(mu) - 1).max() < 1e-12
    assert np.sum(np.isclose(mu, 1.0)) == 2


def test_softening_duffing_is_stable_everywhere():
    b = nnm.continue_nnm(duffing_model(-1.0), 1, 0.2499, max_points=2000)
    assert b.stable.all() and not [e for e in b.events if e["kind"] != "fold"]
    np.testing.assert_array_equal(b.floquet, 1.0)


def test_duffing_multipliers_match_ivp_monodromy():
    m = duffing_model(1.0)
    b = nnm.continue_nnm(m, 1, 2.0, steps_per_period=4000, max_points=60)
    for i in (len(b) // 2, len(b) - 1):
        x, T = periodic_orbit_ivp(m, b.x0[i], None, b.period[i], fix="energy")
        mu_ref = multipliers_ivp(m, x, np.zeros(1), T)
        # both multipliers of a 1-DOF orbit are the trivial pair (a Jordan block: compare its trace)
        assert abs(np.sum(b.floquet[i]) - np.sum(mu_ref)) < 1e-6


def _sorted(mu):
    mu = np.asarray(mu)
    return mu[np.lexsort((np.angle(mu), np.round(np.abs(mu), 4)))]


@pytest.mark.parametrize("energy", [0.5, 2.0])
def test_two_dof_multipliers_match_ivp_monodromy(energy):
    """Newmark's multipliers converge as N^-2 to the continuous-time ones: at N = 2000 and 4000 steps
    per period the same orbit (first point, same modal amplitude) gives multipliers whose Richardson
    extrapolation agrees with a DOP853 monodromy of the refined continuous orbit to 1e-6."""
    m = two_dof_model()
    mus = []
    for N in (2000, 4000):
        b = nnm.continue_nnm(m, 1, 1e9, energy_min=energy, steps_per_period=N, max_points=1, integrator="newmark")
        assert len(b) == 1, b.message
        mus.append(_sorted(_nontrivial(b.floquet[0])))
    x, T = periodic_orbit_ivp(m, b.x0[0], None, b.period[0], fix="energy")
    ref = _sorted(_nontrivial(multipliers_ivp(m, x, np.zeros(2), T)))
    err = [np.abs(mu - ref).max() / np.abs(ref).max() for mu in mus]
    assert err[1] < 0.4 * err[0]                                   # second order in the time step
    richardson = (4 * mus[1] - mus[0]) / 3
    np.testing.assert_allclose(richardson, ref, rtol=1e-6, atol=1e-6)


# ---------------------------------------------------------------------- step control, folds
@pytest.mark.parametrize("spp", [200, 1000])
def test_two_dof_reports_the_3_to_1_and_5_to_1_folds(spp):
    b = nnm.continue_nnm(two_dof_model(), 1, 3e5, steps_per_period=spp, max_points=2000, tongues="follow-all")
    assert b.status == "done"
    folds = [(e["energy"], e["frequency_hz"]) for e in b.events if e["kind"] == "fold"]
    # entry folds of the tongues: 3:1 near 4.7 kJ, 5:1 near 1.1e5 J (both at ~0.2235-0.2243 Hz)
    assert any(4.5e3 < E < 4.9e3 for E, _ in folds), folds
    assert any(1.0e5 < E < 1.2e5 for E, _ in folds), folds
    # and the tips of both tongues (energy minima far below the entries)
    assert any(250 < E < 320 for E, _ in folds) and any(2e3 < E < 2.6e3 for E, _ in folds), folds


def _tip_energy(beam, tip_amplitude):
    """Linear energy (J) of mode 1 with the given tip amplitude (m)."""
    f, Phi = beam.linear_modes()
    a = tip_amplitude / Phi[tip_dof(), 0]
    return 0.5 * (2 * np.pi * f[0] * a) ** 2


@pytest.mark.parametrize("k3, tip0", [(1e7, 1e-4), (1e13, 1e-7)])
def test_beam_reaches_1000_times_its_first_energy_in_300_points(k3, tip0):
    """Hardening tip spring from a nearly linear tip amplitude (0.1 mm; the same structure with
    k3 x 1e6 at 0.1 um): 1000 x the energy bends NNM1 by ~19 % (both: the scaling law), in at most
    300 points whatever the amplitude's order of magnitude (balanced step norm)."""
    beam = cantilever_beam(k3=k3)
    E0 = _tip_energy(beam, tip0)
    b = nnm.continue_nnm(beam, 1, 1000 * E0, energy_min=E0, max_points=300)
    assert b.status == "done" and b.energy.max() >= 1000 * E0, b.message
    assert len(b) <= 300
    assert b.frequency_hz[-1] > 1.15 * b.frequency_hz[0]


# ---------------------------------------------------------------------- escape, loops
def test_softening_beam_with_tip_mass_escapes():
    base = cantilever_beam(k3=-1e7)
    M = np.array(base.M, dtype=float)
    M[tip_dof(), tip_dof()] += 4.0                             # a 4 kg payload at the tip
    beam = nnm.Model(M, base.K, base.springs)
    E_saddle, _ = softening_saddle_energy(beam, tip_dof(), -1e7)
    b = nnm.continue_nnm(beam, 1, 1.0, max_points=2000)
    assert b.status == "escape", b.message
    assert 0.99 * E_saddle < b.energy.max() <= E_saddle * (1 + 1e-6)
    assert f"{b.energy[-1]:.4g}" in b.message


def test_hardening_spring_between_masses_decades_apart_never_escapes():
    """A hardening relative cubic spring (k3 > 0: the potential is convex, x = 0 its only equilibrium) between
    a 1 t and a 1 g mass: mode 2's orbits carry a small component of the stiff light mode, whose linear force
    dominates |Omega^2 q|; the modal restoring-force norm ratio then fell below RESULTS.escape_ratio at 1.1 kJ and the
    branch was stopped as an escape.  The work ratio q . F / q . Omega^2 q (>= 1 when hardening) prevents it."""
    M = np.diag([1e3, 1e-3, 1e3])
    K = 1e9 * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
    b = nnm.continue_nnm(nnm.Model(M, K, springs=[nnm.CubicSpring(dof=0, other=1, k3=1e15)]), 2, 1e4,
                         max_points=300)
    assert b.status == "done", b.message
    assert np.all(np.diff(b.frequency_hz) > 0)          # hardening all the way


def test_softening_cantilever_never_runs_past_its_escape():
    """Without a payload the NNM meets k:1 tongues with mode 2 (k = 7, 9, 11, ...) on its way to the
    saddle: the continuation either passes them and stops at the escape, or follows one whose loop
    (through the mirrored orbits -x0) closes -- never beyond the escape energy, never 'failed'."""
    beam = cantilever_beam(k3=-1e7)
    E_saddle, _ = softening_saddle_energy(beam, tip_dof(), -1e7)
    b = nnm.continue_nnm(beam, 1, 0.02, max_points=2000)
    assert b.status in ("escape", "closed_loop"), b.message
    if b.status == "escape":
        assert 0.99 * E_saddle < b.energy[-1] <= E_saddle * (1 + 1e-6)
    else:
        assert "one lap" in b.message
        tip = b.x0[:, tip_dof()]
        assert tip.min() < 0 < tip.max()                       # the lap goes through the mirrored orbit


def test_loop_detector_on_a_circle_and_on_a_fold():
    det = LoopDetector(mirror=False)
    T_r = 1.0
    hits = []
    for k in range(40):                                        # two laps of a circle in (q0, T)
        a = 2 * np.pi * k / 15
        hits.append(det.add(np.array([2 + np.cos(a), 1.0]), np.zeros(2), 1.0, 1.0 + 0.1 * np.sin(a), T_r))
    first = next(i for i, h in enumerate(hits) if h is not None)
    assert 15 <= first <= 18
    det = LoopDetector(mirror=False)                           # up to a fold and back down: no loop
    for k in list(range(20)) + list(range(19, -1, -1)):
        assert det.add(np.array([1.0 + 0.1 * k, 0.5]), np.zeros(2), 1.0, 1.0 + 0.01 * k + 1e-4 * (k > 19), T_r) is None


def test_restoring_ratio_along_an_orbit():
    """r = |q + g(q)| / |q| for x'' + x - x^3 = 0 is 1 - q^2; over an orbit, the smallest value among the
    configurations with at least half the largest amplitude (passages through 0 do not count)."""
    from nnm_solver.model.modal import modal_system
    from nnm_solver.results.stops import restoring_ratio

    ms = modal_system(duffing_model(-1.0))
    assert restoring_ratio(ms, np.array([0.5])) == pytest.approx(0.75)
    Q = np.array([[0.01], [0.2], [0.99], [0.6], [-0.7]])
    assert restoring_ratio(ms, Q) == pytest.approx(1 - 0.99 ** 2)
    assert restoring_ratio(ms, Q[[0, 1, 3, 4]]) == pytest.approx(1 - 0.7 ** 2)


def test_local_collision_coordinates_match_the_full_eigenproblem():
    """ShootingProblem.local_collision (shift-invert Arnoldi on the deflated half map, used to follow a Krein
    collision during event location) returns the eigenvalues of the full problem nearest the shift."""
    from nnm_solver.model.modal import ModalSystem
    from nnm_solver.orbits.shooting import ShootingProblem
    beam = cantilever_beam(n_el=40)                       # 80 DOF: above the size where the full problem is used
    s = ModalSystem(beam)
    prob = ShootingProblem(s, 0, 100)
    q0 = np.zeros(s.n)
    q0[0] = 3e-3
    u = prob.pack(q0, np.zeros(s.n), prob.T_r)
    _, J = prob.jacobian(u)
    prob.accept(u, J)
    tangent = np.zeros(len(u))
    tangent[0] = 1.0
    prob.multipliers(u, tangent)
    full = np.asarray(prob.collision)
    for shift in (-0.61, 0.07, 0.93):
        local = prob.local_collision(tangent, shift, k=6)
        nearest = full[np.argsort(np.abs(full - shift))[:6]]
        assert np.allclose(np.sort_complex(local), np.sort_complex(nearest), atol=1e-9)
