"""What the backbone fits share: the backbone of a branch as a fine curve in (ln amplitude, ln frequency), the
normalised distance of measured points to it, a bounded scalar search, and the scaling of an element's
nonlinear coefficients (backbone_fit.py, backbone_groups.py)."""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError
from .settings import IDENTIFICATION


def scale_nonlinear(spring, factor):
    """``spring`` with its nonlinear coefficients times ``factor``: a piecewise-linear spring keeps its slope
    k0 at d = 0 (part of the linear model) and scales the slope changes; the others scale every coefficient."""
    from ..model import PiecewiseLinearSpring

    if not isinstance(spring, PiecewiseLinearSpring):
        return spring.scaled(factor)
    k0 = spring.stiffnesses[0]
    neg = {} if spring.symmetric else dict(
        stiffnesses_negative=[k0 + factor * (k - k0) for k in spring.stiffnesses_negative],
        breakpoints_negative=spring.breakpoints_negative)
    return PiecewiseLinearSpring(dof=spring.dof, other=spring.other, eps=spring.eps, breakpoints=spring.breakpoints,
                                 stiffnesses=[k0 + factor * (k - k0) for k in spring.stiffnesses], **neg)


def _curve(branch, dof):
    """(ln amplitude, ln frequency) of the branch's backbone at ``dof``, resampled finely (PCHIP in the point index)."""
    from scipy.interpolate import PchipInterpolator

    from ..files import amplitude_backbone

    bb = amplitude_backbone(branch, dof)
    keep = (bb.amplitude > 0) & np.isfinite(bb.amplitude) & (bb.frequency_hz > 0)
    la, lf = np.log(bb.amplitude[keep]), np.log(bb.frequency_hz[keep])
    if len(la) < 2:
        raise NNMInputError(f"fit_backbone: the model's backbone has {len(la)} usable point(s) (branch status "
                            f"{branch.status!r}); check the mode and the energy range")
    s = np.arange(len(la), dtype=float)
    fine = np.linspace(0.0, s[-1], IDENTIFICATION.curve_samples)
    return PchipInterpolator(s, la)(fine), PchipInterpolator(s, lf)(fine)


def _distances(curve, shift, la, lf, wa, wf):
    """Normalised distance of each point (la, lf) to the polyline curve shifted by ``shift`` in ln amplitude."""
    cx, cy = (curve[0] + shift) / wa, curve[1] / wf
    px, py = la / wa, lf / wf
    x0, y0, dx, dy = cx[:-1], cy[:-1], np.diff(cx), np.diff(cy)
    length2 = np.maximum(dx * dx + dy * dy, 1e-300)
    out = np.empty(len(px))
    for i, (x, y) in enumerate(zip(px, py)):
        u = np.clip(((x - x0) * dx + (y - y0) * dy) / length2, 0.0, 1.0)
        out[i] = np.sqrt(np.min((x0 + u * dx - x) ** 2 + (y0 + u * dy - y) ** 2))
    return out


def _minimise(cost, lo, hi, nodes=61):
    """ln s in [lo, hi] minimising cost: a grid of ``nodes``, then a bounded search around its best node."""
    from scipy.optimize import minimize_scalar

    grid = np.linspace(lo, hi, nodes)
    values = [cost(g) for g in grid]
    j = int(np.argmin(values))
    res = minimize_scalar(cost, bounds=(grid[max(j - 1, 0)], grid[min(j + 1, len(grid) - 1)]), method="bounded",
                          options={"xatol": 1e-7})
    return float(res.x)


