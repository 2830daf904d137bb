r"""The factor on a model's nonlinear coefficients that best matches a measured backbone.

A phase-resonance test (or a ridge of FRFs at growing force levels) gives the backbone of a mode as pairs
(frequency f_i (Hz), peak amplitude a_i of one DOF (m)).  ``fit_backbone`` finds the factor s > 0 on every
element's nonlinear coefficients (cubic and polynomial coefficients; a piecewise-linear spring's slope
changes k_j - k0, its k0 kept) whose NNM backbone of that mode passes closest to the points.

Distance: each point to the model's backbone curve, measured in (ln a / amplitude_rtol, ln f / frequency_rtol),
i.e. in units of the stated relative measurement uncertainties (orthogonal distance: points on the flat,
nearly linear part of the curve weigh little for the amplitude, as they should).  The factor minimises the
sum of the squared distances; its standard error is the Gauss-Newton one with the variance estimated from
the residuals (so it does not rely on the stated uncertainties), and ``confidence`` the 95 % interval.

Cost: models whose elements are all cubic (``CubicSpring``, or ``PolynomialSpring`` with only x^3) obey the
exact scaling law ``cubic_scaling``: with every k3 times s, frequencies are unchanged and amplitudes divided by
sqrt(s), so the nominal branch, computed once, gives the backbone of every s.  Other models are recomputed
for each trial factor (a bounded scalar search on ln s, about 15 branches).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import NNMInputError, finite_number
from .backbone_curves import _curve, _distances, _minimise, scale_nonlinear
from .settings import IDENTIFICATION

__all__ = ["BackboneFit", "fit_backbone", "scale_nonlinear"]


@dataclass(frozen=True, eq=False)
class BackboneFit:
    """k3_factor : the factor s on every element's nonlinear coefficients.  residual : RMS distance of the
    points to the fitted backbone in units of the stated uncertainties (about 1 when the misfit is the
    measurement noise).  stderr : standard error of s; confidence : its 95 % interval (low, high).
    exact_scaling : True when the cubic scaling law gave every trial backbone from one branch.
    covered : True when the fitted backbone reaches past the largest measured amplitude (else the model's
    branch ended first, e.g. at a fold, and the largest points were matched to its end).
    model : the fitted model; frequency_hz, amplitude : its backbone (Hz, m) at DOF ``dof`` (0-based).
    branches : number of NNM branches computed.  With ``groups``: factors (one per group) and group_fit (the
    GroupFit: standard errors, intervals, correlation); k3_factor, stderr and confidence are then those of the
    only group, NaN for several."""

    k3_factor: float
    residual: float
    stderr: float
    confidence: tuple
    exact_scaling: bool
    covered: bool
    model: object
    dof: int
    mode: int
    frequency_hz: np.ndarray
    amplitude: np.ndarray
    branches: int
    factors: tuple = None
    group_fit: object = None


def _pure_cubic(model):
    return all(hasattr(s, "law") and not hasattr(s, "kinks") and set(s.law()) == {3} for s in model.springs)


def _record_points(record, dof, labels):
    """(amplitude, frequency_hz) of a measured frequency record: its only channel, else the channel of the
    model's DOF ``dof`` (its DOF label, e.g. 'node 14 uz')."""
    if record.kind != "frequency":
        raise NNMInputError(f"fit_backbone: {record.source} is a time record; give peak amplitudes against "
                            f"frequency (a frequency record)")
    if record.n_channels == 1:
        j = 0
    elif labels and isinstance(dof, (int, np.integer)) and 0 <= dof < len(labels) and labels[dof] in record.labels:
        j = record.labels.index(labels[dof])
    else:
        raise NNMInputError(f"fit_backbone: {record.source} has {record.n_channels} channels and none is labelled "
                            f"like DOF {dof} of the model; pass record.channel(...) and record.frequency_hz")
    if record.quantities[j] not in ("displacement", "unknown"):
        raise NNMInputError(f"fit_backbone: channel {record.labels[j]!r} of {record.source} is a "
                            f"{record.quantities[j]}; the backbone's amplitudes are displacements (m)")
    return np.abs(record.data[:, j]), record.frequency_hz


def _data(model, mode, dof, amplitude, frequency_hz):
    from ..files.importers.measured import Measurement
    from ..model import Model

    if isinstance(amplitude, Measurement):
        if frequency_hz is not None:
            raise NNMInputError("fit_backbone: a measured record carries its frequencies; leave frequency_hz out")
        amplitude, frequency_hz = _record_points(amplitude, dof, getattr(model, "dof_labels", None))
    elif frequency_hz is None:
        raise NNMInputError("fit_backbone: give frequency_hz (Hz), one per amplitude")

    if not isinstance(model, Model):
        raise NNMInputError(f"fit_backbone: model must be an nnm_solver.Model, got {type(model).__name__}")
    if not model.springs:
        raise NNMInputError("fit_backbone: the model has no nonlinear element to scale")
    model.check_mode(mode)
    if isinstance(dof, bool) or not isinstance(dof, (int, np.integer)) or not 0 <= dof < model.n:
        raise NNMInputError(f"fit_backbone: dof {dof!r} is not a DOF of this model (0-based: 0..{model.n - 1})")
    try:
        a = np.asarray(amplitude, dtype=float).ravel()
        f = np.asarray(frequency_hz, dtype=float).ravel()
    except (TypeError, ValueError):
        raise NNMInputError("fit_backbone: amplitude and frequency_hz must be arrays of numbers") from None
    if len(a) != len(f):
        raise NNMInputError(f"fit_backbone: {len(a)} amplitudes for {len(f)} frequencies; give one of each per point")
    if len(a) < 2:
        raise NNMInputError(f"fit_backbone: {len(a)} measured point(s); give at least 2 (amplitude, frequency) pairs")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(f)) and np.all(a > 0) and np.all(f > 0)):
        raise NNMInputError("fit_backbone: amplitudes (m) and frequencies (Hz) must be finite and positive")
    return a, f


def fit_backbone(model, mode, dof, amplitude, frequency_hz=None, *, energy_max=None, method=None, amplitude_rtol=0.01,
                 frequency_rtol=0.001, groups=None, also=(), **continuation):
    """The factor on every element's nonlinear coefficients whose NNM backbone best matches measured points.

    model : nnm_solver.Model with its nominal nonlinear elements.  mode : 1-based mode number.  dof : 0-based
    DOF index (as ``CubicSpring(dof=...)``) of the measured coordinate.  amplitude : (N,) peak amplitudes
    max |x_dof(t)| (m; as ``amplitude_backbone(kind="peak")``); frequency_hz : (N,) their frequencies (Hz).
    energy_max : energy (J) of the nominal branch; default from the largest amplitude on the linear mode.
    method and further keywords go to ``continue_nnm`` (default: its defaults, Newmark shooting; ``method="hb"``
    is faster on large models, its peak amplitudes differ from shooting's by the two methods' errors, ~1e-4).
    A measured frequency record (``nnm.read_measured``, e.g. a CSV "frequency (Hz), amplitude (mm)") may stand
    for amplitude, frequency_hz left out: its only channel, or the one labelled like the model's DOF ``dof``.
    amplitude_rtol, frequency_rtol : relative measurement uncertainties, the distance's units.
    groups : optional lists of 0-based element indices, one factor per group (backbone_groups.py); elements in no
    group keep their coefficients.  also : further measured backbones [(mode, dof, amplitude, frequency_hz), ...]
    fitted together with the first (with groups only: what tells groups apart).
    Returns a ``BackboneFit`` (module doc).
    """
    from ..driver import continue_nnm

    a, f = _data(model, mode, dof, amplitude, frequency_hz)
    wa = finite_number(amplitude_rtol, "fit_backbone: amplitude_rtol")
    wf = finite_number(frequency_rtol, "fit_backbone: frequency_rtol")
    if not (wa > 0 and wf > 0):
        raise NNMInputError("fit_backbone: amplitude_rtol and frequency_rtol must be positive (relative uncertainties)")
    la, lf = np.log(a), np.log(f)
    lam, phi = model.eigensolution
    shape = abs(phi[dof, mode - 1])
    if shape < 1e-12 * np.max(np.abs(phi[:, mode - 1])):
        raise NNMInputError(f"fit_backbone: DOF {dof} does not move in mode {mode} (node of the mode shape); "
                            f"measure another DOF")
    if energy_max is None:
        energy_max = 2.0 * lam[mode - 1] * (np.max(a) / shape) ** 2       # 4x the linear mode's energy at max a
    energy_max = finite_number(energy_max, "fit_backbone: energy_max")
    kw = dict(continuation) if method is None else dict(continuation, method=method)
    if groups is not None:
        return _fit_groups(model, (mode, dof, la, lf), groups, also, (wa, wf), energy_max, kw)
    if also:
        raise NNMInputError("fit_backbone: further backbones (also=...) are fitted with groups=[...] only")
    exact = _pure_cubic(model)
    branches = 0
    lo, hi = np.log(IDENTIFICATION.factor_range[0]), np.log(IDENTIFICATION.factor_range[1])
    if exact:
        for _ in range(4):                                  # extend the branch until it covers the points
            curve = _curve(continue_nnm(model, mode, energy_max, **kw), dof)
            branches += 1
            ls = _minimise(lambda g: float(np.sum(_distances(curve, -0.5 * g, la, lf, wa, wf) ** 2)), lo, hi)
            reach = curve[0].max() - 0.5 * ls - np.max(la)  # ln of the fitted curve's reach over the largest point
            if reach > 0.05:
                break
            energy_max *= 4.0 * np.exp(-2.0 * reach)
        shifted = (curve[0] - 0.5 * ls, curve[1])
    else:
        cache = {}

        def backbone(g):
            if g not in cache:
                m = model.with_springs([scale_nonlinear(s, np.exp(g)) for s in model.springs])
                cache[g] = _curve(continue_nnm(m, mode, energy_max, **kw), dof)
            return cache[g]

        ls = _minimise(lambda g: float(np.sum(_distances(backbone(g), 0.0, la, lf, wa, wf) ** 2)), -3.0, 3.0, 13)
        shifted = backbone(ls)
        branches = len(cache)
    r = _distances(shifted, 0.0, la, lf, wa, wf)
    h = 0.01                                               # Gauss-Newton on ln s by a central difference
    if exact:
        rp = _distances(curve, -0.5 * (ls + h), la, lf, wa, wf)
        rm = _distances(curve, -0.5 * (ls - h), la, lf, wa, wf)
    else:
        rp = _distances(backbone(ls + h), 0.0, la, lf, wa, wf)
        rm = _distances(backbone(ls - h), 0.0, la, lf, wa, wf)
        branches = len(cache)
    J = (rp - rm) / (2 * h)
    sigma2 = float(r @ r) / max(len(r) - 1, 1)
    se_log = float(np.sqrt(sigma2 / max(float(J @ J), 1e-300)))
    s = float(np.exp(ls))
    fitted = model.with_springs([scale_nonlinear(sp, s) for sp in model.springs])
    return BackboneFit(k3_factor=s, residual=float(np.sqrt(np.mean(r * r))), stderr=s * se_log,
                       confidence=(s * np.exp(-1.96 * se_log), s * np.exp(1.96 * se_log)), exact_scaling=exact,
                       covered=bool(np.max(shifted[0]) >= np.max(la)),
                       model=fitted, dof=int(dof), mode=int(mode), frequency_hz=np.exp(shifted[1]),
                       amplitude=np.exp(shifted[0]), branches=branches)


def _fit_groups(model, first, groups, also, weights, energy_max, kw):
    """fit_backbone with one factor per group of elements (backbone_groups.py)."""
    from ..driver import continue_nnm
    from .backbone_groups import check_groups, fit_groups

    groups = check_groups(model, groups)
    data = [first]
    for item in also:
        try:
            mode, dof, amplitude, frequency_hz = item
        except (TypeError, ValueError):
            raise NNMInputError("fit_backbone: also=[(mode, dof, amplitude, frequency_hz), ...]") from None
        a, f = _data(model, mode, dof, amplitude, frequency_hz)
        data.append((mode, dof, np.log(a), np.log(f)))
    lam, phi = model.eigensolution
    energies = {}
    for mode, dof, la, _ in data:
        shape = abs(phi[dof, mode - 1])
        e = energy_max if energy_max is not None and mode == first[0] else 2.0 * lam[mode - 1] * (np.exp(la.max()) /
                                                                                                   shape) ** 2
        energies[mode] = max(energies.get(mode, 0.0), e)
    fit = fit_groups(model, groups, data, weights, lambda m, mode: continue_nnm(m, mode, energies[mode], **kw))
    mode, dof, la, lf = first
    curve = _curve(continue_nnm(fit.model, mode, energies[mode], **kw), dof)
    one = len(groups) == 1
    nan = float("nan")
    return BackboneFit(k3_factor=fit.factors[0] if one else nan, residual=fit.residual,
                       stderr=fit.stderr[0] if one else nan, confidence=fit.confidence[0] if one else (nan, nan),
                       exact_scaling=False, covered=bool(np.max(curve[0]) >= np.max(la)), model=fit.model,
                       dof=int(dof), mode=int(mode), frequency_hz=np.exp(curve[1]), amplitude=np.exp(curve[0]),
                       branches=fit.branches + 1, factors=fit.factors, group_fit=fit)
