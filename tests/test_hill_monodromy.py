"""The monodromy route of Hill's multipliers (orbits/hill_monodromy.py; issue 52): the time-domain monodromy of the
variational equation along the HB orbit, for models with many modes and few elements (the unreduced aircraft's Ritz
system).  Checked against the dense Hill route: the same exact multipliers of the linearisation (the Hill route
with more harmonics converges to them), the same flags and events on the 2-DOF pitchfork and the 3-DOF chain's Krein
collisions, and the auto route and the driver's default for a Ritz basis."""
import dataclasses

import numpy as np
import pytest

import nnm_solver as nnm
from conftest import two_dof_model
from test_bifurcation import _combination_resonance_model
from test_hill import _matched, _orbits, _with_route
from nnm_solver.driver.problems import hb_floquet_default
from nnm_solver.orbits import hill, hill_monodromy
from nnm_solver.orbits.hb_basis import HBBasis
from nnm_solver.orbits.hill_monodromy import monodromy_multipliers, monodromy_steps, time_symmetric


@pytest.fixture(scope="module")
def pitchfork_orbits():
    m = two_dof_model()
    b = nnm.continue_nnm(m, 1, 57.0, method="hb", harmonics=7, floquet=False, max_points=400)
    return _orbits(m, b, 7, every=max(1, len(b.energy) // 12))


def test_monodromy_converges_to_the_hill_multipliers_with_more_harmonics(pitchfork_orbits):
    """At the last orbit (past the pitchfork, a real pair at 1.51): the monodromy route's error falls as h^6 with the
    steps (Gauss, 3 stages) and the dense Hill route's with its harmonics to the same multipliers; at the orbit's
    own H = 7 Hill's truncation is 1e-3 off them, the default steps 1e-7."""
    problem, us = pitchfork_orbits
    A, w = problem.unpack(us[-1])
    assert time_symmetric(problem.basis, A)
    ref = monodromy_multipliers(problem.sys, problem.basis, A, w, steps=1000)
    errors = [_matched(ref, monodromy_multipliers(problem.sys, problem.basis, A, w, steps=s)) for s in (28, 56, 112)]
    assert errors[0] > 30 * errors[1] > 30 * 30 * errors[2], errors           # ~2^6 per doubling
    assert _matched(ref, hill.hill_multipliers(problem, us[-1], harmonics=21, method="dense")) < 1e-9
    assert _matched(ref, hill.hill_multipliers(problem, us[-1], method="dense")) > 1e-4
    default = hill.hill_multipliers(problem, us[-1], method="monodromy")
    assert monodromy_steps(7) == 56 and _matched(ref, default) < 1e-6
    assert np.abs(default).max() > 1.5                                          # unstable: the test can fail


def test_monodromy_equals_dense_hill_along_the_branch(pitchfork_orbits):
    """Point by point below and past the pitchfork: within the Hill route's truncation (it grows with the amplitude),
    the same stability flag."""
    problem, us = pitchfork_orbits
    tol = 1e-6
    for u in us:
        dense = hill.hill_multipliers(problem, u, harmonics=15, method="dense")
        mono = hill.hill_multipliers(problem, u, method="monodromy")
        assert len(mono) == len(dense) == 2 * problem.n
        assert _matched(dense, mono) < 1e-6
        assert (np.abs(dense).max() <= 1 + tol) == (np.abs(mono).max() <= 1 + tol)


def test_a_full_period_where_the_orbit_is_not_time_symmetric(pitchfork_orbits):
    """The same orbit on the full basis and shifted in time (sines in its coefficients): the full-period route (a 2n x
    2n monodromy) gives the multipliers of the half-period one."""
    problem, us = pitchfork_orbits
    A, w = problem.unpack(us[-1])
    full = HBBasis(problem.basis.harmonics, "full")
    shift = 0.3                        # q(th + s): cos h(th + s) = cos h th cos h s - sin h th sin h s
    F, S = np.zeros((len(full), A.shape[1])), np.zeros((len(full), A.shape[1]))
    for j, hh in enumerate(problem.basis.h):
        c = int(np.flatnonzero((full.h == hh) & ~full.sine)[0])
        F[c] = A[j]
        S[c] += A[j] * np.cos(hh * shift)
        if hh:
            S[c + 1] -= A[j] * np.sin(hh * shift)
    assert time_symmetric(full, F) and not time_symmetric(full, S)
    a = monodromy_multipliers(problem.sys, problem.basis, A, w)
    assert _matched(a, monodromy_multipliers(problem.sys, full, F, w)) < 1e-12
    assert _matched(a, monodromy_multipliers(problem.sys, full, S, w)) < 1e-6


@pytest.mark.parametrize("case", ["pitchfork", "krein"])
def test_monodromy_flags_and_events_equal_dense(monkeypatch, case):
    """The 2-DOF benchmark's pitchfork (H = 7, a real pair through +1 at 40.98 J) and the 3-DOF chain's combination
    resonance (H = 15: two Krein collisions): the same events and flags by the monodromy route as by the dense Hill
    route, the events' energies within the routes' difference (Hill's truncation of the perturbation)."""
    if case == "pitchfork":
        m, E, H, kinds = two_dof_model(), 57.0, 7, ["branch_point"]
    else:
        m, E, H, kinds = _combination_resonance_model(), 3.0, 15, ["torus", "torus"]
    ref = _with_route(monkeypatch, "dense", m, 1, E, harmonics=H, max_points=400)
    mono = _with_route(monkeypatch, "monodromy", m, 1, E, harmonics=H, max_points=400)
    assert [e["kind"] for e in ref.events] == [e["kind"] for e in mono.events] == kinds
    assert np.allclose([e["energy"] for e in mono.events], [e["energy"] for e in ref.events], rtol=1e-3, atol=0)
    assert len(mono.energy) == len(ref.energy) and np.array_equal(mono.stable, ref.stable)
    assert not mono.stable.all()
    if case == "pitchfork":
        assert mono.events[0]["energy"] == pytest.approx(40.975, rel=3e-4)


def test_the_auto_route_and_the_driver_default():
    """auto: reversible, secular, monodromy by the Hill matrix's rows; multipliers by default for a Ritz basis whose
    route is the monodromy's (the unreduced aircraft: 670 modes at H = 9), not for a model's own modes there."""
    assert hill.auto_route(5, 7) == "reversible"
    assert hill.auto_route(100, 9) == "secular"
    assert hill.auto_route(548, 9) == hill.auto_route(670, 9) == "monodromy"
    assert hb_floquet_default(670, 9, True) and not hb_floquet_default(548, 9, False)
    assert hb_floquet_default(5, 7, False) and not hb_floquet_default(100, 9, True)
    assert not hb_floquet_default(5000, 9, True)                                # n^3 a point: not by default


def test_a_ritz_branch_takes_the_monodromy_route_by_default(monkeypatch):
    """A sparse beam above the Ritz threshold with the route's threshold lowered to its size: condensed HB with the
    default floquet computes the multipliers by the monodromy route (and equal to the dense Hill route's of the same
    Ritz system within its truncation)."""
    from test_ritz_multipliers import two_spring_beam
    calls = []
    real = hill_monodromy.monodromy_multipliers

    def counting(*args, **kw):
        calls.append(1)
        return real(*args, **kw)
    monkeypatch.setattr(hill, "monodromy_multipliers", counting)
    monkeypatch.setattr(hill, "ORBITS", dataclasses.replace(hill.ORBITS, hill_monodromy_min_rows=10))
    model = two_spring_beam(1100)
    b = nnm.continue_nnm(model, 1, 1e-4, method="hb", harmonics=5, condensed=True, max_points=6)
    assert b.settings.modal_basis == "ritz" and b.settings.floquet and len(calls) >= len(b)
    assert not np.isnan(b.floquet).any() and np.allclose(np.abs(b.floquet), 1.0, atol=1e-6) and b.stable.all()


def test_the_diagonal_blocks_are_the_monodromys(pitchfork_orbits):
    """hill_monodromy's half assembly (A11, A22) against gauss_monodromy.monodromy's whole map: to round-off."""
    from nnm_solver.integrators.gauss import constants
    from nnm_solver.integrators.gauss_monodromy import monodromy
    problem, us = pitchfork_orbits
    A, w = problem.unpack(us[-1])
    s, N = 3, 40
    k = constants(problem.sys, np.pi / w / N, s)
    Dseq = np.random.default_rng(1).uniform(0.0, 5.0, (N, s * problem.sys.Bq.shape[0]))
    Sq, Sv = monodromy(k, problem.sys.Bq, N, Dseq, 2 * problem.n, velocities=True)
    A11, A22 = hill_monodromy._diagonal_blocks(k, np.ascontiguousarray(problem.sys.Bq), N, Dseq)
    n = problem.n
    assert np.allclose(A11, Sq[:, :n], rtol=0, atol=1e-13 * np.abs(Sq).max())
    assert np.allclose(A22, Sv[:, n:], rtol=0, atol=1e-13 * np.abs(Sv).max())


@pytest.mark.slow
def test_monodromy_flags_equal_the_converged_dense_hill_route_along_a_tongue():
    """A mid-size case: the 20-DOF cantilever's NNM 1 (H = 5) through its 5:1 tongue.  At orbits below, inside and
    past the tongue the monodromy route's largest |multiplier| equals the dense Hill route's with 15 harmonics (1,240
    rows; the linearisation converged) to 1e-4, and so do the flags.  The dense route at the orbit's own H = 5 is far
    from both inside the tongue (|mu| 1.035 at 5.8 mJ, 1.00002 by that route: its truncation of the perturbation),
    which is why the reference here is the converged one.  (~1-3 min)"""
    from reference_models import cantilever_beam
    m = cantilever_beam(n_el=10)
    b = nnm.continue_nnm(m, 1, 0.05, method="hb", freq_tol=None, harmonics=5, floquet=False, max_points=300,
                         tongues="follow-all")
    problem, us = _orbits(m, b, 5)
    tol = 1e-6
    flags, missed = [], 0
    for E in (1.3e-3, 5.8e-3, 0.0134, 0.016):        # below, inside the tongue, near its fold, past it
        i = int(np.argmin(np.abs(b.energy - E)))
        ref = np.abs(hill.hill_multipliers(problem, us[i], harmonics=15, method="dense")).max()
        mono = np.abs(hill.hill_multipliers(problem, us[i], method="monodromy")).max()
        low = np.abs(hill.hill_multipliers(problem, us[i], method="dense")).max()
        assert abs(mono - ref) < 1e-4, (E, mono, ref)
        assert (mono <= 1 + tol) == (ref <= 1 + tol)
        flags.append(bool(mono <= 1 + tol))
        missed += abs(low - ref) > 10 * abs(mono - ref) + 1e-3
    assert flags[0] and not all(flags) and missed >= 1          # stable below, unstable in the tongue: can fail
