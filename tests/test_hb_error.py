"""The truncation error estimate of harmonic-balance branches (orbits/hb_error.py, ``branch.freq_error``) against
independent fixed-energy solutions with more harmonics: a Newton solve of the HB equations with the energy as the
extra equation (least squares, its own loop, not the estimate's tangent step), started from the branch's orbit."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.cli.solve import accuracy_line
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis, harmonics_in
from test_condensed_hb import ecl_beam, two_dof, two_springs_chain


def fixed_energy_frequency(problem, u, harmonics):
    """omega (rad/s) of the HB orbit with ``harmonics`` at the energy of the orbit u of ``problem`` (an HBProblem),
    by Newton on [residual; energy - E0] from u (the new harmonics zero)."""
    big = HBProblem(problem.sys, problem.mode_index, HBBasis(harmonics, problem.basis.kind))
    big.q_ref = problem.q_ref
    A, w = problem.unpack(u)
    v = big.pack(harmonics_in(big.basis, problem.basis, A), w)
    E0 = problem.energy(u)
    for _ in range(40):
        r, J = big.jacobian(v)
        dv = np.linalg.lstsq(np.vstack([J, big.energy_gradient(v)]), -np.r_[r, big.energy(v) - E0], rcond=None)[0]
        v = v + dv
        if np.linalg.norm(dv) <= 1e-13 * np.linalg.norm(v):
            break
    assert abs(big.energy(v) / E0 - 1) < 1e-10
    return big.unpack(v)[1]


def _changes(branch, mode, harmonics, reference):
    """(estimate, |omega_reference / omega - 1|) of each point where the change exceeds 1e-9 (below, the
    corrector's tolerance is the difference)."""
    system = modal_system(branch.model)
    prob = HBProblem(system, mode - 1, HBBasis(harmonics, branch.settings.basis))
    est, true = [], []
    for i in range(len(branch.energy)):
        A = system.to_modal(branch.coefficients_at(i))
        u = prob.pack(A, 2 * np.pi * branch.frequency_hz[i])
        q0 = prob.initial_state(u)[0]
        prob.q_ref = q0 / np.linalg.norm(q0)          # the full basis's phase condition: t = 0 where the orbit rests
        change = abs(fixed_energy_frequency(prob, u, reference(harmonics)) / (2 * np.pi * branch.frequency_hz[i]) - 1)
        if change > 1e-9:
            est.append(branch.freq_error[i])
            true.append(change)
    return np.array(est), np.array(true)


def test_energy_gradient_is_the_derivative_of_the_energy():
    """HBProblem.energy_gradient (closed form) against central differences, odd and full bases (the full one with
    sine terms: a velocity at t = 0), a model with a grounded and a relative spring of both signs."""
    system = modal_system(two_springs_chain())
    rng = np.random.default_rng(3)
    for kind in ("odd", "full"):
        prob = HBProblem(system, 1, HBBasis(5, kind))
        u = prob.pack(rng.normal(scale=0.3, size=(prob.nb, prob.n)), 1.3 * prob.w_r)
        g, g_fd = prob.energy_gradient(u), prob.energy_gradient_fd(u)
        assert np.max(np.abs(g - g_fd)) < 1e-7 * np.max(np.abs(g)), kind


@pytest.mark.parametrize("condensed", [False, True])
@pytest.mark.parametrize("basis", ["odd", "full"])
def test_estimate_is_the_error_on_the_two_dof_backbone(basis, condensed):
    """2-DOF (cubic spring to ground), NNM 1 to 5 J at H = 5: the estimate is 0.95-1.0 of the frequency's
    distance from the 15-harmonic orbit at the same energy (the error itself: the harmonics decay fast), for the
    uncondensed and the condensed equations and both bases; finite at every point."""
    b = nnm.continue_nnm(two_dof(), 1, 5.0, method="hb", harmonics=5, basis=basis, condensed=condensed,
                         floquet=False, tongues="skip")
    assert b.status == "done" and np.isfinite(b.freq_error).all()
    est, true = _changes(b, 1, 5, lambda H: 3 * H)
    assert len(est) >= 20 and true.max() > 1e-6                # a nonlinear stretch, errors above the tolerance
    ratio = est / true
    assert ratio.min() > 0.95 and ratio.max() < 1.02, (ratio.min(), ratio.max())


@pytest.mark.parametrize("condensed", [False, True])
def test_estimate_is_the_change_with_two_more_harmonics_on_a_chain(condensed):
    """A 6-DOF chain with a grounded hardening and a relative softening spring, NNM 2 at H = 7 in the full basis:
    the estimate is the change to H + 2 at the same energy (within 2 %)."""
    b = nnm.continue_nnm(two_springs_chain(), 2, 0.3, method="hb", harmonics=7, basis="full", condensed=condensed,
                         floquet=False, tongues="skip")
    est, true = _changes(b, 2, 7, lambda H: H + 2)
    assert len(est) >= 10
    assert np.all(np.abs(est / true - 1) < 0.02), est / true


@pytest.mark.slow
@pytest.mark.parametrize("condensed", [False, True])
def test_estimate_on_the_ecl_beam_past_its_tongues(condensed):
    """The ECL cantilever (tip cubic spring), NNM 1 to 0.5 J at H = 5 with its tongues skipped, where the 7th
    harmonic nears mode 2 (the larger problem far from linear: several Newton steps): the estimate is 0.6-1.1 of the
    change to H + 2 at the same energy at every point, its median 1 (measured: 0.91-1.06 uncondensed, 0.66-1.02
    condensed).  Against 15 harmonics it cannot see the narrow tongues of k:1 resonances with k > 7 (documented in
    hb_error.py): not asserted here."""
    b = nnm.continue_nnm(ecl_beam(), 1, 0.5, method="hb", harmonics=5, condensed=condensed, floquet=False,
                         tongues="skip")
    est, true = _changes(b, 1, 5, lambda H: H + 2)
    ratio = est / true
    assert len(ratio) > 100 and true.max() > 1e-3
    assert ratio.min() > 0.6 and ratio.max() < 1.1 and abs(np.median(ratio) - 1) < 0.01, (ratio.min(), ratio.max())


def test_estimate_off_and_the_cli_line():
    """error_estimate=False leaves NaN; the CLI's accuracy line names the truncation and the remedy (harmonics)."""
    off = nnm.continue_nnm(two_dof(), 1, 5.0, method="hb", harmonics=3, floquet=False, error_estimate=False)
    assert np.isnan(off.freq_error).all()
    assert accuracy_line(off) == "  accuracy: no per-point error estimate"
    on = nnm.continue_nnm(two_dof(), 1, 5.0, method="hb", harmonics=3, floquet=False)
    line = accuracy_line(on)
    assert "harmonic balance, 3 harmonics" in line and "truncation" in line
    assert ("raise --harmonics" in line) == (np.nanmax(on.freq_error) > 1e-4)
