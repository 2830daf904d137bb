"""Locator.root: the Illinois variant of regula falsi, safeguarded by bisection (RETAIN_LIMIT) -- few evaluations
on a smooth g, a jump located at bisection's cost (not at max_iter unconverged)."""
import dataclasses

import numpy as np
import pytest

import nnm_solver.stability.roots as roots
from nnm_solver.stability.locator import Locator


def _root(g, lo, hi, width):
    """Locator.root on g with a bracket-width stop, counting evaluations; returns (root, bracket, evaluations)."""
    seen = []
    bracket = []

    def counted(x):
        seen.append(x)
        return g(x)

    def converged(a, b, fa, fb):
        bracket[:] = [min(a, b), max(a, b)]
        return abs(b - a) <= width

    loc = Locator.__new__(Locator)                  # root uses only g and converged
    x = loc.root(counted, lo, hi, converged=converged)
    return x, bracket, len(seen)


@pytest.mark.parametrize("low, high", [(-1e-3, 1e-10), (-1.0, 1e-4)])
def test_a_jump_is_bisected(monkeypatch, low, high):
    """g jumps from low to high at 0.3137 (a selected multiplier changing identity): Illinois alone halves the
    kept end ~log2(|low / high|) times per move and does not reach a 1e-9 bracket in max_iter = 60; with the
    safeguard it does in about log2(1e9) = 30 evaluations, and the bracket holds the jump."""
    jump = 0.3137
    g = lambda s: low if s < jump else high             # noqa: E731
    x, (a, b), n = _root(g, 0.0, 1.0, 1e-9)
    assert a <= jump <= b and b - a <= 1e-9
    assert n <= 40
    monkeypatch.setattr(roots, "STABILITY", dataclasses.replace(roots.STABILITY, retain_limit=10 ** 9))
    x, (a, b), n = _root(g, 0.0, 1.0, 1e-9)
    assert b - a > 1e-9 and n > 60


@pytest.mark.parametrize("g, root", [(lambda s: s ** 3 - 0.2, 0.2 ** (1 / 3)),
                                     (lambda s: np.exp(4 * s) - 3.0, np.log(3.0) / 4)])
def test_smooth_functions_keep_superlinear_convergence(monkeypatch, g, root):
    """On a smooth convex g (its ends' values 1:25 and 1:10 apart) the safeguard keeps Illinois' superlinear
    order: a 1e-12 bracket in <= 20 evaluations, within 5 of Illinois alone (bisection needs 40)."""
    x, (a, b), n = _root(g, 0.0, 1.0, 1e-12)
    assert a <= root <= b and b - a <= 1e-12
    monkeypatch.setattr(roots, "STABILITY", dataclasses.replace(roots.STABILITY, retain_limit=10 ** 9))
    n_illinois = _root(g, 0.0, 1.0, 1e-12)[2]
    assert n <= 20 and n <= n_illinois + 5
