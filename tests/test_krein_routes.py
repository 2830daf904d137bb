"""The Krein locator without bisection of the full flag over a step (krein._earlier_change, krein_follow._root_within), on
synthetic spectra whose local solver sees only the 6 eigenvalues nearest its shift (as the shift-invert Arnoldi
does): a pair that drifts out of that window before the followed collision, and a pair whose test function is far
from linear (the secant stalls).  Each is checked against the full flag's own change (what a bisection of the
flag finds) and by the number of full spectra used; the dense route's count is what bisection costs."""
import dataclasses

import numpy as np
import pytest

import nnm_solver.stability.krein as krein
import nnm_solver.stability.krein_follow as krein_follow
from test_bifurcation import _pair, _synthetic_locator
from test_krein_location import _windowed

#: a dense real background spectrum (0.01 apart), as a large model's: the local window of 6 spans +-0.03
BACKGROUND = list(np.arange(-0.95, -0.05, 0.01) + 0.003)


def _flag_change(loc, lo, hi):
    """The full flag's change between lo and hi by bisection to 1e-12 (the dense reference)."""
    f_lo = loc.stable(lo)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if loc.stable(mid) == f_lo else (lo, mid)
    return 0.5 * (lo + hi)


def _locate(loc, seen, coords, unstable_end):
    ends = [(loc.stable(x), coords(x)) for x in (0.0, 1.0)]
    assert ends[0][0] != ends[1][0]
    seen.clear()
    lo, hi = krein.locate_collision(loc, 0.0, 1.0, krein.candidates(coords(unstable_end)), ends=ends)
    return lo, hi, len(set(seen))


@pytest.mark.parametrize("earlier", [True, False])
def test_a_pair_that_drifted_out_of_the_window_is_found_at_the_margin(monkeypatch, earlier):
    """Pair A collides at 0.8 and is the most unstable at the step's end; pair B collides at 0.3 and keeps still until
    0.8, then drifts 0.1 along the axis by the step's end: the local window around its end coordinate no longer
    holds it at A's collision, so it is not followed there.  The full flag at A's stable-side margin point is then
    unstable, and B is complex there: B is followed from that point (a few full spectra) instead of bisecting the
    full flag over the step (~30).  Both find the flag's own change at B's collision."""
    if not earlier:
        monkeypatch.setattr(krein, "STABILITY", dataclasses.replace(krein.STABILITY, krein_depth=0))

    def coords(sigma):
        centre = -0.4 - 0.5 * max(0.0, sigma - 0.8)
        return np.array(BACKGROUND + _pair(0.5, 0.01 * (0.8 - sigma)) + _pair(centre, 1e-4 * (0.3 - sigma)),
                        dtype=complex)

    loc, seen = _windowed(coords)
    lo, hi, full = _locate(loc, seen, coords, 1.0)
    ref = _flag_change(loc, 0.0, 1.0)
    assert abs(ref - 0.3) < 1e-3
    assert min(lo, hi) <= ref + 1e-9 and ref - 1e-9 <= max(lo, hi) and abs(hi - lo) <= loc.rtol * (1 + hi)
    if earlier:
        assert full <= 2 * (2 + krein.STABILITY.krein_probes) + 2
    else:
        assert full > 25


@pytest.mark.parametrize("checked", ["all", "overshoot", "none"])
def test_a_stalled_secant_is_not_taken_for_the_root(monkeypatch, checked):
    """A pair complex from the step's unstable start (sigma = 0) whose imaginary part stays at twice the stability
    threshold until 0.45, where it jumps onto the real axis and separates (its test function: -3e-10, then
    +7e-11 rising by 0.01 per unit sigma).  The secant from the far real side moves by ~1e-8 of the step and
    would stop there, short of the root; one local evaluation at the margin point shows the sign unchanged, so the
    follower bisects on (_root_within, or _beyond_root where the step was predicted that small); a secant iterate
    that close to the bracket's end is moved ten times as far from it (_clear_of_ends), which shows the stall by
    itself ("overshoot": the two checks off).  The flag's change at 0.45 is found from two margin spectra and the
    probes; with none of the three (and no nested location), by bisecting the full flag."""
    if checked != "all":                # (neither the secant's own check nor its predicted convergence's)
        monkeypatch.setattr(krein_follow, "_root_within", lambda *a, **k: None)
        monkeypatch.setattr(krein_follow, "_beyond_root", lambda *a, **k: None)
        monkeypatch.setattr(krein, "STABILITY", dataclasses.replace(krein.STABILITY, krein_depth=0))
    if checked == "none":
        monkeypatch.setattr(krein_follow, "_clear_of_ends", lambda c, lo, hi, again: (c, False, False))

    def coords(sigma):
        pair = ([0.5 + 2e-5j, 0.5 - 2e-5j] if sigma < 0.45 else _pair(0.5, 0.01 * (sigma - 0.45)))
        return np.array(BACKGROUND + pair, dtype=complex)

    loc, seen = _windowed(coords)
    loc.rtol = 5e-7                     # Newmark's event tolerance (the aircraft's): the secant's stall looks converged
    lo, hi, full = _locate(loc, seen, coords, 0.0)
    ref = _flag_change(loc, 0.0, 1.0)
    assert abs(ref - 0.45) < 1e-9
    assert min(lo, hi) <= ref + 1e-9 and ref - 1e-9 <= max(lo, hi) and abs(hi - lo) <= loc.rtol * (1 + hi)
    if checked != "none":
        assert full <= 2 + krein.STABILITY.krein_probes
    else:
        assert full > 25


@pytest.mark.slow
def test_aircraft_mode_20_events_and_flags_equal_the_dense_route(monkeypatch):
    """The aircraft's NNM 20 (548 modes, 4 cubic springs; 470 modes see them) to 10 J (Newmark, 200 steps): the local
    route (Krein collisions followed by shift-invert Arnoldi, the eigenproblem of the coupled modes) against the
    dense one (every Krein collision bisected on the full flag, the eigenproblem of all 548 modes): the same points,
    flags at every point, multipliers, and events (a loss at 7.44 J and a gain at 8.91 J).  The energies agree to
    1e-5: there the unstable pair's modulus excess |mu| - 1 hovers at the stability tolerance (9.985e-6 to 9.989e-6
    over 1.2e-5 of relative energy), so where it crosses 1e-5 moves by ~1e-5 with round-off and the orbit's own
    error (the two routes place it 5.4e-6 and 2.7e-6 apart)."""
    from pathlib import Path
    import nnm_solver as nnm
    import nnm_solver.stability.settings as st
    from test_decoupled_modes import _matched
    model = nnm.load_model(str(Path(__file__).resolve().parent.parent / "assets" / "paris.h5"))
    local = nnm.continue_nnm(model, 20, 10.0, integrator="newmark", freq_tol=None,
                             tongues="follow-all")   # the routes measured with
                                                                                      # Newmark-200, fixed steps
    with monkeypatch.context() as m:
        m.setattr(st, "STABILITY", dataclasses.replace(st.STABILITY, krein_route="dense"))
        dense = nnm.continue_nnm(model, 20, 10.0, integrator="newmark", freq_tol=None, tongues="follow-all")
    assert len(local.energy) == len(dense.energy) > 15
    assert np.allclose(local.energy, dense.energy, rtol=1e-9)
    assert np.array_equal(np.asarray(local.stable), np.asarray(dense.stable))
    assert max(_matched(a, b) for a, b in zip(local.floquet, dense.floquet)) < 1e-8
    kinds = [(e["kind"], e.get("stability_change")) for e in dense.events]
    assert kinds == [("torus", "loss"), ("torus", "gain")]
    assert [(e["kind"], e.get("stability_change")) for e in local.events] == kinds
    assert np.allclose([e["energy"] for e in local.events], [e["energy"] for e in dense.events], rtol=1e-5, atol=0)


def test_the_dense_route_is_a_setting(monkeypatch):
    """STABILITY.krein_route = "dense" (the reference) locates the 3-DOF combination resonance's two Krein collisions
    by bisection on the full flag (no local evaluation) and gives the default route's flags and events (gauss6, 100
    steps); any other value is refused."""
    import nnm_solver as nnm
    import nnm_solver.stability.settings as st
    import nnm_solver.stability.locator as locator
    from test_bifurcation import _combination_resonance_model
    m = _combination_resonance_model()
    calls = []
    local_collision = locator.Locator.local_collision

    def counted(self, sigma, shift):
        calls.append(sigma)
        return local_collision(self, sigma, shift)

    monkeypatch.setattr(locator.Locator, "local_collision", counted)
    local = nnm.continue_nnm(m, 1, 3.0, integrator="gauss6", steps_per_period=100, freq_tol=None)
    n_local = len(calls)
    monkeypatch.setattr(st, "STABILITY", dataclasses.replace(st.STABILITY, krein_route="dense"))
    calls.clear()
    dense = nnm.continue_nnm(m, 1, 3.0, integrator="gauss6", steps_per_period=100, freq_tol=None)
    assert n_local > 0 and not calls
    assert np.array_equal(np.asarray(local.stable), np.asarray(dense.stable))
    kinds = [(e["kind"], e.get("stability_change")) for e in dense.events]
    assert [(e["kind"], e.get("stability_change")) for e in local.events] == kinds
    assert [k for k in kinds if k[0] == "torus"] == [("torus", "loss"), ("torus", "gain")]
    assert np.allclose([e["energy"] for e in local.events], [e["energy"] for e in dense.events], rtol=2e-6, atol=0)
    with pytest.raises(ValueError, match="krein_route"):
        dataclasses.replace(st.STABILITY, krein_route="secular")


def _curve_locator(step, off=()):
    """A Locator on the plane curve u(sigma) = (sigma, sigma^2 + sigma^3) (w = 1, p_a = (1, 0): sigma is u's first
    coordinate), with the step's two ends and points at 1/8, 1/4 and 1/2 of the step cached; ``off`` : (fraction,
    offset) pairs that move the point at that fraction of the step by offset x step off the curve (another branch)."""
    from nnm_solver.stability.locator import Locator

    class Plane:
        def scale(self, u):
            return np.ones(2)

    def point(x, shift=0.0):
        return np.array([x, x * x + x ** 3 + shift]), None, np.array([1.0, 2 * x + 3 * x * x]) / np.hypot(
            1.0, 2 * x + 3 * x * x)

    loc = Locator(Plane(), None, 1e-10, np.zeros(2), np.array([1.0, 0.0]), step=step)
    moved = dict(off)
    for frac in (0.0, 0.125, 0.25, 0.5, 1.0):
        loc.cache[frac * step] = point(frac * step, moved.get(frac, 0.0) * step)
    return loc


def test_a_located_point_off_the_ends_interpolant_says_the_step_jumped():
    """Locator.strayed: points on the branch (a cubic, which the ends' Hermite interpolant reproduces) are not
    judged a jump; a point at 1/8 of the step moved 0.1 step lengths off (another sheet of the branch, as on the
    aircraft's NNM 20 at 1.374 J) is, whatever the mid-step point says; at 0.01 step lengths it is not (the limit is
    STABILITY.jump_limit = 0.05).  An end whose tangent is parallel to the hyperplanes is not judged."""
    assert krein.STABILITY.jump_limit == 0.05
    assert _curve_locator(0.3).strayed() == ""
    reason = _curve_locator(0.3, [(0.125, 0.1)]).strayed()
    assert "0.125 of the step" in reason and "0.10 step lengths" in reason
    assert _curve_locator(0.3, [(0.125, 0.01)]).strayed() == ""
    loc = _curve_locator(0.3, [(0.125, 0.1)])
    u, J, _ = loc.cache[0.3]
    loc.cache[0.3] = (u, J, np.array([0.0, 1.0]))
    assert loc.strayed() == ""


@pytest.mark.slow
def test_aircraft_mode_20_defaults_the_routes_follow_the_same_branch(monkeypatch):
    """The aircraft's NNM 20 with the defaults (gauss6, tongues followed) to 1.7 J, the dense route against the local
    one.  The step 1.3247 -> 1.6528 J crosses the entrance of the 3:1 tongue at 35.1336 Hz and lands on the backbone's
    sheet beyond it; its mid-step point lies 0.0499 step lengths off the ends' interpolant (below the jump limit), and
    the dense route's bisection placed its points on that other sheet (0.07-0.18 off) and reported a gain at 1.3739 J
    there.  Located points off the interpolant now refuse the step (Locator.strayed): both routes take the same
    points, into the tongue, with the same flags and events: the loss at 1.32291 J and the gain at 1.33465 J, where
    the full flag of the backbone's orbits, corrected on their energy level sets from the skeleton, changes
    (unstable at 1.33431 J, its excess |mu| - 1 = 1.2e-4; stable at 1.33541 J)."""
    from pathlib import Path
    import nnm_solver as nnm
    import nnm_solver.stability.settings as st
    model = nnm.load_model(str(Path(__file__).resolve().parent.parent / "assets" / "paris.h5"))
    local = nnm.continue_nnm(model, 20, 1.7)
    with monkeypatch.context() as m:
        m.setattr(st, "STABILITY", dataclasses.replace(st.STABILITY, krein_route="dense"))
        dense = nnm.continue_nnm(model, 20, 1.7)
    assert len(local.energy) == len(dense.energy) > 15
    assert np.allclose(local.energy, dense.energy, rtol=1e-9)
    assert np.allclose(local.frequency_hz, dense.frequency_hz, rtol=1e-12)
    assert np.array_equal(np.asarray(local.stable), np.asarray(dense.stable))
    for b in (local, dense):
        assert [(e["kind"], e.get("stability_change")) for e in b.events] == [("torus", "loss"), ("torus", "gain")]
        assert np.allclose([e["energy"] for e in b.events], [1.3229149, 1.3346490], rtol=5e-7, atol=0)
        assert any(label.startswith("tongue 3:1") for label in b.labels)     # the branch enters the tongue
        assert 1.33431 < b.events[1]["energy"] < 1.33541


def test_a_point_located_without_its_tangent_is_the_same_orbit(monkeypatch):
    """Locator.at(sigma, tangent=False) (the Krein follower's local evaluations, quarter-period shooting: the
    multipliers are swept at the orbit itself) ends on an older Jacobian's chord iterations, with no Jacobian at the
    converged point: the same orbit as the point with its tangent (the same iterations), one Jacobian fewer;
    asked for again with its tangent, the point gets the tangent a fresh locator computes.  3-DOF chain, gauss6."""
    import nnm_solver as nnm
    from nnm_solver.stability.locator import Locator
    from test_bifurcation import _combination_resonance_model
    it = nnm.iter_nnm(_combination_resonance_model(), 1, 3.0, integrator="gauss6", steps_per_period=100,
                      freq_tol=None)
    for _ in range(4):
        next(it)
    cp = it._prev[0]
    prob = it._problem
    assert prob.stability_needs_jacobian is False
    calls = []
    jacobian = type(prob).jacobian

    def counted(self, u):
        calls.append(1)
        return jacobian(self, u)

    monkeypatch.setattr(type(prob), "jacobian", counted)

    def locator():
        loc = Locator(prob, it._cs, it._tol, cp.u, cp.tangent, step=0.05)
        loc.cache[0.0] = (cp.u, None, cp.tangent)
        return loc

    rough, exact = locator(), locator()
    for loc in (rough, exact):           # a point located before, as the follower's earlier iterates
        loc.at(0.02)
    x = 0.0201
    calls.clear()
    u_r = rough.at(x, tangent=False)[0]
    n_rough = len(calls)
    u_e, _, p_e = exact.at(x)
    n_exact = len(calls) - n_rough
    assert x in rough.rough and x not in exact.rough
    assert n_rough < n_exact
    w = exact.w
    assert np.array_equal(u_r, u_e)      # the same chord iterations; the exact one adds the Jacobian at the end
    u_x, _, p_x = rough.at(x)
    assert x not in rough.rough and u_x is u_r
    assert np.linalg.norm(w * (p_x - p_e)) <= 1e-6
