"""Hill's multipliers of harmonic-balance orbits by the secular route (orbits/hill.py, issue 30) against the dense
route (every eigenpair of the Hill matrix, the reference): the same multipliers point by point, the same stability
flags and the same located events, on the 2-DOF benchmark's pitchfork (40.97 J), the 3-DOF chain's two Krein
collisions and a cantilever whose NNM 1 runs through a 5:1 tongue (where the classes near the trivial pair's copies
are found by their copies, orbits/hill_copies.py, or by the structured route where those decline)."""
import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

import nnm_solver as nnm
from conftest import two_dof_model
from reference_models import cantilever_beam
from test_bifurcation import _combination_resonance_model
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits import hill
from nnm_solver.orbits.hill_shared import forget_warm_starts
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from nnm_solver.stability.floquet import is_stable, without_nearest_to_one


def _matched(a, b):
    """Largest distance between the multipliers a and b paired one to one (the closest pairing)."""
    D = np.abs(np.asarray(a)[:, None] - np.asarray(b)[None, :])
    i, j = linear_sum_assignment(D)
    return D[i, j].max()


def _orbits(model, branch, harmonics, every=1):
    system = modal_system(model)
    problem = HBProblem(system, 0, HBBasis(harmonics, branch.settings.basis))
    us = [problem.pack(np.array([system.to_modal(x) for x in np.asarray(branch.coefficients_at(i))]),
                       2 * np.pi * branch.frequency_hz[i]) for i in range(0, len(branch.energy), every)]
    return problem, us


def _with_route(monkeypatch, route, *args, **kw):
    monkeypatch.setattr(HBProblem, "hill_method", route)
    return nnm.continue_nnm(*args, method="hb", **kw)


@pytest.fixture(scope="module")
def beam_tongue():
    """A 20-DOF cantilever's NNM 1 by HB (H = 5) through its 5:1 tongue (energy maximum 0.0141 J, minimum 0.0012 J)."""
    m = cantilever_beam(n_el=10)
    b = nnm.continue_nnm(m, 1, 0.05, method="hb", freq_tol=None, harmonics=5, floquet=False, max_points=300,
                         tongues="follow-all")
    assert [e["kind"] for e in b.events].count("fold") == 2
    return m, b


@pytest.mark.slow
def test_secular_multipliers_equal_dense_along_a_tongue(beam_tongue):
    """Point by point along the branch (warm starts from point to point, as in a continuation), outside and inside
    the tongue: the multipliers of the secular route (with its fallbacks) within 1e-8 of the dense route's (but at
    one orbit where the ordering is ambiguous) and the same flags everywhere; the secular route vouches for most
    points itself, with its copies or the structured route on its hard classes only inside the tongue.  (~30-70 s:
    a dense eigenproblem of 440 rows per point)"""
    m, b = beam_tongue
    problem, us = _orbits(m, b, 5, every=6)
    calls = {"none": 0, "hard": 0}
    from nnm_solver.orbits import hill_secular, hill_structured
    iterate, secular = hill_structured._iterate, hill._secular

    def counting(*args, **kw):
        calls["hard"] += 1
        return iterate(*args, **kw)

    def counting_secular(*args, **kw):
        mu = secular(*args, **kw)
        calls["none"] += mu is None
        return mu

    unstable, differ = 0, []
    hill_structured._iterate = hill_secular._iterate = counting      # the structured route's iteration, from both
    hill._secular = counting_secular
    try:
        for i, u in enumerate(us):
            mu = hill.hill_multipliers(problem, u, method="secular")
            A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
            ref = without_nearest_to_one(hill._dense(problem, w, bp, C))
            if _matched(without_nearest_to_one(mu), ref) >= 1e-8:
                differ.append(i)
            assert is_stable(without_nearest_to_one(mu)) == is_stable(ref)
            unstable += not is_stable(ref)
    finally:
        hill_structured._iterate = hill_secular._iterate = iterate
        hill._secular = secular
    # at the default period cap one sampled orbit inside the tongue (1 of 41) gets other multipliers than the dense
    # route's (0.18 apart; the structured route 0.008 there), with the same flag: there a kept eigenvector mixes with
    # the trivial pair's copies and which copy the wave-number ordering keeps is ambiguous (issue 30, open)
    assert len(differ) <= max(1, len(us) // 20), differ
    assert unstable >= 1              # the tongue's unstable side is in the sample
    assert calls["none"] <= 2 and 0 < calls["hard"]


def test_secular_route_is_fast_on_a_beam(beam_tongue, monkeypatch):
    """Away from internal resonances the secular route costs a few Newton iterations on 11 x 11 matrices, well below
    the dense eigenproblem of 440 rows: it vouches for every orbit below the tongue without the dense Hill matrix
    (nor an eigenproblem of more than r = 11 rows), and gives the dense route's multipliers.  (A wall-clock ratio
    here failed at load 3 with the suite beside it; the time is a benchmark's, not a unit test's.)"""
    m, b = beam_tongue
    problem, us = _orbits(m, b, 5)
    us = us[:20]                                      # below the tongue
    refs = []
    for u in us:
        A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
        refs.append(without_nearest_to_one(hill._dense(problem, w, bp, C)))
    sizes = []
    eigvals, solve, svd = np.linalg.eigvals, np.linalg.solve, np.linalg.svd

    def sized(f):
        def g(a, *args, **kw):
            sizes.append(np.shape(a)[-1])
            return f(a, *args, **kw)
        return g

    monkeypatch.setattr(hill, "_dense", lambda *a, **k: pytest.fail("the secular route fell back to the dense one"))
    monkeypatch.setattr(np.linalg, "eigvals", sized(eigvals))
    monkeypatch.setattr(np.linalg, "solve", sized(solve))
    monkeypatch.setattr(np.linalg, "svd", sized(svd))
    for u, ref in zip(us, refs):
        A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
        mu = hill._secular(problem, A, w, bp, C)
        assert mu is not None
        assert _matched(without_nearest_to_one(mu), ref) < 1e-8
    assert sizes and max(sizes) <= 2 * problem.n < len(bp) * problem.n    # no matrix of the dense route's size


@pytest.mark.parametrize("case", ["pitchfork", "krein"])
def test_secular_flags_and_events_equal_dense(monkeypatch, case):
    """The 2-DOF benchmark's pitchfork (NNM 1, H = 7: a real pair through +1 at 40.98 J) and the 3-DOF chain's
    combination resonance (H = 15: two Krein collisions, 1.71 and 2.37 J): the same points, flags, events (to 1e-8
    in energy) and multipliers (1e-8; 1e-7 through the collisions) by the secular route as by the dense one."""
    if case == "pitchfork":
        m, E, H, kinds = two_dof_model(), 57.0, 7, ["branch_point"]
    else:
        m, E, H, kinds = _combination_resonance_model(), 3.0, 15, ["torus", "torus"]
    ref = _with_route(monkeypatch, "dense", m, 1, E, harmonics=H, max_points=400)
    sec = _with_route(monkeypatch, "secular", m, 1, E, harmonics=H, max_points=400)
    assert [e["kind"] for e in ref.events] == [e["kind"] for e in sec.events] == kinds
    assert np.allclose([e["energy"] for e in sec.events], [e["energy"] for e in ref.events], rtol=1e-8, atol=0)
    assert len(sec.energy) == len(ref.energy) and np.array_equal(sec.stable, ref.stable)
    # next to a Krein collision the multipliers are a double eigenvalue: the dense route's own error there is about
    # sqrt(eps) (measured: 1.7e-8 at the default period cap), elsewhere the routes agree to ~1e-10
    assert max(_matched(a, b) for a, b in zip(sec.floquet, ref.floquet)) < (1e-8 if case == "pitchfork" else 1e-7)
    if case == "pitchfork":
        assert sec.events[0]["energy"] == pytest.approx(40.975, rel=3e-4)


@pytest.mark.slow
def test_secular_events_equal_dense_through_a_tongue(monkeypatch, beam_tongue):
    """The whole beam branch with the multipliers at every point: the same flags and events by the default route
    (secular) as by the dense one, to 1e-6.  Both put the loss of stability on the 5:1 tongue's energy maximum: the
    pair through +1 is located 1.6e-4 relative past the fold there, within the HB orbit's energy spread (3e-3), so it
    is the fold's (stability.events).  Before the structured route kept the trivial pair by its exponents (not by
    the vectors nearest the velocity, which next to a fold include the pair through +1) the secular route put that
    crossing at 0.0141042 J, the dense one at 0.0141099 J.  (~1 min)"""
    m, _ = beam_tongue
    ref = _with_route(monkeypatch, "dense", m, 1, 0.05, harmonics=5, max_points=300, tongues="follow-all")
    auto = _with_route(monkeypatch, "auto", m, 1, 0.05, harmonics=5, max_points=300, tongues="follow-all")
    assert len(auto.energy) == len(ref.energy) and np.array_equal(auto.stable, ref.stable)
    assert [e["kind"] for e in auto.events] == [e["kind"] for e in ref.events] == ["fold", "fold"]
    assert [e.get("stability_change") for e in auto.events] == [e.get("stability_change") for e in ref.events]
    assert [e.get("stability_change") for e in ref.events] == ["loss", "gain"]
    Ea, Er = np.array([e["energy"] for e in auto.events]), np.array([e["energy"] for e in ref.events])
    assert np.allclose(Ea, Er, rtol=1e-6, atol=0)


@pytest.mark.parametrize("case", ["pitchfork", "krein"])
def test_reversible_flags_and_events_equal_dense(monkeypatch, case):
    """The dense route on the symmetry blocks of a time-symmetric orbit (hill_reversible.py; the default up to
    DENSE_MAX_ROWS rows) against the whole Hill matrix: the 2-DOF pitchfork (H = 7) and the 3-DOF chain's two Krein
    collisions (H = 15): the same points, flags, events (to 1e-8 in energy) and multipliers point by point, and the
    reversible route answered every call itself (no fallback to the whole matrix)."""
    if case == "pitchfork":
        m, E, H, kinds = two_dof_model(), 57.0, 7, ["branch_point"]
    else:
        m, E, H, kinds = _combination_resonance_model(), 3.0, 15, ["torus", "torus"]
    ref = _with_route(monkeypatch, "dense", m, 1, E, harmonics=H, max_points=400)
    calls = {"rev": 0, "none": 0}
    rev_fn = hill.reversible_multipliers

    def counting(*args, **kw):
        mu = rev_fn(*args, **kw)
        calls["rev"] += 1
        calls["none"] += mu is None
        return mu

    monkeypatch.setattr(hill, "reversible_multipliers", counting)
    rev = _with_route(monkeypatch, "reversible", m, 1, E, harmonics=H, max_points=400)
    assert calls["rev"] >= len(rev.energy) and calls["none"] == 0
    assert [e["kind"] for e in ref.events] == [e["kind"] for e in rev.events] == kinds
    assert np.allclose([e["energy"] for e in rev.events], [e["energy"] for e in ref.events], rtol=1e-8, atol=0)
    assert len(rev.energy) == len(ref.energy) and np.array_equal(rev.stable, ref.stable)
    assert max(_matched(a, b) for a, b in zip(rev.floquet, ref.floquet)) < (1e-8 if case == "pitchfork" else 1e-7)
    if case == "pitchfork":
        assert rev.events[0]["energy"] == pytest.approx(40.975, rel=3e-4)


def test_reversible_route_needs_the_symmetry():
    """An orbit with sines (no time reversal) is not the reversible route's: it says so (None), the whole matrix
    decides; on a symmetric orbit its multipliers are the whole matrix's."""
    from nnm_solver.orbits.hill_reversible import reversible_multipliers
    m = two_dof_model()
    b = nnm.continue_nnm(m, 1, 30.0, method="hb", freq_tol=None, harmonics=7, floquet=False, max_points=40)
    problem, us = _orbits(m, b, 7)
    u = us[-1]
    A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
    ref = hill._dense(problem, w, bp, C)
    mu = reversible_multipliers(problem, w, bp, C)
    assert _matched(without_nearest_to_one(mu), without_nearest_to_one(ref)) < 1e-10
    full = HBProblem(problem.sys, 0, HBBasis(7, "full"))
    Af = np.zeros((len(full.basis), problem.n))
    Af[1] = A[0]                                        # cos 1
    Af[4] = 0.3 * A[0]                                  # sin 2: q(-t) != q(t)
    uf = full.pack(Af, w)
    Af_, wf, _, bpf, Cf = hill._galerkin_blocks(full, uf, None)
    assert reversible_multipliers(full, wf, bpf, Cf) is None


def test_hard_classes_by_their_copies_equal_dense_inside_a_tongue(beam_tongue):
    """Inside the 5:1 tongue the class near the trivial pair's copies is found by its copies at every lattice point
    (orbits/hill_copies.py) instead of the structured route's subspace iteration: at the points where the copies
    answer, the kept multipliers equal the dense route's (1e-8) with the same flags; they answer most hard points
    (the others: a pair colliding with the trivial one next to a fold, or a zero count near 0 they do not account
    for), and both flags occur among their answers (measured: 18 answered, 3 declined, 3 of the 18 unstable)."""
    from nnm_solver.orbits import hill_secular
    m, b = beam_tongue
    problem, us = _orbits(m, b, 5, every=3)
    answered, declined = [], 0
    copies = hill_secular.hard_copies

    def counting(*args, **kw):
        nonlocal declined
        found = copies(*args, **kw)
        if found is None:
            declined += 1
        else:
            answered.append(len(answered) + declined)
        return found

    hill_secular.hard_copies = counting
    flags = []
    try:
        for u in us:
            before = len(answered)
            mu = hill.hill_multipliers(problem, u, method="secular")
            if len(answered) == before:
                continue
            A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
            ref = without_nearest_to_one(hill._dense(problem, w, bp, C))
            assert _matched(without_nearest_to_one(mu), ref) < 1e-8
            assert is_stable(without_nearest_to_one(mu)) == is_stable(ref)
            flags.append(is_stable(ref))
    finally:
        hill_secular.hard_copies = copies
    assert len(answered) >= 5 and len(answered) > declined, (len(answered), declined)
    assert True in flags and False in flags


def test_copies_of_a_class_beyond_the_hill_harmonics():
    """The same beam's NNM 1 by HB with H = 3: mode 2's exponent sits near 5 i, beyond the H = 3 lattice points the
    copies start from by default; the class's own central copy is searched there too (at 0 .. max(H, |k0|)), so
    where the copies answer the multipliers equal the dense route's (1e-8) with its flags (measured before the
    fix: 2.2e-3 off at one orbit, the copy at 2.02 i kept instead of 5.02 i)."""
    from nnm_solver.orbits import hill_secular
    m = cantilever_beam(n_el=10)
    b = nnm.continue_nnm(m, 1, 0.05, method="hb", freq_tol=None, harmonics=3, floquet=False, max_points=300,
                         tongues="follow-all")
    problem, us = _orbits(m, b, 3, every=2)
    beyond = []
    copies = hill_secular.hard_copies

    def counting(nu_hard, H, *args, **kw):
        found = copies(nu_hard, H, *args, **kw)
        if found is not None and np.any(np.abs(np.round(np.imag(nu_hard))) > H):
            beyond.append(True)
        return found

    hill_secular.hard_copies = counting
    worst = 0.0
    try:
        for u in us:
            n_before = len(beyond)
            mu = hill.hill_multipliers(problem, u, method="secular")
            A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
            ref = without_nearest_to_one(hill._dense(problem, w, bp, C))
            assert is_stable(without_nearest_to_one(mu)) == is_stable(ref)
            if len(beyond) > n_before:
                worst = max(worst, _matched(without_nearest_to_one(mu), ref))
    finally:
        hill_secular.hard_copies = copies
    assert beyond, "no class beyond the Hill harmonics was answered by its copies"
    assert worst < 1e-8, worst


def test_trivial_pair_is_kept_by_its_exponents_next_to_a_fold():
    """Next to an energy fold the pair through +1 joins the trivial pair's Jordan chain: all four eigenvectors lie
    on the orbit's velocity (measured on NLvib's beam, example 09, just past its 5:1 tongue's energy maximum: |cos|
    0.9997 for a real pair +-3.7e-7, 1.0000 for the trivial pair +-1.4e-8 -- and the other way round at other
    orbits).  The structured route takes as the trivial pair the two exponents nearest 0 among the vectors near the
    velocity (the dense route's two multipliers nearest +1), so the real pair stays, whichever vectors are nearer."""
    from nnm_solver.orbits.hill_shared import _trivial_pair
    theta = np.array([-3.7e-7, 3.7e-7, 1.4e-8j, -1.4e-8j])
    for cos in ([0.99999, 0.99999, 0.9997, 0.9997], [0.9997, 0.9997, 0.99999, 0.99999]):
        assert list(_trivial_pair(np.array(cos), theta)) == [False, False, True, True]
    # a vector far from the velocity is never the trivial pair's, however near 0 its exponent; with fewer than two
    # near the velocity fewer are returned (and _iterate then declines: the block at 0 must hold the trivial pair)
    assert list(_trivial_pair(np.array([0.1, 0.9, 0.9, 0.2]), np.array([1e-9, 1e-3, 2e-3, 0.5]))) == \
        [False, True, True, False]
    assert list(_trivial_pair(np.array([0.9, 0.3, 0.2, 0.1]), np.array([1e-9, 1e-3, 2e-3, 0.5]))) == \
        [True, False, False, False]


@pytest.mark.slow
def test_cold_starts_inside_a_tongue_equal_dense(beam_tongue):
    """Each orbit from 15 points before the 5:1 tongue's energy maximum to 15 after its minimum on its own (no warm
    start: a branch switched onto inside the tongue, a file re-analysed, a sweep's worker): the default route's
    multipliers equal the dense route's (1e-6) with its flags.  Before the structured route's block at 0 waited for
    its trivial pair to converge (it excluded the two vectors nearest the velocity while iterating, which after a
    cold start are whatever the first sweep gives, and so could stop with nothing converged): 3 of these 42 orbits
    off by 0.1, one with |mu| - 1 = 4.5e-3 called stable.  (~8 s: 42 dense eigenproblems of 440 rows)"""
    from nnm_solver.orbits import hill_secular
    m, b = beam_tongue
    problem, us = _orbits(m, b, 5)
    first, last = [e["index"] for e in b.events if e["kind"] == "fold"][:2]
    flags, answered = [], []
    iterate = hill_secular._iterate

    def counting(*args, **kw):
        found = iterate(*args, **kw)
        answered.append(found is not None)
        return found

    hill_secular._iterate = counting
    try:
        _cold_orbits(problem, us, range(first - 15, last + 15), flags)
    finally:
        hill_secular._iterate = iterate
    assert flags.count(False) >= 5 and flags.count(True) >= 5
    assert sum(answered) >= 5              # the structured route answered (measured 7; not just handing over)


def _cold_orbits(problem, us, indices, flags):
    for i in indices:
        forget_warm_starts(problem)
        mu = without_nearest_to_one(hill.hill_multipliers(problem, us[i], method="secular"))
        A, w, _, bp, C = hill._galerkin_blocks(problem, us[i], None)
        ref = without_nearest_to_one(hill._dense(problem, w, bp, C))
        assert _matched(mu, ref) < 1e-6 and is_stable(mu) == is_stable(ref), i
        flags.append(is_stable(ref))


def test_secular_route_with_two_elements_equals_dense():
    """Two elements (a grounded and a relative spring, n_s = 2: the secular route's block products by an einsum over
    the 2 x 2 blocks, not the single-element column scaling): wherever the secular route answers (8 of 11 orbits),
    its multipliers are the dense route's to 1e-8, the trivial pair set to 1 in both (NNM 2 of a 6-DOF chain at
    H = 5 to 0.3 J)."""
    from test_condensed_hb import two_springs_chain
    m = two_springs_chain()
    b = nnm.continue_nnm(m, 2, 0.3, method="hb", freq_tol=None, harmonics=5, basis="full", floquet=False, tongues="skip")
    system = modal_system(m)
    problem = HBProblem(system, 1, HBBasis(5, "full"))
    us = [problem.pack(system.to_modal(b.coefficients_at(i)), 2 * np.pi * b.frequency_hz[i])
          for i in range(0, len(b.energy), 3)]
    assert problem.sys.Bq.shape[0] == 2
    answered = 0
    for u in us:
        A, w, _, bp, C = hill._galerkin_blocks(problem, u, None)
        mu = hill._secular(problem, A, w, bp, C)
        if mu is None:
            continue
        answered += 1
        # (the dense route splits the trivial pair's Jordan block by up to ~1e-5 here: set to 1 as the driver does)
        assert _matched(without_nearest_to_one(mu), without_nearest_to_one(hill._dense(problem, w, bp, C))) < 1e-8
    assert answered >= len(us) // 2
