"""What locating an event costs (issue 52: "locating an event costs a few orbits"): a counting wrapper around the
shooting problem's eigen-solvers and the located orbits of each step, on the 3-DOF combination resonance (two Krein
collisions, gauss6 at 100 steps a period).  A regression to bisection of the full flag (the dense route, about 23
spectra an event) fails here."""
import dataclasses

import numpy as np

import nnm_solver as nnm
import nnm_solver.driver.iterator as iterator
import nnm_solver.integrators.registry as registry
import nnm_solver.stability.locator as locator
import nnm_solver.orbits.shooting_stability as shooting_stability
import nnm_solver.stability.settings as settings
from test_bifurcation import _combination_resonance_model


def _counted_run(monkeypatch):
    """The branch and, per step whose stability changes, (kind, local evaluations, full spectra, orbits located,
    sensitivity sweeps): the locator's local eigen-solver evaluations (near one pair), the problem's full multiplier
    sets (the coupled modes' eigenproblem), the points the step's locator computed besides its two ends, and the
    integrator's sensitivity sweeps during the location (Jacobians and half-period maps)."""
    calls = {"local": 0, "full": 0, "sweeps": 0}
    cls = shooting_stability.ShootingStability

    def counting(name, key):
        method = getattr(cls, name)

        def counted(self, *a, **k):
            calls[key] += 1
            return method(self, *a, **k)
        monkeypatch.setattr(cls, name, counted)

    counting("multipliers", "full")
    counting("multipliers_later", "full")
    local_collision = locator.Locator._local_collision

    def counted_local(self, *a, **k):        # (the locator's evaluations: a small model's may call the problem twice)
        calls["local"] += 1
        return local_collision(self, *a, **k)
    monkeypatch.setattr(locator.Locator, "_local_collision", counted_local)
    for name in ("sensitivity", "sensitivity_stages"):    # (the quarter-period Jacobian's sweep: sensitivity_stages)
        def counted_sweep(self, *a, _sweep=getattr(registry._Gauss, name), **k):
            calls["sweeps"] += 1
            return _sweep(self, *a, **k)
        monkeypatch.setattr(registry._Gauss, name, counted_sweep)
    per_event = []
    locate_between = iterator.locate_between

    def counted_between(loc, *a, **k):
        before, known = dict(calls), len(loc.cache)
        events, end = locate_between(loc, *a, **k)
        for e in events:
            if e.get("stability_change"):
                per_event.append((e["kind"], calls["local"] - before["local"], calls["full"] - before["full"],
                                  len(loc.cache) - known, calls["sweeps"] - before["sweeps"]))
        return events, end

    monkeypatch.setattr(iterator, "locate_between", counted_between)
    branch = nnm.continue_nnm(_combination_resonance_model(), 1, 3.0, integrator="gauss6", steps_per_period=100,
                              freq_tol=None)
    return branch, per_event


def test_a_krein_collision_costs_a_handful_of_orbits(monkeypatch):
    """Each of the two Krein collisions is located with at most 11 evaluations of the multipliers (the follower's
    local ones, the two margin points' spectra and the 3 probes'; measured 11 and 10, 12 and 10 before the follower's
    predicted convergence), at most 10 orbits computed inside the step and 18 sensitivity sweeps (15 and 13; 20 and 17
    while each point's half-period map took a sweep of its own, before the quarter-period Jacobian's sweep gave it: a
    model this small has the trivial coordinate in every local window, so each local evaluation takes its point's
    Jacobian too); the dense route's bisection of the full flag needs 23 spectra and 23 sweeps for each (46 before).  The same flags, and the events within 1e-7 of the dense route's (the
    event tolerance is 1e-8, but the full flag's round-off band, STABILITY.flag_band, moves the threshold of a slow
    collision further: 5.0e-8 at the second torus, 5.3e-8 before this count was introduced)."""
    local, cost = _counted_run(monkeypatch)
    assert [c[0] for c in cost] == ["torus", "torus"]
    for kind, n_local, n_full, orbits, sweeps in cost:
        assert n_local + n_full <= 11 and orbits <= 10 and sweeps <= 18, cost
        assert n_full <= 2 + settings.STABILITY.krein_probes, cost
    monkeypatch.setattr(settings, "STABILITY", dataclasses.replace(settings.STABILITY, krein_route="dense"))
    dense, dense_cost = _counted_run(monkeypatch)
    assert [c[0] for c in dense_cost] == ["torus", "torus"]
    assert all(n_local == 0 and n_full > 20 and sweeps > 20 for _, n_local, n_full, _, sweeps in dense_cost), dense_cost
    assert np.array_equal(np.asarray(local.stable), np.asarray(dense.stable))
    e_local = [e["energy"] for e in local.events if e.get("stability_change")]
    e_dense = [e["energy"] for e in dense.events if e.get("stability_change")]
    assert np.allclose(e_local, e_dense, rtol=1e-7, atol=0), (e_local, e_dense)
