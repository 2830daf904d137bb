"""Bifurcation analysis (issue 11): located and classified events, branch switching, backbones past
tongues and tongues as their own branches.  The reference is the project's harmonic balance with
21 harmonics (an independent method), and the shooting results extrapolated in the time step."""
import numpy as np
import pytest

import nnm_solver as nnm
from conftest import two_dof_model
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from nnm_solver.stability.events import classify_multipliers, stability_changes


@pytest.fixture(scope="module")
def located():
    m = two_dof_model()
    shooting = {spp: nnm.continue_nnm(m, 1, 5000, steps_per_period=spp) for spp in (200, 1000)}
    hb = nnm.continue_nnm(m, 1, 5000, method="hb", harmonics=21, max_points=400)
    return shooting, hb


def _first(b, kind, n=1):
    return [e for e in b.events if e["kind"] == kind][:n]


def test_events_located_against_harmonic_balance(located):
    shooting, hb = located
    picks = lambda b: _first(b, "branch_point", 2) + _first(b, "fold", 2)     # loss, regain, tongue entry, tip
    ref = np.array([e["energy"] for e in picks(hb)])
    E200 = np.array([e["energy"] for e in picks(shooting[200])])
    E1000 = np.array([e["energy"] for e in picks(shooting[1000])])
    assert ref[0] == pytest.approx(40.975, rel=1e-4) and ref[2] == pytest.approx(4680.4, rel=1e-4)
    # at 1000 steps per period the located events carry Newmark's O(N^-2) error: <= 3e-4 here
    assert np.max(np.abs(E1000 / ref - 1)) < 3e-4
    # the error is the discretisation's, not the location's: extrapolated in N it vanishes
    extrapolated = E1000 + (E1000 - E200) / (25 - 1)
    assert np.max(np.abs(extrapolated / ref - 1)) < 5e-5


def test_events_located_to_1e4_with_a_higher_order_integrator(located):
    """Issue 12's 6th-order Gauss scheme removes the discretisation error that limits Newmark: the same four
    events at 200 steps per period agree with HB (21 harmonics) to 5e-5 and with 100 steps to 1e-6."""
    m = two_dof_model()
    hb = located[1]
    picks = lambda b: _first(b, "branch_point", 2) + _first(b, "fold", 2)
    ref = np.array([e["energy"] for e in picks(hb)])
    E = {spp: np.array([e["energy"] for e in picks(nnm.continue_nnm(m, 1, 5000, steps_per_period=spp,
                                                                     integrator="gauss6"))]) for spp in (100, 200)}
    assert np.max(np.abs(E[200] / ref - 1)) < 5e-5
    assert np.max(np.abs(E[100] / E[200] - 1)) < 1e-6


def test_located_events_carry_their_orbit(located):
    b = located[0][1000]
    m = b.model
    for e in b.events:
        assert e["located"] and len(e["x0"]) == m.n
        assert m.energy(np.array(e["x0"]), np.array(e["v0"])) == pytest.approx(e["energy"], rel=1e-9)
    fold = _first(b, "fold")[0]
    i = fold["index"]
    assert fold["energy"] >= b.energy[i - 1] and fold["energy"] >= b.energy[i]     # the maximum itself
    assert [e["stability_change"] for e in stability_changes(b.events)][:2] == ["loss", "gain"]


def test_classifier_on_synthetic_multipliers():
    unit = np.exp(1j * np.array([0.3, -0.3, 1.0, -1.0]))
    assert classify_multipliers(np.r_[unit, 1.0, 1.0]) == ""
    assert classify_multipliers(np.r_[unit, 1.2, 1 / 1.2]) == "branch_point"
    assert classify_multipliers(np.r_[unit, -1.3, -1 / 1.3]) == "period_doubling"
    z = 1.05 * np.exp(0.7j)
    assert classify_multipliers(np.r_[unit, z, np.conj(z), 1 / z, 1 / np.conj(z)]) == "torus"


def test_switch_branch_at_the_first_loss_of_stability(located):
    b = located[0][200]
    k = b.events.index(_first(b, "branch_point")[0])
    s = nnm.switch_branch(b, k, 1e4)
    assert len(s) > 10 and s.status in ("done", "closed_loop", "max_points")
    assert "family from the branch_point" in s.message and s.message.split(": ", 1)[1]
    assert not s.settings.symmetric and not s.settings.reversible
    assert np.abs(s.v0).max() > 1e-3 * np.abs(s.x0).max()                # general orbits, not at rest at t = 0
    h = s.harmonics(len(s) // 2, 4)
    assert h[2].max() > 0.05 * h[1].max()                                 # even harmonics: symmetry broken
    parent = b.harmonics(10, 4)
    assert parent[2].max() < 1e-6 * parent[1].max()                       # the parent family has none
    with pytest.raises(nnm.NNMInputError, match="cannot switch"):
        nnm.switch_branch(b, b.events.index(_first(b, "fold")[0]), 1e4)


def test_skip_mode_returns_the_backbone_and_tongues_match_follow():
    m = two_dof_model()
    follow = nnm.continue_nnm(m, 1, 3e5, tongues="follow-all")
    skip = nnm.continue_nnm(m, 1, 3e5, tongues="skip")
    assert skip.status == "done" and np.all(np.diff(skip.energy) > 0)     # a backbone, no excursion
    assert set(skip.labels) == {"backbone"}
    labels = [t["label"] for t in skip.tongues]
    # the 3:1 and 5:1 tongues that follow goes through; narrower odd ones above them (e.g. a 9:1 at 130 kJ whose
    # entrance follow steps over, tip 25.6 kJ) may be met too, depending on where the points fall
    assert labels[:2] == ["tongue 3:1", "tongue 5:1"]
    assert all(t["order"] > 5 and t["order"] % 2 == 1 for t in skip.tongues[2:])
    assert all(t["partner_mode"] == 2 for t in skip.tongues)
    assert len(skip) < len(follow)
    folds_follow = [e["energy"] for e in follow.events if e["kind"] == "fold"]
    for j, t in enumerate(skip.tongues):
        tb = nnm.continue_tongue(skip, j)
        assert tb.status == "done" and "back on the backbone" in tb.message
        assert any(lab == t["label"] for lab in tb.labels)
        if t["label"] not in follow.labels:
            continue
        for e in (e for e in tb.events if e["kind"] == "fold"):           # every fold of a tongue follow saw ...
            assert min(abs(E / e["energy"] - 1) for E in folds_follow) < 1e-5   # ... is one of follow's
        # the tongue's tip, far below its entry (the 3:1's tip 285.6 J; its entry, where the skip branch leaves the
        # backbone, is 1841 J since the skeleton tells the tongue's sheet from the backbone's (family_guide.py):
        # 3457 J before, the skeleton then following the tongue's upper sheet towards its 4708 J fold)
        tip = min(e["energy"] for e in tb.events if e["kind"] == "fold")
        assert tip < 0.2 * t["entry_energy"]


def test_events_labels_and_tongues_survive_the_file(tmp_path):
    m = two_dof_model()
    b = nnm.continue_nnm(m, 1, 3e5, tongues="skip", max_points=400)
    f = nnm.continue_nnm(m, 1, 1e4)
    path = tmp_path / "b.h5"
    nnm.save_branch(path, b)
    nnm.save_branch(path, f)
    lb, lf = nnm.load_branches(path)
    assert lb.tongues == b.tongues and lb.events == b.events
    assert list(lf.labels) == list(f.labels) and "tongue 3:1" in set(lf.labels)
    ax = nnm.plot_fep([lf], path=str(tmp_path / "fep.png"))
    labels = ax.get_legend_handles_labels()[1]
    assert "fold" in labels and "branch point" in labels


def _combination_resonance_model():
    """3 DOF, linear frequencies 1, 1.8, 2.4 rad/s (mixed by a fixed rotation), a hardening cubic spring on
    DOF 0: NNM 1 hardens through the combination resonance 4 w = w2 + w3, where two multipliers of opposite
    Krein signature collide (a 'torus' instability between two located events)."""
    from scipy.stats import ortho_group
    Phi = ortho_group.rvs(3, random_state=0)
    K = Phi @ np.diag([1.0, 1.8 ** 2, 2.4 ** 2]) @ Phi.T
    return nnm.Model(M=np.eye(3), K=K, springs=[nnm.CubicSpring(dof=0, k3=1.0)])


def test_krein_collisions_located_against_harmonic_balance(monkeypatch):
    """The Krein collisions located by the secant on their test function (floquet.krein_gap), with
    gauss6 shooting, match harmonic balance (Hill's multipliers, flag bisection) to 1e-6, and the same
    shooting branch located by bisection on the stability flag gives the same energies with more
    corrector runs."""
    import nnm_solver.stability.events as ev
    m = _combination_resonance_model()
    hb = nnm.continue_nnm(m, 1, 3.0, method="hb", harmonics=15, max_points=400)
    runs = []
    at = ev.Locator.at

    def counting_at(self, sigma, **kw):
        if float(sigma) not in self.cache:
            runs.append(sigma)
        return at(self, sigma, **kw)

    monkeypatch.setattr(ev.Locator, "at", counting_at)
    sh = nnm.continue_nnm(m, 1, 3.0, integrator="gauss6", steps_per_period=100, freq_tol=None)   # one step size:
    n_secant = len(runs)                                                # the locators' runs, not refinements
    ref = [e["energy"] for e in hb.events if e["kind"] == "torus"]
    got = [e["energy"] for e in sh.events if e["kind"] == "torus"]
    assert len(ref) == len(got) == 2 and all(e["located"] for e in sh.events if e["kind"] == "torus")
    assert np.allclose(got, ref, rtol=1e-6, atol=0)
    runs.clear()
    monkeypatch.setattr(ev, "locate_collision", lambda loc, lo, hi, rho_stars, ends=None: loc.bisect(loc.stable, lo, hi))
    bis = nnm.continue_nnm(m, 1, 3.0, integrator="gauss6", steps_per_period=100, freq_tol=None)
    assert np.allclose([e["energy"] for e in bis.events if e["kind"] == "torus"], got, rtol=2e-6, atol=0)
    assert n_secant < 0.75 * len(runs)


def test_located_folds_lie_on_their_step():
    """Every located fold is an energy extremum of its own step: at or beyond the energies of the two points
    around it and within 1 % of them.  (Near a tongue a hyperplane of the locator can cut the solution curve
    twice within one step; chord iterations started from another located point once converged to the
    other cut, 3 % away, on this beam.)"""
    import sys
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from reference_models import cantilever_beam
    b = nnm.continue_nnm(cantilever_beam(n_el=30), 1, 0.05, max_points=150, tongues="follow-all")
    E = np.asarray(b.energy)
    folds = [e for e in b.events if e["kind"] == "fold" and e["located"]]
    assert folds
    for e in folds:
        lo, hi = sorted((E[e["index"] - 1], E[e["index"]]))
        ext = hi if e["detail"] == "energy maximum" else lo
        assert (e["energy"] >= hi * (1 - 1e-9)) if e["detail"] == "energy maximum" else (e["energy"] <= lo * (1 + 1e-9))
        assert abs(e["energy"] / ext - 1) < 0.01, (e["energy"], lo, hi)


def test_beam_tongue_both_folds_located_and_passed():
    """A 60-DOF cantilever's NNM 1 runs into a tongue (energy maximum, then an energy minimum where
    the stability is regained) and out of it onto the backbone above.  A step once jumped from just
    past the tongue's energy-minimum fold back onto the incoming backbone: the minimum was left
    unlocated and the branch was cut as a spurious closed loop.  The step is now refused when an event
    inside it cannot be located, so both folds are located and the continuation goes on."""
    import sys
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from reference_models import cantilever_beam
    b = nnm.continue_nnm(cantilever_beam(n_el=30), 1, 0.05, max_points=160, tongues="follow-all")   # gauss6-100: 150 points to 5e-3 J
    assert b.status == "max_points", b.message
    folds = [e for e in b.events if e["kind"] == "fold"]
    assert [e["detail"] for e in folds] == ["energy maximum", "energy minimum"]
    assert all(e["located"] for e in folds)
    # the stability is regained at the minimum; it is lost at (or, within the stability tolerance, just past)
    # the maximum, where the critical pair leaves the unit circle very slowly
    assert folds[1].get("stability_change") == "gain"
    loss = [e for e in b.events if e.get("stability_change") == "loss"]
    assert len(loss) == 1 and abs(loss[0]["energy"] / folds[0]["energy"] - 1) < 5e-3
    E, f = np.asarray(b.energy), np.asarray(b.frequency_hz)
    i_min = folds[1]["index"]
    assert folds[1]["energy"] <= E[i_min - 3:i_min + 3].min() * (1 + 1e-9)
    # past the tongue: energy and frequency rise again along the backbone, above the tongue's frequencies
    assert E[-1] > 1.4 * folds[1]["energy"] and f[-1] > f[:i_min].max() + 0.05


def _synthetic_locator(coords):
    """An events.Locator whose branch is sigma itself (E = 1 + sigma) and whose collision coordinates are
    coords(sigma): the Krein locator's logic on a known spectrum."""
    import types
    from nnm_solver.stability.locator import Locator

    class Synthetic(Locator):
        def __init__(self):
            self.cache, self.spectra = {}, {}
            self.problem = types.SimpleNamespace(collision_per_modulus=1.0)

        def energy(self, sigma):
            return 1.0 + sigma

        def collision(self, sigma):
            return coords(sigma)

        def local_collision(self, sigma, shift):
            return coords(sigma)

        def stable(self, sigma, tol=1e-5):
            c = coords(sigma)
            return bool(np.all(np.abs(c.imag) <= tol * np.sqrt(np.clip(1 - c.real ** 2, 0, None))))

    return Synthetic()


def _pair(centre, d2):
    """Two collision coordinates centre +- sqrt(d2): real while d2 > 0, a complex pair once d2 < 0."""
    r = np.sqrt(complex(d2))
    return [centre + r, centre - r]


@pytest.mark.parametrize("reverse", [False, True])
def test_krein_locator_finds_the_first_of_several_collisions_in_a_step(reverse):
    """A step (sigma 0 -> 1) where pair A collides at 0.8 (complex at the unstable end) and pair B collides at
    0.3 and separates again at 0.6 (real at both ends): the stability changes first at 0.3, which the
    Krein locator must report (following A alone gives 0.8).  Reversed: the stable end is sigma = 1 and
    the change nearest it is at 1 - 0.3."""
    import nnm_solver.stability.krein as krein

    def coords(sigma):
        s = 1.0 - sigma if reverse else sigma
        return np.array(_pair(0.5, 0.01 * (0.8 - s)) + _pair(-0.3, 0.01 * (s - 0.3) * (s - 0.6)) + [0.9, -0.95],
                        dtype=complex)

    loc = _synthetic_locator(coords)
    ends = [(loc.stable(x), coords(x)) for x in (0.0, 1.0)]
    assert ends[0][0] != ends[1][0]
    unstable = coords(0.0 if reverse else 1.0)
    lo, hi = krein.locate_collision(loc, 0.0, 1.0, krein.candidates(unstable), ends=ends)
    expected = 0.7 if reverse else 0.3
    assert abs(0.5 * (lo + hi) - expected) < 1e-5 and loc.stable(lo) != loc.stable(hi)


def test_similar_mode_loss_of_stability_matches_hills_equation():
    """A 2-DOF system with identical grounded cubic springs and a linear coupling Kc has the similar
    anti-phase NNM x1 = -x2 = x(t), x'' + (1 + 2 Kc) x + x^3 = 0.  Its in-phase perturbation y obeys Hill's
    equation y'' + (1 + 3 x(t)^2) y = 0, whose monodromy (integrated by DOP853 at rtol 1e-12) gives the exact
    energy where the orbit loses stability (|trace| = 2).  gauss6 shooting locates it to 2e-8."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq
    Kc = 0.1
    m = nnm.Model(M=np.eye(2), K=np.array([[1 + Kc, -Kc], [-Kc, 1 + Kc]]),
                  springs=[nnm.CubicSpring(dof=0, k3=1.0), nnm.CubicSpring(dof=1, k3=1.0)])

    def trace_minus_two(A):
        def f(t, s):
            x, v, y, yd, z, zd = s
            q = 1 + 3 * x * x
            return [v, -(1 + 2 * Kc) * x - x ** 3, yd, -q * y, zd, -q * z]
        half = lambda t, s: s[1]
        half.direction, half.terminal = 1, True          # x = -A: half a period, the period of x^2
        sol = solve_ivp(f, [0, 50], [A, 0, 1, 0, 0, 1], method="DOP853", rtol=1e-12, atol=1e-14, events=half)
        s = sol.y_events[0][0]
        return abs(s[2] + s[5]) - 2

    amps = np.linspace(0.05, 1.0, 20)
    g = [trace_minus_two(A) for A in amps]
    i = next(k for k in range(len(g) - 1) if g[k] * g[k + 1] < 0)
    A = brentq(trace_minus_two, amps[i], amps[i + 1], xtol=1e-15, rtol=1e-15)
    exact = 2 * (A * A / 2 + A ** 4 / 4) + 2 * Kc * A * A
    b = nnm.continue_nnm(m, 2, 2.0, integrator="gauss6", steps_per_period=100)
    changes = stability_changes(b.events)
    assert len(changes) == 1 and changes[0]["kind"] == "branch_point" and changes[0]["stability_change"] == "loss"
    assert abs(changes[0]["energy"] / exact - 1) < 2e-8, (changes[0]["energy"], exact)


def _fold_and_crossing_step(s_fold, s_cross, rate=1.0, curvature=-1e-3):
    """A synthetic step sigma 0 -> 1: the energy 1 + curvature (sigma - s_fold)^2 (a fold at s_fold: a maximum for
    curvature < 0) and a real pair through +1 at s_cross (rho = 1 + rate (ds + 0.3 ds^2): a loss of stability for
    rate > 0, a gain for rate < 0).  Returns (locator, point(sigma), slope(sigma))."""
    import types
    from nnm_solver.stability.floquet import is_stable, sort_multipliers
    from nnm_solver.stability.locator import Locator

    def energy(s):
        return 1.0 + curvature * (s - s_fold) ** 2

    def slope(s):
        return 2 * curvature * (s - s_fold)

    def mults(s):
        # not linear: regula falsi does not land on the crossing, where the pair is 1, 1 (trivial)
        rho = 1.0 + rate * ((s - s_cross) + 0.3 * (s - s_cross) ** 2)
        m = ([np.exp(1j * np.arccos(rho)), np.exp(-1j * np.arccos(rho))] if rho <= 1 else
             [rho + np.sqrt(rho * rho - 1), 1 / (rho + np.sqrt(rho * rho - 1))])
        return sort_multipliers(np.array(m + [np.exp(0.7j), np.exp(-0.7j), 1.0, 1.0]))

    class Synthetic(Locator):
        def __init__(self):
            self.cache, self.spectra = {}, {}
            self.problem = types.SimpleNamespace()

        def at(self, s):
            self.cache[float(s)] = None
            return s, None, None

        def energy(self, s):
            self.at(s)
            return energy(s)

        def slope(self, s):
            self.at(s)
            return slope(s)

        def multipliers(self, s):
            self.at(s)
            return mults(s)

    def point(s):
        mu = mults(s)
        return types.SimpleNamespace(energy=energy(s), frequency_hz=1.0 + s, period=1 / (1.0 + s), x0=[s], v0=[0.0],
                                     floquet=mu, stable=is_stable(mu), _collision=None)
    return Synthetic(), point, slope


@pytest.mark.parametrize("s_cross, merged", [(0.3, True), (0.45, False)])
def test_stability_change_is_the_folds_only_where_the_fold_is(s_cross, merged):
    """A pair through +1 at the fold is the fold's stability change; one 15 % of the step further along the
    branch is a branch point of its own, although its energy is within 3e-5 of the fold's (energy is flat at a
    fold: it once was merged by energy)."""
    from nnm_solver.stability.events import locate_between
    loc, point, slope = _fold_and_crossing_step(0.3, s_cross)
    events, _ = locate_between(loc, 1.0, (point(0.0), slope(0.0)), (point(1.0), slope(1.0)), 5, point)
    kinds = [e["kind"] for e in events]
    if merged:
        assert kinds == ["fold"] and events[0]["stability_change"] == "loss"
    else:
        assert kinds == ["fold", "branch_point"] and "stability_change" not in events[0]
        assert abs(events[1]["x0"][0] - s_cross) < 1e-6 and events[1]["stability_change"] == "loss"


@pytest.mark.parametrize("spread, rate, curvature, path, s_cross", [
    (5e-5, 1.0, -1e-3, "crosses", 0.45), (5e-6, 1.0, -1e-3, None, 0.45), (3e-5, 1e-9, -1e-3, "located", 0.45),
    (2e-5, 1e-9, -1e-3, None, 0.45), (5e-5, -1.0, -1e-3, "crosses", 0.45), (5e-5, 1.0, 1e-3, "crosses", 0.45),
    (5e-6, -1.0, 1e-3, None, 0.45), (5e-5, 1.0, -1e-3, "crosses", 0.15), (5e-6, -1.0, 1e-3, None, 0.15)])
def test_a_crossing_within_the_orbits_energy_spread_is_the_folds(spread, rate, curvature, path, s_cross):
    """An approximate orbit (harmonic balance) defines its energy only to its spread over the period
    (HBProblem.energy_spread); a crossing 15 % of the step past or before the fold (2.25e-5 J from it) is the fold's
    when that spread is larger than its distance in energy, a branch point of its own when it is smaller: losses and
    gains (rate < 0), energy maxima and minima (curvature > 0).  Decided from the flag where the energy has moved by
    the spread ("crosses": events._within_spread) or, where the pair grows so slowly (rate 1e-9) that the flag there
    is still stable (|mu| - 1 < 1e-5), from the located crossing ("located")."""
    from nnm_solver.stability.events import locate_between
    loc, point, slope = _fold_and_crossing_step(0.3, s_cross, rate, curvature)
    loc.problem.energy_spread = lambda u: spread
    events, _ = locate_between(loc, 1.0, (point(0.0), slope(0.0)), (point(1.0), slope(1.0)), 5, point)
    kinds = [e["kind"] for e in events]
    change = "loss" if rate > 0 else "gain"
    if path:
        assert kinds == ["fold"] and events[0]["stability_change"] == change
        assert events[0]["note"].startswith(f"the multiplier through +1 {path}")
        assert events[0]["detail"] == ("energy maximum" if curvature < 0 else "energy minimum")
    else:
        assert kinds == ["fold", "branch_point"] and "stability_change" not in events[0]
        assert events[1]["stability_change"] == change and abs(events[1]["x0"][0] - s_cross) < 1e-3


@pytest.mark.parametrize("rate, change, end", [(1.0, "loss", 1.0), (-1.0, "gain", 0.0)])
def test_a_stability_change_quotes_the_multiplier_of_the_point_it_names(rate, change, end):
    """The event's text quotes the largest multiplier of the step's unstable end and names that point: the next
    one for a loss, the previous one for a gain (a gain once quoted the unstable point before it as 'next point',
    though the next point is stable)."""
    from nnm_solver.stability.events import locate_between
    loc, point, slope = _fold_and_crossing_step(2.0, 0.45, rate)        # (the fold outside the step: none in it)
    a, b = point(0.0), point(1.0)
    events, _ = locate_between(loc, 1.0, (a, slope(0.0)), (b, slope(1.0)), 5, point)
    (e,) = events
    assert e["kind"] == "branch_point" and e["stability_change"] == change
    unstable = point(end)
    assert not unstable.stable and abs(unstable.floquet[0]) > 1.5
    which = "next point" if change == "loss" else "previous point"
    assert e["detail"].endswith(f"({which}: {unstable.floquet[0]:.5g})"), e["detail"]


def test_hb_energy_spread_vanishes_on_exact_orbits_and_measures_the_truncation():
    """The energy of an HB orbit varies over its period by what the truncation leaves out: ~0 for the linear mode
    (an exact orbit), and on the 2-DOF benchmark's NNM 1 it shrinks with the harmonics (H = 3 -> 9 at ~20 J)."""
    from nnm_solver.model.modal import modal_system
    m = two_dof_model()
    spreads = []
    for H in (3, 9):
        b = nnm.continue_nnm(m, 1, 20.0, method="hb", harmonics=H, floquet=False)
        system = modal_system(m)
        problem = HBProblem(system, 0, HBBasis(H, b.settings.basis))
        rel = []
        for i in (0, len(b.energy) - 1):
            A = np.array([system.to_modal(x) for x in np.asarray(b.coefficients_at(i))])
            u = problem.pack(A, 2 * np.pi * b.frequency_hz[i])
            rel.append(problem.energy_spread(u) / b.energy[i])
        assert rel[0] < 1e-9
        spreads.append(rel[1])
    assert spreads[1] < 1e-3 * spreads[0] and spreads[0] > 1e-6, spreads


def test_locator_prediction_is_on_its_hyperplane_and_exact_for_a_cubic_branch():
    """Between two known points the locator predicts by cubic Hermite interpolation in sigma (values and
    tangents, du/dsigma = p / (w^2 p_a . p)): on sigma's hyperplane, and exact for a branch that is a cubic in
    sigma; outside the known points, the nearest point's tangent line."""
    from nnm_solver.stability.locator import Locator
    rng = np.random.default_rng(3)
    n = 6
    w = rng.uniform(0.5, 2.0, n)
    p_a = rng.standard_normal(n)
    p_a /= np.linalg.norm(w * p_a)
    row = w * w * p_a
    c1, c2 = 0.2 * rng.standard_normal(n), 0.1 * rng.standard_normal(n)      # a gently curved branch
    c1 -= (row @ c1) / (row @ p_a) * p_a                 # sigma = row . (u - u_a) exactly along the branch
    c2 -= (row @ c2) / (row @ p_a) * p_a
    u_a = rng.standard_normal(n)

    def u(s):
        return u_a + s * p_a + s * s * c1 + s ** 3 * c2

    def du(s):
        d = p_a + 2 * s * c1 + 3 * s * s * c2
        return 7.0 * d / np.linalg.norm(w * d)           # any normalisation of the tangent
    loc = Locator.__new__(Locator)
    loc.w, loc.p_a, loc.u_a, loc.cache = w, p_a, u_a, {}
    for s in (0.0, 1.0):
        loc.cache[s] = (u(s), None, du(s))
    for s in (0.13, 0.5, 0.91):
        pred = loc.prediction(s)
        assert abs(row @ (pred - u_a) - s) < 1e-12
        assert np.allclose(pred, u(s), atol=1e-12)
    ext = loc.prediction(1.2)                              # beyond: the tangent line at sigma = 1
    assert abs(row @ (ext - u_a) - 1.2) < 1e-12
    assert np.allclose(ext, u(1.0) + 0.2 * du(1.0) / (row @ du(1.0)), atol=1e-12)
