"""A branch's stored states rescaled: its records to another k3 by the cubic scaling law (Branch.scaled: amplitudes x
1/sqrt(factor), energies x 1/factor, model/scaling.py), and an interpolated state to an energy (Branch.interpolate)."""
from __future__ import annotations

import numpy as np

__all__ = ["scaled_event", "scaled_message", "energy_factor"]


def scaled_event(event, sc):
    """An event record (a dict) of a branch scaled by ``sc`` (scaling.CubicScaling): energy (J) x sc.energy, a
    located event's orbit x0, v0 (m, m/s) x sc.amplitude; frequency, period, multipliers and text unchanged."""
    out = dict(event, energy=float(event["energy"]) * sc.energy)
    for key in ("x0", "v0"):
        if key in event:
            out[key] = (np.asarray(event[key], dtype=float) * sc.amplitude).tolist()
    return out


def scaled_message(message, sc):
    """A scaled branch's message: the computed branch's (free text, its numbers unchanged), with a note that says
    so; '' stays ''."""
    if not message:
        return message
    return (f"{message} [then scaled: every k3 x {sc.ratio:g}, so the energies quoted before this note are x "
            f"{sc.energy:g} on this branch]")


def energy_factor(model, x, v, energy):
    """The factor c > 0 that gives the state (c x, c v) the energy ``energy`` (J): secant iteration on E(c x, c v) =
    energy from c = 1, for any element law; 1 if it does not converge to 1e-9."""
    if energy <= 0 or not model.energy(x, v) > 0:
        return 1.0
    f = lambda c: float(model.energy(c * x, c * v)) - energy
    c0, c1 = 1.0, 1.0 + 1e-3
    f0, f1 = f(c0), f(c1)
    for _ in range(60):
        if f1 == f0:
            break
        c2 = c1 - f1 * (c1 - c0) / (f1 - f0)
        c2 = c2 if c2 > 0 else 0.5 * c1
        c0, f0, c1, f1 = c1, f1, c2, f(c2)
        if abs(f1) <= 1e-12 * energy:
            break
    if not abs(f1) <= 1e-9 * energy:
        return 1.0
    return c1
