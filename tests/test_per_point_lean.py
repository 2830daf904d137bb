"""The lean per-point path of condensed harmonic balance (issue 52) gives the branches of the plain one: compiled
kernels (orbits/condensed_kernels.py) against the numpy forms, the corrector's QR through numba against scipy's, the
energy slope from the closed-form gradient against central differences, and the mid-step check where the step is long
or a tongue near (stability/locator.mid_step_check) against at every step.  Compared: the aircraft's NNM 20 to 3 J
and, skipping tongues, to 6 J; the 2-DOF benchmark's NNM 1 to 50 J and, skipping tongues, to 200 J.  The branches
agree to round-off (the kernels sum in another order): the same points, labels, statuses, events and tongues, energies
and frequencies to 1e-12 relative on the 2-DOF, 1e-10 on the aircraft to 3 J (5e-12 seen), 1e-8 after a skip's
landings (2e-10 seen: a landing is corrected on the energy level set, its round-off moves the points after it along
the branch), freq_error (the truncation estimate, from an ill-conditioned bordered system next to a fold) to 1e-4
relative (7e-6 seen)."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.continuation import linalg
from nnm_solver.orbits import condensed_kernels
from nnm_solver.orbits.condensed_hb import CondensedHBProblem
from nnm_solver.stability import locator

ROOT = Path(__file__).resolve().parent.parent


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


CASES = {
    "aircraft to 3 J": (lambda: nnm.load_model(str(ROOT / "assets" / "paris.h5")), 20, 3.0,
                        dict(harmonics=9), 1e-10),
    "aircraft to 6 J, skip": (lambda: nnm.load_model(str(ROOT / "assets" / "paris.h5")), 20, 6.0,
                              dict(harmonics=9, tongues="skip"), 1e-8),
    "2-DOF to 50 J": (two_dof, 1, 50.0, {}, 1e-12),
    "2-DOF to 200 J, skip": (two_dof, 1, 200.0, dict(tongues="skip"), 1e-12),
}


def plain(monkeypatch):
    """The per-point path without the lean parts: numpy forms, scipy's QR, central differences, the check always."""
    monkeypatch.setattr(condensed_kernels, "AVAILABLE", False)
    monkeypatch.setattr(linalg, "_GEQRF", None)
    monkeypatch.setattr(CondensedHBProblem, "slope_from_gradient", False)
    monkeypatch.setattr(locator, "STABILITY", dataclasses.replace(locator.STABILITY, jump_check_long=0.0))


@pytest.mark.skipif(not condensed_kernels.AVAILABLE, reason="numba is not installed")
@pytest.mark.parametrize("name", sorted(CASES))
def test_the_lean_path_gives_the_plain_paths_branch(name, monkeypatch):
    make, mode, E, kw, rtol = CASES[name]
    model = make()
    lean = nnm.continue_nnm(model, mode, E, method="hb", condensed=True, **kw)
    with monkeypatch.context() as m:
        plain(m)
        ref = nnm.continue_nnm(model, mode, E, method="hb", condensed=True, **kw)
    assert lean.status == ref.status and len(lean) == len(ref) and len(lean) > 20, (lean.message, ref.message)
    assert list(lean.labels) == list(ref.labels)
    assert np.array_equal(lean.stable, ref.stable)
    np.testing.assert_allclose(lean.energy, ref.energy, rtol=rtol, atol=0)
    np.testing.assert_allclose(lean.frequency_hz, ref.frequency_hz, rtol=rtol, atol=0)
    np.testing.assert_allclose(lean.freq_error, ref.freq_error, rtol=1e-4, atol=0)
    np.testing.assert_allclose(lean.x0, ref.x0, rtol=0, atol=1e3 * rtol * np.max(np.abs(ref.x0)))
    assert [e["kind"] for e in lean.events] == [e["kind"] for e in ref.events]
    for a, b in zip(lean.events, ref.events):
        assert a["located"] == b["located"] and abs(a["energy"] / b["energy"] - 1) < 1e-9
    assert len(lean.tongues) == len(ref.tongues)
    for a, b in zip(lean.tongues, ref.tongues):
        assert (a.order, a.partner_mode, a.entry_index, a.landings, a.skipped) == \
               (b.order, b.partner_mode, b.entry_index, b.landings, b.skipped)
        assert abs(a.exit_energy / b.exit_energy - 1) < 1e-8 and abs(a.entry_energy / b.entry_energy - 1) < 1e-8


def test_mid_step_check_policy():
    """Long steps and steps next to a tongue (or where no skeleton measures the distance) are checked; short steps
    whose two ends lie on the family well within their labels' tolerance are not."""
    s = locator.STABILITY
    on = (1e-7, 1e-4)                        # (dev, tolerance): on the family, far from any tongue
    near = (0.05 * 1e-4, 1e-4)               # 5 % of the tolerance: the smallest seen at a jump on the aircraft
    assert not locator.mid_step_check(0.5 * s.jump_check_long, (on, on))
    assert locator.mid_step_check(s.jump_check_long, (on, on))
    assert locator.mid_step_check(1e-3, (on, near)) and locator.mid_step_check(1e-3, (near, on))
    assert locator.mid_step_check(1e-3, (None, on)) and locator.mid_step_check(1e-3, (on, (None, 0.0)))
    assert locator.mid_step_check(1e-3, (on, (np.inf, 1e-4)))


def test_restoring_lower_bound_is_below_the_ratio():
    """candidate.restoring_lower_bound: at most the exact restoring-force ratio (stops.restoring_ratio) on orbits of
    hardening and softening springs, at least 1 for hardening ones, and close to the ratio where the softening
    spring nearly cancels the linear force (where the escape test needs the ratio: it is then computed)."""
    from nnm_solver.driver.candidate import restoring_lower_bound
    from nnm_solver.model.modal import modal_system
    from nnm_solver.results.stops import restoring_ratio
    K = 2 * np.eye(4) - np.eye(4, k=1) - np.eye(4, k=-1)
    theta = 2 * np.pi * np.arange(40) / 40
    rng = np.random.default_rng(4)
    for k3 in (2.0, -0.5, -2.0):
        system = modal_system(nnm.Model(np.eye(4), K, springs=[nnm.CubicSpring(dof=0, k3=k3),
                                                               nnm.CubicSpring(dof=1, other=3, k3=0.5 * k3)]))
        for scale in (0.1, 0.3, 1.0):
            Q = scale * (np.outer(np.cos(theta), rng.standard_normal(4))
                         + 0.2 * np.outer(np.cos(3 * theta), rng.standard_normal(4)))
            bound, ratio = restoring_lower_bound(system, Q), restoring_ratio(system, Q)
            assert bound <= ratio * (1 + 1e-12)
            if k3 > 0:
                assert bound >= 1.0
            if k3 < 0 and scale == 0.1:
                assert bound > 0.5 * ratio            # a useful bound where the spring is weak
