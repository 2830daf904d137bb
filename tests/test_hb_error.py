"""The truncation error estimate of harmonic-balance branches (orbits/hb_error.py, ``branch.freq_error``) against
independent fixed-energy solutions with more harmonics: a Newton solve of the HB equations with the energy as the
extra equation (least squares, its own loop run to convergence, not the estimate's steps), started from the
branch's orbit."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.cli.solve import accuracy_line
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis, harmonics_in
from test_condensed_hb import ecl_beam, two_dof, two_springs_chain


def fixed_energy_frequency(problem, u, harmonics, samples=None):
    """omega (rad/s) of the HB orbit with ``harmonics`` (and ``samples``) at the energy of the orbit u of
    ``problem`` (an HBProblem), by Newton on [residual; energy - E0] from u (the new harmonics zero)."""
    big = HBProblem(problem.sys, problem.mode_index, HBBasis(harmonics, problem.basis.kind, samples))
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


def _changes(branch, mode, harmonics, reference, samples=None):
    """(estimate, |omega_reference / omega - 1|) of each point where the change exceeds 1e-7 (below, the
    corrector's tolerance, 1e-8 on the residual, is much of the difference)."""
    system = modal_system(branch.model)
    prob = HBProblem(system, mode - 1, HBBasis(harmonics, branch.settings.basis, samples))
    est, true = [], []
    for i in range(len(branch.energy)):
        if np.isinf(branch.freq_error[i]):            # not resolved: H + 2 does not settle there (no reference either)
            continue
        A = system.to_modal(branch.coefficients_at(i))
        u = prob.pack(A, 2 * np.pi * branch.frequency_hz[i])
        q0 = prob.initial_state(u)[0]
        prob.q_ref = q0 / np.linalg.norm(q0)          # the full basis's phase condition: t = 0 where the orbit rests
        H_ref, samples_ref = reference(harmonics)
        change = abs(fixed_energy_frequency(prob, u, H_ref, samples_ref) / (2 * np.pi * branch.frequency_hz[i]) - 1)
        if change > 1e-7:
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
    b = nnm.continue_nnm(two_dof(), 1, 5.0, method="hb", freq_tol=None, harmonics=5, basis=basis, condensed=condensed,
                         floquet=False, tongues="skip")
    assert b.status == "done" and np.isfinite(b.freq_error).all()
    est, true = _changes(b, 1, 5, lambda H: (3 * H, None))
    assert len(est) >= 10 and true.max() > 1e-6                # a nonlinear stretch, errors above the tolerance
    ratio = est / true
    assert ratio.min() > 0.95 and ratio.max() < 1.02, (ratio.min(), ratio.max())


@pytest.mark.parametrize("condensed", [False, True])
def test_estimate_is_the_change_with_two_more_harmonics_on_a_chain(condensed):
    """A 6-DOF chain with a grounded hardening and a relative softening spring, NNM 2 at H = 5 in the full basis to
    0.3 J: the estimate is the change to H + 2 at the same energy (within 3 %)."""
    b = nnm.continue_nnm(two_springs_chain(), 2, 0.3, method="hb", freq_tol=None, harmonics=5, basis="full", condensed=condensed,
                         floquet=False, tongues="skip")
    est, true = _changes(b, 2, 5, lambda H: (H + 2, None))
    assert len(est) >= 5
    assert np.all(np.abs(est / true - 1) < 0.03), est / true


def test_estimate_follows_the_error_where_a_softening_branch_steepens_before_its_saddle():
    """A 2-DOF chain with a softening spring (saddle at 0.417 J), NNM 1 at H = 9: over its last 1 % in energy below
    its saddle the frequency falls 25 % (|d ln E / d ln f| 0.12 to 0.02, no fold); the estimate is the change to
    31 harmonics at the same energy within a factor 2 (a balanced-norm fold test once made it 8e-9 for 4e-5)."""
    m = nnm.Model(np.eye(2), np.array([[1.3, -0.3], [-0.3, 10.9]]), springs=[nnm.CubicSpring(dof=0, k3=-1.0)])
    b = nnm.continue_nnm(m, 1, 0.5, method="hb", freq_tol=None, harmonics=9, basis="full", floquet=False, tongues="skip")
    steep = b.subset(np.flatnonzero((b.energy > 0.409) & (b.energy < 0.4145)))
    est, true = _changes(steep, 1, 9, lambda H: (31, None))
    assert len(est) >= 20 and true.max() > 5e-5
    assert np.all((est / true > 0.5) & (est / true < 2.0)), est / true


@pytest.mark.slow
@pytest.mark.parametrize("condensed", [False, True])
def test_estimate_on_the_ecl_beam_past_its_tongues(condensed):
    """The ECL cantilever (tip cubic spring), NNM 1 to 0.5 J at H = 5 with its tongues skipped, where the 7th
    harmonic nears mode 2 (the larger problem far from linear: several Newton steps): the estimate is 0.9-1.1 of the
    change to H + 2 at the same energy at every point, its median 1 (measured: 0.95-1.06), and finite everywhere.
    Against 15 harmonics it cannot see the narrow tongues of k:1 resonances with k > 7 (documented in hb_error.py):
    not asserted here."""
    b = nnm.continue_nnm(ecl_beam(), 1, 0.5, method="hb", freq_tol=None, harmonics=5, condensed=condensed, floquet=False,
                         tongues="skip")
    # the skip backbone (issue 51: the family past its tongues, jumped from the skeleton) has a few points next to a
    # 7:1 or 9:1 tongue where H + 2 does not settle: their estimate is inf, 'not resolved' (no silent number)
    finite = np.isfinite(b.freq_error)
    assert finite.mean() > 0.9 and np.all(np.isinf(b.freq_error[~finite]))
    est, true = _changes(b, 1, 5, lambda H: (H + 2, None))
    ratio = est[np.isfinite(est)] / true[np.isfinite(est)]
    assert len(ratio) > 100 and true.max() > 1e-3
    assert ratio.min() > 0.9 and ratio.max() < 1.1 and abs(np.median(ratio) - 1) < 0.01, (ratio.min(), ratio.max())


def test_estimate_keeps_the_sampling_density():
    """A clearance (piecewise-linear, smoothed) at H = 5 with samples=128 against aliasing: the larger problem is
    sampled as densely per harmonic, so the estimate is the change to H + 2 at that density (within 3 %), not the
    aliasing of the default 4H + 4 samples (which differs by 10-100x here)."""
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]),
                      springs=[nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.0, 3.0], breakpoints=[0.2], eps=0.02)])
    b = nnm.continue_nnm(model, 1, 2.0, method="hb", freq_tol=None, harmonics=5, samples=128, floquet=False, tongues="skip",
                         max_points=80)
    est, true = _changes(b, 1, 5, lambda H: (H + 2, int(np.ceil(128 * (H + 2) / H))), samples=128)
    assert len(est) >= 5
    assert np.all(np.abs(est / true - 1) < 0.03), est / true


@pytest.mark.slow
def test_estimate_inside_an_unresolved_tongue_is_inf():
    """2-DOF NNM 1 followed into its 3:1 tongue at H = 7 up to 2e4 J: where the orbit with two harmonics more is not
    near (Newton on the larger problem does not settle, or leaves the energy), the estimate is inf, not a number
    (it had given 4.6 and 11.8 there); those points are all in the tongue, the finite estimates stay below 0.05 and
    the backbone's below 2e-2 (1.25e-2 at the backbone point next to the tongue's entry fold: the frequency error at a
    fixed energy, magnified there by the branch's slope, fep_slope.py; the orthogonal step had said below 1e-2)."""
    b = nnm.continue_nnm(two_dof(), 1, 2e4, method="hb", freq_tol=None, harmonics=7, floquet=False, tongues="follow", max_points=800)
    err, labels = b.freq_error, np.asarray(b.labels)
    assert np.isinf(err).any() and not np.isnan(err).any()
    assert set(labels[np.isinf(err)]) == {"tongue 3:1"}
    assert err[np.isfinite(err)].max() < 0.05 and err[labels == "backbone"].max() < 2e-2
    assert "not resolved by the truncation" in accuracy_line(b)


def test_estimate_off_and_the_cli_line():
    """error_estimate=False leaves NaN; the CLI's accuracy line names the truncation and the remedy (harmonics)."""
    off = nnm.continue_nnm(two_dof(), 1, 5.0, method="hb", harmonics=3, floquet=False, error_estimate=False)
    assert np.isnan(off.freq_error).all()
    assert accuracy_line(off) == "  accuracy: no per-point error estimate"
    on = nnm.continue_nnm(two_dof(), 1, 5.0, method="hb", freq_tol=None, harmonics=3, floquet=False)
    line = accuracy_line(on)
    assert "harmonic balance, 3 harmonics" in line and "truncation" in line
    assert ("raise --harmonics" in line) == (np.nanmax(on.freq_error) > 1e-4)
