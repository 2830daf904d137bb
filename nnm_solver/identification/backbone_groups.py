r"""Several factors at once: one per group of elements, fitted to measured backbones (``fit_backbone(groups=...)``).

Group j of elements (0-based indices into ``model.springs``) gets the factor s_j on its nonlinear coefficients
(``scale_nonlinear``); elements in no group keep theirs.  The factors minimise the same normalised distances as
the single factor (backbone_fit.py), summed over every measured backbone given: one backbone of one DOF rarely
tells two groups apart (their effects on it may be nearly proportional), a second DOF or a second mode often
does.  Least squares on ln s (scipy ``least_squares``, trust region, bounds 1e-3..1e3), each residual a new
branch per backbone; the covariance is the Gauss-Newton one with the variance estimated from the residuals, so
that an unidentifiable combination shows as a large standard error (and ``correlation`` near +-1).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import NNMInputError
from .backbone_curves import _curve, _distances, scale_nonlinear
from .settings import IDENTIFICATION

__all__ = ["GroupFit", "check_groups", "fit_groups"]


@dataclass(frozen=True, eq=False)
class GroupFit:
    """factors (one per group), their standard errors and 95 % intervals, the correlation matrix of ln s,
    the RMS normalised distance, the fitted model and the number of branches computed."""

    factors: tuple
    stderr: tuple
    confidence: tuple
    correlation: np.ndarray
    residual: float
    model: object
    branches: int


def check_groups(model, groups):
    """The groups as tuples of element indices; one-line NNMInputError for bad ones."""
    n = len(model.springs)
    try:
        out = [tuple(int(i) for i in g) for g in groups]
    except (TypeError, ValueError):
        raise NNMInputError("fit_backbone: groups must be lists of 0-based element indices, e.g. [[0, 1], [2, 3]]") \
            from None
    seen = set()
    for g in out:
        if not g:
            raise NNMInputError("fit_backbone: a group is empty; give each group at least one element")
        bad = [i for i in g if not 0 <= i < n]
        if bad:
            raise NNMInputError(f"fit_backbone: element {bad[0]} is not an element of the model (0..{n - 1})")
        twice = seen.intersection(g)
        if twice:
            raise NNMInputError(f"fit_backbone: element {min(twice)} is in two groups")
        seen.update(g)
    if not out:
        raise NNMInputError("fit_backbone: groups is empty")
    return out


def scaled_model(model, groups, factors):
    springs = list(model.springs)
    for g, s in zip(groups, factors):
        for i in g:
            springs[i] = scale_nonlinear(springs[i], float(s))
    return model.with_springs(springs)


def fit_groups(model, groups, data, weights, solve):
    """Factors of ``groups`` (check_groups) fitted to ``data`` = [(mode, dof, ln a, ln f), ...] with
    ``weights`` = (amplitude_rtol, frequency_rtol); ``solve(model, mode)`` computes a branch.  Returns a GroupFit."""
    from scipy.optimize import least_squares

    wa, wf = weights
    count = [0]
    cache = {}

    def residuals(g):
        key = tuple(np.round(g, 12))
        if key not in cache:
            m = scaled_model(model, groups, np.exp(g))
            parts = []
            for mode, dof, la, lf in data:
                count[0] += 1
                parts.append(_distances(_curve(solve(m, mode), dof), 0.0, la, lf, wa, wf))
            cache[key] = np.concatenate(parts)
        return cache[key]

    lo, hi = np.log(IDENTIFICATION.group_range[0]), np.log(IDENTIFICATION.group_range[1])
    res = least_squares(residuals, np.zeros(len(groups)), bounds=(lo, hi), diff_step=1e-3, x_scale=1.0,
                        xtol=1e-8, ftol=1e-10, max_nfev=60)
    r = residuals(res.x)
    J = res.jac
    dof_free = max(len(r) - len(groups), 1)
    sigma2 = float(r @ r) / dof_free
    try:
        cov = sigma2 * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((len(groups), len(groups)), np.inf)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    s = np.exp(res.x)
    return GroupFit(factors=tuple(float(v) for v in s), stderr=tuple(float(v) for v in s * se),
                    confidence=tuple((float(v * np.exp(-1.96 * e)), float(v * np.exp(1.96 * e))) for v, e in zip(s, se)),
                    correlation=corr, residual=float(np.sqrt(np.mean(r * r))),
                    model=scaled_model(model, groups, s), branches=count[0])
