"""Geometry of the Paris-like aircraft: fuselage, lifting surfaces, tip tanks (SI units, m).

Axes: x aft (from the nose, x = 0, towards the tail), y towards the right wing, z up;
the ground is z = 0.
"""
from __future__ import annotations

import numpy as np


def naca_half_thickness(xc, tau):
    """Half thickness / chord of a symmetric NACA 4-digit section of thickness ratio tau."""
    xc = np.asarray(xc, float)
    return 5 * tau * (0.2969 * np.sqrt(xc) - 0.1260 * xc - 0.3516 * xc ** 2 + 0.2843 * xc ** 3 - 0.1015 * xc ** 4)


def box_section(n_le, n_box, n_web, x_spar, x_rear):
    """Chord fractions and sides of a closed box contour: upper rear -> LE -> lower rear -> web.

    Returns (xc (R,), side (R,) in {+1 upper, -1 lower, 0 web}, web_frac (R,)), plus the
    ring indices of the upper/lower nodes at x_spar and x_rear.
    """
    le = x_spar * (1 - np.cos(np.linspace(0, np.pi / 2, n_le + 1)))
    box = np.linspace(x_spar, x_rear, n_box + 1)
    fwd = np.concatenate([le, box[1:]])            # 0 .. x_rear
    up = fwd[::-1]                                  # x_rear .. 0
    low = fwd[1:]                                   # (0) .. x_rear
    web = np.linspace(-1, 1, n_web + 1)[1:-1]       # lower -> upper, interior
    xc = np.concatenate([up, low, np.full(len(web), x_rear)])
    side = np.concatenate([np.ones(len(up)), -np.ones(len(low)), np.zeros(len(web))])
    side[len(up) - 1] = 0.0                         # leading edge node
    frac = np.concatenate([np.ones(len(up)), -np.ones(len(low)), web])
    frac[len(up) - 1] = 0.0
    n_up = len(up)
    i_spar_up = int(np.argmin(np.abs(up - x_spar)))
    i_spar_low = n_up + int(np.argmin(np.abs(low - x_spar)))
    idx = dict(spar_up=i_spar_up, spar_low=i_spar_low, rear_up=0, rear_low=n_up + len(low) - 1,
               n_up=n_up, n_low=len(low), n_web=len(web))
    return xc, frac, idx


def fuselage_profile(x):
    """Half width b, half height h and centre height zc (m) of the fuselage section at x."""
    X = [0.15, 0.6, 1.5, 2.6, 4.5, 6.0, 7.5, 9.0, 9.9]
    B = [0.08, 0.35, 0.58, 0.675, 0.675, 0.58, 0.42, 0.25, 0.12]
    H = [0.08, 0.38, 0.62, 0.725, 0.725, 0.60, 0.45, 0.30, 0.15]
    Z = [1.00, 1.05, 1.18, 1.275, 1.275, 1.25, 1.22, 1.20, 1.20]
    return np.interp(x, X, B), np.interp(x, X, H), np.interp(x, X, Z)


def superellipse_ring(n, b, h, zc, x, p=2.5):
    """n points (bottom first, symmetric about y = 0) of a superellipse section."""
    th = -np.pi / 2 + 2 * np.pi * np.arange(n) / n
    c, s = np.cos(th), np.sin(th)
    y = b * np.sign(c) * np.abs(c) ** (2 / p)
    z = zc + h * np.sign(s) * np.abs(s) ** (2 / p)
    return np.column_stack([np.full(n, x), y, z])


def tank_radius(x, x0, length, radius):
    """Radius (m) of a tip tank (ogive nose 0.6 m, tail cone 0.8 m) at abscissa x."""
    s = np.asarray(x, float) - x0
    r = np.full_like(s, radius)
    nose, tail = 0.6, 0.8
    a = s < nose
    r[a] = radius * np.sqrt(np.clip(1 - ((nose - s[a]) / nose) ** 2, 0.0, 1.0))
    b = s > length - tail
    r[b] = radius * (1 - 0.8 * (s[b] - (length - tail)) / tail)
    return np.maximum(r, 0.04)
