"""freq_tol's finer time step (driver/refinement.StepRefinement): where the steps aimed at a quarter of the tolerance
do not converge next to the point (e.g. beside an energy fold the finer step moves), steps that just meet the
tolerance are tried before the refinement pauses."""
from types import SimpleNamespace

import numpy as np

import nnm_solver.driver.refinement as refinement
from nnm_solver.continuation.engine import CorrectorFailure


class _Problem:
    def __init__(self, spp=100, order=2):
        self.spp = spp
        self.integrator = SimpleNamespace(order=order)

    def set_steps(self, spp):
        self.spp = int(spp)

    def scale(self, u):
        return np.ones(len(u))


def _refine(monkeypatch, largest_converging, est=4e-4):
    prob = _Problem()
    monkeypatch.setattr(refinement, "correct", lambda p, *a: (_ for _ in ()).throw(CorrectorFailure("no"))
                        if p.spp > largest_converging else None)
    r = refinement.StepRefinement(freq_tol=1e-4)
    cand = SimpleNamespace(point=SimpleNamespace(freq_error=est), disc_error=est, solution=None)
    cp = SimpleNamespace(u=np.ones(3), tangent=np.ones(3))
    engine = r.refine(prob, cp, cand, None, 1e-8)
    return prob, r, engine


def test_the_quarter_tolerance_step_when_it_converges(monkeypatch):
    prob, r, engine = _refine(monkeypatch, 10 ** 6)
    assert engine is not None and prob.spp == 400          # (4e-4 / 2.5e-5)^(1/2) = 4
    assert r.failures == 0


def test_the_step_that_just_meets_the_tolerance_next(monkeypatch):
    prob, r, engine = _refine(monkeypatch, 250)
    assert engine is not None and prob.spp == 200          # (4e-4 / 1e-4)^(1/2) = 2
    assert r.failures == 0


def test_neither_converges_keeps_the_coarse_step_and_pauses(monkeypatch):
    prob, r, engine = _refine(monkeypatch, 150)
    assert engine is None and prob.spp == 100 and r.failures == 1
