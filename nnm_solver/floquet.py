"""Floquet multipliers and stability of periodic orbits of conservative systems.

For a conservative system the multipliers come in pairs (mu, 1/mu) and two of them equal +1 (the
time shift along the orbit and the change of energy along the family).  An orbit is called stable
when no multiplier lies outside the unit circle by more than ``STABILITY_TOL``:
``max |mu| <= 1 + STABILITY_TOL``.  The tolerance absorbs the round-off and the Newmark
discretisation, which keep the multipliers of a stable orbit within ~1e-6 of the unit circle.
"""
from __future__ import annotations

import numpy as np

#: stability tolerance on the modulus of the Floquet multipliers
STABILITY_TOL = 1e-3


def sort_multipliers(mu):
    """Multipliers sorted by decreasing modulus (the most unstable first)."""
    mu = np.asarray(mu, dtype=complex)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def is_stable(mu, tol=STABILITY_TOL):
    return bool(np.max(np.abs(mu)) <= 1.0 + tol)


def instability_kind(mu, tol=STABILITY_TOL):
    """How an orbit is unstable, from its largest multiplier: '+1', '-1', 'complex' or '' if stable."""
    mu = sort_multipliers(mu)
    m = mu[0]
    if abs(m) <= 1.0 + tol:
        return ""
    if abs(m.imag) <= 1e-6 * abs(m):
        return "+1" if m.real > 0 else "-1"
    return "complex"


def detect_events(energy, frequency_hz, floquet, stable):
    """Folds and bifurcations along a branch.

    fold: the energy turns back between points i-1, i, i+1 (recorded at i).
    bifurcation: the stability flag changes between i-1 and i; the kind says where the critical
    multiplier leaves the unit circle ('+1': branch point or fold of the period, '-1': period
    doubling, 'complex': Neimark-Sacker / Krein collision).
    Returns a list of dicts with keys kind, index, energy, frequency_hz, detail.
    """
    events = []
    E = np.asarray(energy)
    for i in range(1, len(E) - 1):
        a, b = E[i] - E[i - 1], E[i + 1] - E[i]
        if a * b < 0:
            events.append(dict(kind="fold", index=i, energy=float(E[i]), frequency_hz=float(frequency_hz[i]),
                               detail="energy maximum" if a > 0 else "energy minimum"))
    for i in range(1, len(E)):
        if bool(stable[i]) != bool(stable[i - 1]):
            j = i if not stable[i] else i - 1
            kind = instability_kind(floquet[j]) or "+1"
            events.append(dict(kind="bifurcation", index=i, energy=float(E[i]),
                               frequency_hz=float(frequency_hz[i]),
                               detail=f"{'loss' if not stable[i] else 'gain'} of stability, multiplier through {kind}"))
    events.sort(key=lambda e: (e["index"], e["kind"]))
    return events
