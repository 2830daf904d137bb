"""The Floquet multipliers computed in the worker thread while the engine computes the next point
(ShootingStability.multipliers_later, EngineDriver.ahead, Locator.prefetch) give the branch that computing them
in turn gives: the same points, flags and events, also when a step is refused after the engine went on."""
import dataclasses

import numpy as np
import pytest

import nnm_solver as nnm
import nnm_solver.continuation.engine_driver as engine_driver
import nnm_solver.stability.locator as locator
import nnm_solver.orbits.shooting_stability as shooting_stability
from conftest import two_dof_model


def _background_from(monkeypatch, n):
    """The multipliers in the worker threads from n modes up (ORBITS.background_min_n of shooting_stability)."""
    monkeypatch.setattr(shooting_stability, "ORBITS",
                        dataclasses.replace(shooting_stability.ORBITS, background_min_n=n))


def _run(monkeypatch, background, refuse=(), model=None, mode=1, energy=1e4, **kw):
    """The branch with the eigenproblems in the worker thread (background) or not; refuse : the calls of the
    mid-step check (Locator.jumped) that refuse their step whatever it finds.  Returns (branch, the number of
    points computed ahead, the number of engine restarts)."""
    _background_from(monkeypatch, 1 if background else 10 ** 9)
    calls, ahead, restarts = [], [], []
    jumped, go_ahead = locator.Locator.jumped, engine_driver.EngineDriver.ahead
    restart = engine_driver.EngineDriver.restart

    def check(self, *a):
        calls.append(1)
        return "refused by the test" if len(calls) in refuse else jumped(self, *a)

    def count(self):
        ahead.append(1)
        return go_ahead(self)

    monkeypatch.setattr(locator.Locator, "jumped", check)
    monkeypatch.setattr(engine_driver.EngineDriver, "ahead", count)
    monkeypatch.setattr(engine_driver.EngineDriver, "restart", lambda self, e: restarts.append(1) or restart(self, e))
    b = nnm.continue_nnm(model or two_dof_model(), mode, energy, **kw)
    return b, len(ahead), len(restarts)


def _same(a, b):
    assert len(a) == len(b) and a.status == b.status
    assert np.allclose(a.energy, b.energy, rtol=1e-9, atol=0)
    assert np.allclose(a.frequency_hz, b.frequency_hz, rtol=1e-11, atol=0)
    assert list(a.stable) == list(b.stable)
    assert np.allclose(np.abs(a.floquet), np.abs(b.floquet), rtol=0, atol=1e-9)
    assert [e["kind"] for e in a.events] == [e["kind"] for e in b.events]
    assert np.allclose([e["energy"] for e in a.events], [e["energy"] for e in b.events], rtol=1e-8, atol=0)


@pytest.mark.parametrize("refuse", [(), (5, 20)])
def test_multipliers_in_the_background_give_the_same_branch(monkeypatch, refuse):
    """NNM 1 of the 2-DOF through its 3:1 tongue (folds and branch points): the same branch both ways, also with
    two steps refused after the engine had computed the next point (it restarts at the point before them)."""
    ref, ahead_ref, _ = _run(monkeypatch, False, refuse)
    got, ahead, restarts = _run(monkeypatch, True, refuse)
    assert ahead_ref == 0 and ahead >= len(got) - 2
    assert restarts == len(refuse)          # each refusal came after the engine had gone on: a restart
    assert len(got.events) >= 4
    _same(ref, got)


def test_krein_collisions_located_with_prefetched_spectra(monkeypatch):
    """A combination resonance of a 3-DOF chain (two Krein collisions): located the same when the margin and probe
    spectra of the Krein locator are computed side by side (Locator.prefetch)."""
    from test_bifurcation import _combination_resonance_model
    kw = dict(model=_combination_resonance_model(), energy=3.0, integrator="gauss6", steps_per_period=100)
    ref = _run(monkeypatch, False, **kw)[0]
    got, ahead, _ = _run(monkeypatch, True, **kw)
    assert ahead > 0 and [e["kind"] for e in got.events].count("torus") == 2
    _same(ref, got)


def test_spectrum_workers_from_the_environment(monkeypatch):
    """NNM_SPECTRUM_WORKERS: a whole number (0: the multipliers computed in turn), anything else one clear error;
    with no worker threads the problem does not compute in the background."""
    import nnm_solver.threads as threads
    for text, n in (("0", 0), ("3", 3), (" 1 ", 1), ("", 0), ("-2", 0)):
        monkeypatch.setenv("NNM_SPECTRUM_WORKERS", text)
        assert threads._workers_from_environment() == n
    monkeypatch.setenv("NNM_SPECTRUM_WORKERS", "two")
    with pytest.raises(ValueError, match="NNM_SPECTRUM_WORKERS must be a whole number"):
        threads._workers_from_environment()
    _background_from(monkeypatch, 1)
    monkeypatch.setattr(threads, "WORKERS", 0)
    assert _run(monkeypatch, True, energy=10.0)[1] == 0       # (_run sets background_min_n = 1 itself)
