"""Pseudo-arclength continuation on the 2-DOF benchmark: tongue, stability, scaling law, failures."""
import threading

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.shooting import ShootingProblem

from conftest import duffing_model, two_dof_model


def test_low_energy_is_the_linear_mode(two_dof_nnm1):
    b = two_dof_nnm1
    assert b.frequency_hz[0] == pytest.approx(1 / (2 * np.pi), rel=1e-4)
    assert b.mac_to_linear(0)[0] > 0.9999
    # conservative system: multipliers on the unit circle at low energy, the trivial pair at +1
    for i in range(5):
        mu = b.floquet[i]
        assert np.allclose(np.abs(mu), 1.0, atol=1e-3)
        assert np.sum(np.abs(mu - 1) < 1e-2) == 2
        assert b.stable[i]


def test_backbone_hardens_monotonically_before_the_tongue(two_dof_nnm1):
    b = two_dof_nnm1
    before = b.energy < 100
    assert np.all(np.diff(b.energy[before]) > 0)
    assert np.all(np.diff(b.frequency_hz[before]) > 0)


def test_three_to_one_tongue_is_traversed(two_dof_nnm1):
    """Energy goes up, down the tongue to its tip, up again, and the branch carries on beyond it."""
    b = two_dof_nnm1
    folds = [e for e in b.events if e["kind"] == "fold"]
    assert len(folds) >= 2
    top, tip = folds[0], folds[1]
    assert top["detail"] == "energy maximum" and tip["detail"] == "energy minimum"
    assert tip["energy"] < 0.2 * top["energy"]          # a long excursion down the tongue
    assert b.energy[-1] > top["energy"]                 # and beyond it
    # at the tip the orbit is dominated by the third harmonic (NNM2 at three times the frequency)
    h = b.harmonics(tip["index"], 5)
    assert h[3, 0] > 5 * h[1, 0]
    assert h[3].sum() > 0.7 * h[1:].sum()          # 0.75 at gauss6's fold (Newmark-200's, moved by its period error: 0.8)
    # the tongue sits where 3 x (its frequency) meets NNM2's frequency at that energy
    nnm2 = nnm.continue_nnm(b.model, mode=2, energy_max=tip["energy"] * 1.5)
    f2 = np.interp(tip["energy"], nnm2.energy, nnm2.frequency_hz)
    assert 3 * tip["frequency_hz"] == pytest.approx(f2, rel=0.05)


def test_energy_conserved_along_returned_orbits(two_dof_nnm1):
    b = two_dof_nnm1
    for i in (0, 20, len(b) // 2, len(b) - 1):
        t, x = b.motion(i, samples=200)
        v = b.velocity(i, samples=200)
        E = b.model.energy(x, v)
        assert np.ptp(E) / b.energy[i] < 2e-3
        assert E[0] == pytest.approx(b.energy[i], rel=1e-12)
        # and the orbit closes: periodicity
        tt, xx = b.motion(i, samples=200)
        assert np.allclose(x[0], xx[0])


def test_scaled_branch_equals_recomputation():
    m = two_dof_model(0.5)
    b = nnm.continue_nnm(m, mode=1, energy_max=20.0)
    s = b.scaled(4.0)
    r = nnm.continue_nnm(m.scaled(4.0), mode=1, energy_max=5.0)
    assert np.allclose(s.energy, b.energy / 4.0)
    f_interp = np.interp(np.log(r.energy), np.log(s.energy), s.frequency_hz)
    inside = (r.energy > s.energy[0]) & (r.energy < s.energy[-1])
    assert inside.sum() > 5
    assert np.allclose(r.frequency_hz[inside], f_interp[inside], rtol=1e-3)
    # every scaled orbit is a periodic orbit of the scaled model, to the continuation tolerance
    ms = modal_system(s.model)
    from nnm_solver.integrators.registry import get_integrator
    prob = ShootingProblem(ms, 0, s.settings["steps_per_period"], integrator=get_integrator(s.settings["integrator"]))
    for i in range(0, len(s), 5):
        u = prob.pack(ms.to_modal(s.x0[i]), ms.to_modal(s.v0[i]), s.period[i])
        assert prob.error(u, prob.residual(u)) < 1e-6
        assert s.model.energy(s.x0[i], s.v0[i]) == pytest.approx(s.energy[i], rel=1e-10)


def test_cancelled_job_keeps_its_points():
    m = two_dof_model()
    job = nnm.start_branch(m, 1, 1e8, max_points=100000)
    while len(job.points()) < 5:
        assert not job.done, job.error
        threading.Event().wait(0.02)
    job.cancel()
    b = job.result(timeout=30)
    assert job.done and job.error is None
    assert b.status == "cancelled" and len(b) >= 5
    assert np.all(np.isfinite(b.energy))
    # its progress is the fraction it reached, in log energy from the first point to 1e8 J (it said 1)
    expected = np.log(b.energy.max() / b.energy[0]) / np.log(1e8 / b.energy[0])
    assert job.progress == pytest.approx(expected) and job.progress < 0.5
    done = nnm.start_branch(m, 1, 1.0)
    done.result(timeout=60)
    done.cancel()                                      # after the end: nothing changes
    assert done.progress == 1.0 and done.result().status == "done"


def test_job_reports_solver_errors_without_raising_in_thread():
    def boom():
        raise RuntimeError("solver exploded")
        yield
    m = two_dof_model()
    it = nnm.iter_nnm(m, 1, 1.0)
    it._engine.engine = boom()           # (the engine inside the iterator's EngineDriver)
    job = nnm.Job(it)
    job._thread.start()
    with pytest.raises(RuntimeError, match="exploded"):
        job.result(timeout=10)
    assert job.done and isinstance(job.error, RuntimeError)


def test_softening_duffing_stops_at_its_escape():
    # softening Duffing: no periodic orbit above the separatrix energy 1/(4|k|) = 0.25 J
    b = nnm.continue_nnm(duffing_model(-1.0), mode=1, energy_max=1.0, max_points=2000)
    assert b.status == "escape" and "escape" in b.message and "equilibrium" in b.message
    assert len(b) > 10
    assert b.energy.max() < 0.25 + 1e-9 and b.energy.max() > 0.2499
    assert b.frequency_hz[-1] < 0.4 * b.frequency_hz[0]     # the period grows towards the separatrix
    assert b.stable.all()                                    # every orbit of a 1-DOF oscillator is stable


def test_branch_that_stops_converging_keeps_its_points():
    it = nnm.iter_nnm(two_dof_model(), 1, 1e4)
    engine = it._engine.engine

    def singular_after_ten():          # the engine gives up after 10 points, as at a singular point
        for _ in range(10):
            yield next(engine)
        return "16 consecutive failed steps (last: singular corrector system)"

    it._engine.engine = singular_after_ten()
    list(it)
    b = it.branch()
    assert b.status == "failed" and len(b) == 10
    assert "kept" in b.message and "singular corrector system" in b.message and "after point 10" in b.message


def test_at_energy_and_interpolate(two_dof_nnm1):
    b = two_dof_nnm1
    p = b.at_energy(1.0)
    assert len(p) == 1
    assert p.energy[0] == pytest.approx(1.0, rel=1e-9)          # the interpolated state is scaled to the energy
    j = np.searchsorted(b.energy, 1.0)
    assert b.frequency_hz[j - 1] <= p.frequency_hz[0] <= b.frequency_hz[j]
    with pytest.raises(nnm.NNMInputError):
        b.at_energy(1e9)
    q = b.interpolate(3.0)
    assert np.allclose(q.x0[0], b.x0[3])


def test_at_energy_of_a_harmonic_balance_branch_is_one_orbit():
    """An interpolated HB point's orbit (from its coefficients: orbit, motion) starts at its x0 and has its energy:
    the coefficients are scaled to the energy with x0 and v0 (they were not: x(0) 1.3 % below x0, the orbit's
    energy 2.7 % below the point's, between the widely spaced low-energy points of a Duffing branch)."""
    model = nnm.Model(np.eye(1), np.eye(1), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    b = nnm.continue_nnm(model, mode=1, energy_max=10.0, method="hb")
    for E in (1e-3, 0.37, 3.0):
        a = b.at_energy(E)
        t, x, v = a.orbit(0)
        assert x[0, 0] == pytest.approx(a.x0[0, 0], rel=1e-12)
        assert model.energy(x[0], v[0]) == pytest.approx(E, rel=1e-9) and a.energy[0] == pytest.approx(E, rel=1e-9)


def test_stop_event_stops_continue_nnm():
    ev = threading.Event()
    ev.set()
    b = nnm.continue_nnm(two_dof_model(), mode=1, energy_max=10.0, stop=ev)
    assert b.status == "cancelled" and len(b) == 0


def test_five_to_one_tongue_at_higher_energy(two_dof):
    b = nnm.continue_nnm(two_dof, mode=1, energy_max=3e5, tongues="follow-all")
    folds = [e for e in b.events if e["kind"] == "fold"]
    maxima = [e for e in folds if e["detail"] == "energy maximum"]
    top5 = max(maxima, key=lambda e: e["energy"])
    tip5 = next(e for e in folds if e["index"] > top5["index"] and e["detail"] == "energy minimum")
    assert top5["energy"] > 5e4 and tip5["energy"] < 0.1 * top5["energy"]
    h = b.harmonics(tip5["index"], 7)
    assert np.argmax(h[1:, 0]) + 1 == 5          # the 5th harmonic dominates at the tip


def test_general_phase_condition_agrees_with_reversible(two_dof):
    rev = nnm.continue_nnm(two_dof, mode=1, energy_max=10.0, tol=1e-9)
    gen = nnm.continue_nnm(two_dof, mode=1, energy_max=10.0, tol=1e-9, reversible=False)
    assert not gen.settings["reversible"] and rev.settings["reversible"]
    f = np.interp(np.log(rev.energy), np.log(gen.energy), gen.frequency_hz)
    inside = (rev.energy > gen.energy[0]) & (rev.energy < gen.energy[-1])
    assert np.allclose(rev.frequency_hz[inside], f[inside], rtol=2e-4)
    assert np.all(np.abs(gen.v0) < 1e-3 * np.abs(gen.x0).max())   # it also finds the orbits at rest


def test_engine_refuses_a_point_and_retries_with_half_the_step():
    """send(REFUSE) takes the engine back to the point before the refused one and steps again with half the
    step: the new point lies on the branch between the two."""
    import nnm_solver.continuation.engine as co
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=1.0)])
    it = nnm.iter_nnm(m, 1, 10.0)
    next(it)
    eng = co.pseudo_arclength(it._problem, it._prev[0].u, it._prev[0].tangent, it._cs, it._tol)
    first = next(eng)
    second = next(eng)
    third = eng.send(co.REFUSE)
    assert np.isclose(third.step, 0.5 * second.step)
    E = [it._problem.energy(cp.u) for cp in (first, third, second)]
    assert E[0] < E[1] < E[2]
    fourth = next(eng)                      # and goes on from there
    assert it._problem.energy(fourth.u) > E[1]
