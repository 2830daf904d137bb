"""Round 4 of the lean per-point path of condensed harmonic balance (issue 52): each cut computes the numbers of the form
it replaced (checked here against that form), and the branches are the same bit for bit.

* the corrector's chord iterations in one compiled call for the condensed problem (continuation/chord.py around the
  problem's residual kernel, the engine's hook ``problem.residual_kernel``; orbits/condensed_chord.py before round 5): the engine's iterates, errors, iteration counts and failures;
* Locator.jumped: the ends' interpolant made once (it is ``prediction``'s at mid-step) and no residual of its own at
  it (the corrector's first iterate is that residual: where it has converged already, d = 0).
"""
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from corrector_runs import corrected, same_run
from nnm_solver.continuation import chord, engine, linalg
from nnm_solver.continuation.engine import ContinuationSettings, CorrectorFailure, correct_factored
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits import condensed_kernels
from nnm_solver.orbits.condensed_hb import CondensedHBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from nnm_solver.stability import locator
from nnm_solver.stability.settings import STABILITY

ROOT = Path(__file__).resolve().parent.parent
numba = pytest.importorskip("numba")
needs_kernels = pytest.mark.skipif(not condensed_kernels.AVAILABLE or linalg._GEQRF is None,
                                   reason="numba (and its LAPACK) is not installed")


def chain(n=5):
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.eye(n), K, springs=[nnm.CubicSpring(dof=0, k3=0.8),
                                            nnm.CubicSpring(dof=2, other=4, k3=-0.3)])


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


@numba.njit
def _numba_dot(x, y):
    return np.dot(x, y)


def test_numbas_dot_is_numpys_bit_for_bit():
    """The compiled chord iterations take their norms and the arclength row's product by numba's np.dot: numpy's
    x.dot(y) and x @ y of 1-D float arrays (the engine's) give the same numbers (both BLAS's ddot) at every length."""
    rng = np.random.default_rng(3)
    for n in list(range(1, 70)) + [100, 257, 548]:
        for _ in range(40):
            x = rng.standard_normal(n) * 10.0 ** rng.uniform(-6, 6, n)
            y = rng.standard_normal(n)
            assert _numba_dot(x, y) == x.dot(y) == x @ y
            assert _numba_dot(x, x) == x.dot(x)


def _problem(model, mode=1, harmonics=5):
    system = modal_system(model)
    return CondensedHBProblem(system, mode - 1, HBBasis(harmonics, "odd"))


def _without_chord(monkeypatch):
    monkeypatch.setattr(chord, "AVAILABLE", False)


@needs_kernels
def test_the_compiled_chord_iterations_are_the_engines(monkeypatch):
    """correct_factored with the condensed problem's compiled chord iterations and with the engine's own loop: the same
    point, Jacobian, iteration count and error bit for bit, or the same failure (message and error), from predictions
    near and far along the 2-DOF's branch at 30 J (3 to 9 iterations, the Jacobian refreshed on the way; no
    convergence), with few iterations allowed, from a given iterate and factorisation (the locator's start) and without
    the refresh at the converged point."""
    it = nnm.iter_nnm(two_dof(), 1, 30.0, method="hb", condensed=True, floquet=False)
    for _ in it:
        pass
    prob, cp = it._problem, it._prev[0]
    u, p, w = cp.u, cp.tangent, prob.scale(cp.u)
    cases = [(u + s * p, ContinuationSettings(0.1, 1e-6, 1.0, max_iter=max_iter), refresh, None)
             for s in (0.05, 0.2, 0.5, 1.0) for max_iter in (12, 4) for refresh in (True, False)]
    row = w * w * p
    for s in (0.05, 0.3):                 # the locator's start: the point moved to the hyperplane, its factorisation
        cases.append((u + s * p, ContinuationSettings(0.1, 1e-6, 1.0), False, (u + s * p, cp.factor)))
    calls = []
    real = chord.chord_iterations

    def counted(*a):
        calls.append(a[9])
        return real(*a)

    monkeypatch.setattr(chord, "chord_iterations", counted)
    new = [corrected(prob, up, p, cs, 1e-10, w, start, refresh) for up, cs, refresh, start in cases]
    assert len(calls) >= len(cases) and row.dot(row) > 0
    with monkeypatch.context() as m:
        _without_chord(m)
        old = [corrected(prob, up, p, cs, 1e-10, w, start, refresh) for up, cs, refresh, start in cases]
    assert sum(isinstance(x, str) for x in old) >= 4 and sum(not isinstance(x, str) for x in old) >= 8
    assert max(x[2] for x in old if not isinstance(x, str)) >= 5
    for a, b in zip(new, old):
        assert same_run(a, b), (a, b)


@needs_kernels
def test_the_corrector_asks_no_residual_of_the_condensed_problem(monkeypatch):
    """With the compiled chord iterations the corrector evaluates no residual in Python (work counted, not timed): on
    the 2-DOF branch to 10 J the corrector calls the problem's residual method never, against several times a point
    with the engine's own loop (the skeleton's Newton, outside the corrector, calls it in both)."""
    import sys
    counts = {}

    def run(key):
        real = CondensedHBProblem.residual
        counts[key] = 0

        def counted(self, u):
            counts[key] += sys._getframe(1).f_code is engine.correct_factored.__code__
            return real(self, u)

        with monkeypatch.context() as m:
            m.setattr(CondensedHBProblem, "residual", counted)
            return nnm.continue_nnm(two_dof(), 1, 10.0, method="hb", condensed=True)

    new = run("new")
    with monkeypatch.context() as m:
        _without_chord(m)
        old = run("old")
    assert np.array_equal(new.energy, old.energy) and len(new) > 10
    assert counts["old"] > 2 * len(old)        # several chord iterations a point
    assert counts["new"] == 0


def reference_jumped(self, limit=STABILITY.jump_limit):
    """Locator.jumped as written before round 4: the interpolant's residual first, then the corrector from
    ``prediction``."""
    s = self.step
    if s is None or float(s) not in self.factors or self._ends_interpolant(0.5 * s) is None:
        return ""
    sigma = 0.5 * s
    u_pred = self.prediction(sigma)
    r = self.problem.residual(u_pred)
    if np.all(np.isfinite(r)) and self.problem.error(u_pred, r) < self.tol:
        return ""
    try:
        u, J, _, _, factor = correct_factored(self.problem, u_pred, self.p_a, self.settings, self.tol, self.w,
                                              start=(u_pred, self.factors[float(s)]), refresh=False)
    except CorrectorFailure as exc:
        return f"no convergence at mid-step ({exc})"
    if J is not None:
        self.latest = (sigma, u, factor)
        self._keep(sigma, u, J, factor)
    d = np.linalg.norm(self.w * (u - u_pred)) / abs(s)
    return f"the mid-step point lies {d:.2f} step lengths off the ends' interpolant" if d > limit else ""


def _snapshot(loc):
    import copy
    x = copy.copy(loc)
    x.cache, x.factors, x.latest = dict(loc.cache), dict(loc.factors), loc.latest
    return x


def test_jumped_decides_as_before_on_every_step(monkeypatch):
    """Locator.jumped and its earlier form on every step the 2-DOF's branch to 200 J checks (its tongues skipped):
    the same answer (reason and distance) and the same point kept for event location, step by step."""
    pairs = []
    real = locator.Locator.jumped

    def spy(self, limit=STABILITY.jump_limit):
        before = _snapshot(self)
        answer = real(self, limit)
        pairs.append((answer, self.latest, reference_jumped(before, limit), before.latest))
        return answer

    monkeypatch.setattr(locator.Locator, "jumped", spy)
    nnm.continue_nnm(two_dof(), 1, 200.0, method="hb", condensed=True, tongues="skip")
    assert len(pairs) > 15
    for answer, latest, reference, reference_latest in pairs:
        assert answer == reference
        assert (latest is None) == (reference_latest is None)
        if latest is not None:
            assert latest[0] == reference_latest[0] and np.array_equal(latest[1], reference_latest[1])
    assert sum(not a for a, *_ in pairs) > 10


@needs_kernels
@pytest.mark.parametrize("name", ["aircraft to 3 J", "2-DOF to 200 J, skip"])
def test_round_four_gives_round_threes_branch_bit_for_bit(name, monkeypatch):
    """The branch with round 4's forms and with the forms they replaced (the engine's own chord loop, jumped's
    residual first): equal in every column, bit for bit, the same labels, events and tongues."""
    cases = {"aircraft to 3 J": (lambda: nnm.load_model(str(ROOT / "assets" / "paris.h5")), 20, 3.0,
                                 dict(harmonics=9)),
             "2-DOF to 200 J, skip": (two_dof, 1, 200.0, dict(tongues="skip"))}
    make, mode, E, kw = cases[name]
    model = make()
    new = nnm.continue_nnm(model, mode, E, method="hb", condensed=True, **kw)
    with monkeypatch.context() as m:
        _without_chord(m)
        m.setattr(locator.Locator, "jumped", reference_jumped)
        old = nnm.continue_nnm(model, mode, E, method="hb", condensed=True, **kw)
    assert (new.status, new.message, list(new.labels)) == (old.status, old.message, list(old.labels))
    assert len(new) > 20
    for column in ("energy", "frequency_hz", "freq_error", "fundamental_share", "x0", "v0", "coefficients", "stable"):
        assert np.array_equal(getattr(new, column), getattr(old, column), equal_nan=True), column
    assert [(e["kind"], e["energy"]) for e in new.events] == [(e["kind"], e["energy"]) for e in old.events]
    assert [repr(t) for t in new.tongues] == [repr(t) for t in old.tongues]
