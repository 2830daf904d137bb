"""The Krein locator's full-flag check (krein._flag_change_near) and the located points' continuity check
(Locator._from_latest), on a synthetic spectrum and on the 2-DOF benchmark."""
import dataclasses

import numpy as np
import pytest

import nnm_solver.stability.krein as krein
import nnm_solver.stability.krein_follow as krein_follow
from test_bifurcation import _pair, _synthetic_locator


def _windowed(coords):
    """A synthetic locator on coords(sigma) whose local solver returns the 6 coordinates nearest the shift, and the
    list of sigmas where the full flag was evaluated."""
    loc = _synthetic_locator(coords)
    seen = []
    stable = loc.stable

    def counted(sigma, tol=1e-5):
        seen.append(float(sigma))
        return stable(sigma, tol)

    loc.stable = counted
    loc.local_collision = lambda sigma, shift: (lambda c: c[np.argsort(np.abs(c - shift))[:6]])(coords(sigma))
    return loc, seen


def _noisy_locator(excess):
    """A synthetic step (E = 1 + sigma) with one pair colliding at sigma = 0.4, slowly (its imaginary part reaches
    the stability tolerance at 0.475); the full flag sees that imaginary part (1 + excess) times the local
    solver's, as two eigen-solvers differ near a collision.  Returns (locator, the sigmas of full evaluations)."""
    def local(sigma):
        return np.array(_pair(0.5, 1e-9 * (0.4 - sigma)) + [0.9, -0.95], dtype=complex)

    def full(sigma):
        c = local(sigma)
        return c.real + 1j * c.imag * (1 + excess)

    loc = _synthetic_locator(local)
    seen = []

    def stable(sigma, tol=1e-5):
        seen.append(float(sigma))
        c = full(sigma)
        return bool(np.all(np.abs(c.imag) <= tol * np.sqrt(np.clip(1 - c.real ** 2, 0, None))))

    loc.stable = stable
    loc.collision = full
    return loc, seen


@pytest.mark.parametrize("band", [True, False])
def test_full_flag_bracketed_by_two_margin_spectra(monkeypatch, band):
    """With the full flag's imaginary part 2e-4 relative above the local solver's, the full flag changes 1.5e-5
    before the local threshold: far outside the event tolerance (1e-8 here).  The two margin points around the
    local root bracket the change within the round-off band (FLAG_BAND): two full evaluations besides the
    probes, and the bracket is within the energy tolerance.  Without the band the flag is bisected instead."""
    if not band:
        monkeypatch.setattr(krein, "STABILITY", dataclasses.replace(krein.STABILITY, flag_band=0.0))
    loc, seen = _noisy_locator(2e-4)
    ends = [(loc.stable(x), loc.collision(x)) for x in (0.0, 1.0)]
    assert ends[0][0] and not ends[1][0]
    seen.clear()
    lo, hi = krein.locate_collision(loc, 0.0, 1.0, krein.candidates(loc.collision(1.0)), ends=ends)
    threshold = 0.4 + (1e-5 * np.sqrt(0.75)) ** 2 / 1e-9            # where the local pair's |mu| reaches 1 + tol
    assert abs(hi - lo) <= loc.rtol * (1 + hi) and min(lo, hi) < max(lo, hi)
    full_evaluations = len(set(seen))
    if band:
        assert abs(0.5 * (lo + hi) - threshold) < 1e-6
        assert full_evaluations == 2 + krein.STABILITY.krein_probes
    else:                                   # bisection on the full flag: its own change, more spectra
        assert not loc.stable(max(lo, hi)) and loc.stable(min(lo, hi))
        assert full_evaluations > 2 + krein.STABILITY.krein_probes + 5


def test_located_point_off_the_interpolant_is_computed_afresh(monkeypatch):
    """A located point whose chord iterations from the latest point converge 0.2 x d sigma off the interpolant of
    the known points (a branch alongside) is refused (None: computed afresh); on the interpolant it is kept."""
    import nnm_solver as nnm
    import nnm_solver.stability.locator as locator
    from conftest import two_dof_model
    from nnm_solver.continuation.engine import ContinuationSettings

    it = nnm.iter_nnm(two_dof_model(), 1, 10.0)
    pts = [next(it) for _ in range(6)]
    assert len(pts) == 6
    pcp = it._prev[0]
    prob = it._problem
    loc = locator.Locator(prob, it._cs or ContinuationSettings(), it._tol, pcp.u, pcp.tangent, step=0.05)
    loc.cache[0.0] = (pcp.u, pcp.jacobian, pcp.tangent)
    u1, J1, p1 = loc.at(0.02)                       # a located point: the latest
    assert loc.latest is not None and loc.latest[0] == 0.02
    sigma = 0.021
    u_pred = loc.prediction(sigma)
    kept = loc._from_latest(sigma, u_pred)
    assert kept is not None and np.linalg.norm(loc.w * (kept[0] - u_pred)) < 0.05 * 0.001
    correct = locator.correct_factored
    off = np.zeros_like(u_pred)
    off[0] = 0.2 * 0.001 / loc.w[0]                  # 0.2 x the distance to the nearest known point

    def elsewhere(*a, **k):
        u, J, it_, err, factor = correct(*a, **k)
        return u + off, J, it_, err, factor

    monkeypatch.setattr(locator, "correct_factored", elsewhere)
    assert loc._from_latest(sigma, u_pred) is None


@pytest.mark.parametrize("complex_shift", [True, False])
def test_a_pair_far_off_the_axis_in_a_dense_spectrum_is_followed(monkeypatch, complex_shift):
    """A dense real spectrum (0.0006 apart, as a 1,100-mode plate's) and a pair colliding at sigma = 0.3 that is
    0.017 off the axis at the step's unstable end: the 6 eigenvalues nearest its real part (the local solver's
    window) are all real there, so a real shift loses the pair and the flag is bisected (~20 full spectra); the
    pair's complex coordinate as the shift keeps it (the margin spectra and the probes only)."""
    if not complex_shift:
        monkeypatch.setattr(krein_follow, "STABILITY", dataclasses.replace(krein.STABILITY, local_crowd=10 ** 9))
    dense = list(0.30 + 0.0006 * np.arange(300))

    def coords(sigma):
        return np.array(dense + _pair(0.3903, 4e-4 * (0.3 - sigma)), dtype=complex)

    loc, seen = _windowed(coords)
    ends = [(loc.stable(x), coords(x)) for x in (0.0, 1.0)]
    seen.clear()
    lo, hi = krein.locate_collision(loc, 0.0, 1.0, krein.candidates(coords(1.0)), ends=ends)
    threshold = 0.3 + (1e-5 * np.sqrt(1 - 0.3903 ** 2)) ** 2 / 4e-4
    assert abs(0.5 * (lo + hi) - threshold) < 1e-6 and loc.stable(min(lo, hi)) and not loc.stable(max(lo, hi))
    if complex_shift:
        assert len(set(seen)) == 2 + krein.STABILITY.krein_probes
    else:
        assert len(set(seen)) > 2 + krein.STABILITY.krein_probes + 10
