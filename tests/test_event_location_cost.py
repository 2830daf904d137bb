"""What event location asks of its orbits and its full spectra (issue 52: "locating an event costs a few orbits"):
the located orbits' accuracy against the events' energy tolerance (Locator.chord_tol), and the full-flag probes of a
nested Krein location placed around the spectra its parent computed already (krein.probe_points), each checked
against an independent reference (the residual recomputed at each located orbit; the flag's change found by
bisection of the full flag on a synthetic spectrum)."""
import numpy as np
import pytest

import nnm_solver as nnm
import nnm_solver.stability.krein as krein
import nnm_solver.stability.locator as locator
from nnm_solver.stability.settings import STABILITY
from test_bifurcation import _combination_resonance_model, _pair
from test_krein_location import _windowed
from test_krein_routes import _flag_change


def test_probe_points_without_known_spectra_are_evenly_spaced():
    """No spectrum known inside: the STABILITY.krein_probes evenly spaced points, ordered from the stable end."""
    n = STABILITY.krein_probes
    assert np.allclose(krein.probe_points(0.0, 1.0), np.arange(1, n + 1) / (n + 1))
    assert np.allclose(krein.probe_points(1.0, 0.0), 1 - np.arange(1, n + 1) / (n + 1))
    assert np.allclose(krein.probe_points(0.0, 1.0, [0.0, 1.0, 1.5, -2.0]), np.arange(1, n + 1) / (n + 1))


@pytest.mark.parametrize("known", [[0.2455, 0.491], [0.05], [0.1, 0.2, 0.3, 0.4, 0.5], [0.559]])
def test_probe_points_keep_the_evenly_spaced_probes_gap(known):
    """With spectra known inside (start, stop), every one of them is checked, and new points only where two consecutive
    checked points (the ends included) lie farther apart than evenly spaced probes would, where that saves a probe;
    else the evenly spaced probes: never a larger gap, never more new points (the aircraft's NNM 20 at 200.59 J: its parent's probes at 0.2455 and
    0.491 of the step, in a nested location on [0, 0.5609]: 2 new probes instead of 3)."""
    start, stop = 0.0, 0.5609
    n = STABILITY.krein_probes
    for a, b in ((start, stop), (stop, start)):
        points = krein.probe_points(a, b, known)
        assert all(min(a, b) < x < max(a, b) for x in points)
        assert points == sorted(points, key=lambda x: abs(x - a))          # from the stable end
        checked = np.sort([a, b] + points)
        assert np.max(np.diff(checked)) <= abs(b - a) / (n + 1) * (1 + 1e-12)
        new = [x for x in points if x not in known]
        if len(new) < n:                              # the known points saved probes: all of them are checked
            assert all(k in points for k in known)
        else:                                         # else the evenly spaced probes
            assert np.allclose(sorted(points), min(a, b) + abs(b - a) * np.arange(1, n + 1) / (n + 1))
    if known == [0.2455, 0.491]:
        assert len([x for x in krein.probe_points(start, stop, known) if x not in known]) == 2


def test_a_nested_location_reuses_its_parents_probes(monkeypatch):
    """A step (stable at 0, complex at 1) where pair A collides at 0.95 and pair B collides at 0.6 and separates at
    0.72 (real at both ends, complex at the parent's probe 0.7125): the stability changes first at 0.6.  The nested
    location on [0, 0.7125] checks its probes between 0 and 0.6 around the parent's stable probes 0.2375 and 0.475
    (two new full spectra instead of three); the bracket holds the full flag's change found by bisection either way."""
    def coords(sigma):
        return np.array(_pair(0.5, 0.01 * (0.95 - sigma)) + _pair(-0.3, 0.01 * (sigma - 0.6) * (sigma - 0.72))
                        + [0.9, -0.95], dtype=complex)

    def run():
        loc, seen = _windowed(coords)
        flag = loc.stable

        def stable(sigma, tol=1e-5):            # a full spectrum is kept, as Locator.multipliers keeps it
            loc.spectra[float(sigma)] = (None, coords(sigma))
            return flag(sigma, tol)
        loc.stable = stable
        ends = [(loc.stable(x), coords(x)) for x in (0.0, 1.0)]
        seen.clear()
        lo, hi = krein.locate_collision(loc, 0.0, 1.0, krein.candidates(coords(1.0)), ends=ends)
        full = len(set(seen))
        ref = _flag_change(loc, 0.0, 0.65)            # (the first change from the stable end: inside B's bubble)
        assert abs(ref - 0.6) < 1e-6 and min(lo, hi) - 1e-9 <= ref <= max(lo, hi) + 1e-9
        return full

    reused = run()
    evenly = krein.probe_points
    monkeypatch.setattr(krein, "probe_points", lambda start, stop, known=(): evenly(start, stop))
    assert run() == reused + 1


def test_located_orbits_resolve_the_events_tolerance(monkeypatch):
    """Every orbit the event locators computed by chord iterations (Locator._from_latest) on the 3-DOF combination
    resonance (two Krein collisions, gauss6 at 100 steps) has a periodicity error, recomputed from its own residual,
    below Locator.chord_tol, which is at most STABILITY.chord_event_fraction x the events' energy tolerance: the
    orbits differ across an event's bracket by about rtol / 2, far more than their error."""
    seen = []
    from_latest = locator.Locator._from_latest

    def recorded(self, sigma, u_pred, refresh=True):
        result = from_latest(self, sigma, u_pred, refresh)
        if result is not None:
            seen.append((self, result[0].copy()))
        return result

    monkeypatch.setattr(locator.Locator, "_from_latest", recorded)
    branch = nnm.continue_nnm(_combination_resonance_model(), 1, 3.0, integrator="gauss6", steps_per_period=100,
                              freq_tol=None)
    assert [e["kind"] for e in branch.events if e.get("stability_change")] == ["torus", "torus"]
    assert len(seen) > 10
    for loc, u in seen:
        assert loc.chord_tol() <= STABILITY.chord_event_fraction * loc.rtol * (1 + 1e-12)
        error = loc.problem.error(u, loc.problem.residual(u))
        assert error < loc.chord_tol(), (error, loc.chord_tol(), loc.rtol)
