"""Attachments and springs of the aircraft builder: tip tanks on shear-flexible attachment stubs
(the retained interface nodes) and landing gears (3D springs to ground with point masses)."""
from __future__ import annotations

import numpy as np

from . import geometry as geo
from .structure import StructureBuilder, grid_quads


def add_tip_tanks(b: StructureBuilder, ring):
    """Tip tanks and their front/rear attachments to the wing-tip ribs of ``ring`` (wing skin ids).

    Returns the retained nodes: R front (w, t), R rear (w, t), L front (w, t), L rear (w, t).
    """
    p, fe = b.p, b.fe
    tip_chord = p.tip_chord
    x_tip_le = p.x_le_root + np.tan(np.radians(p.le_sweep_deg)) * p.semi_span
    z_tip = p.z_wing_root + np.tan(np.radians(p.dihedral_deg)) * p.semi_span
    x_front = x_tip_le + 0.1 * tip_chord
    x_att = [x_front, x_front + p.att_spacing]
    x0 = 0.5 * (x_att[0] + x_att[1]) - 0.45 * p.tank_length
    xt = np.linspace(x0, x0 + p.tank_length, b.n(40, 8) + 1)
    nct = 2 * b.n(12, 4)
    retained = []
    L_att = p.tank_gap
    A_att, I_att, J_att = 1.2e-3, 1.0e-6, 1.0e-8
    G = p.E / (2 * (1 + p.nu))
    # shear-flexible stub: vertical (and fore-aft) stiffness p.att_kz, stiff in rotation
    def _kappa(k):
        return 1.0 / (A_att * G * (1.0 / k - L_att ** 3 / (12 * p.E * I_att)) / L_att)
    kappa = (_kappa(p.att_kz), _kappa(p.att_kx))   # e2 = z (vertical), e3 = x (fore-aft)
    for side, sgn, grp in (("R", 1.0, 5), ("L", -1.0, 6)):
        yc = sgn * (p.semi_span + p.tank_gap + p.tank_radius)
        r = geo.tank_radius(xt, x0, p.tank_length, p.tank_radius)
        th = -np.pi / 2 + 2 * np.pi * np.arange(nct) / nct
        Xt = np.stack([np.column_stack([np.full(nct, x), yc + rr * np.cos(th), z_tip + rr * np.sin(th)])
                       for x, rr in zip(xt, r)])
        T = b.pool(Xt.reshape(-1, 3), grp).reshape(len(xt), nct)
        part = f"tank {side}"
        xm = np.repeat(0.5 * (xt[:-1] + xt[1:]), nct)
        wt = np.exp(-0.5 * ((xm - 0.5 * (x_att[0] + x_att[1])) / p.tank_mass_sigma) ** 2)
        b.shells(part, grid_quads(T, True), p.tank_skin_t, 0.01, part, "tank", weight=wt)
        b.grids.append(("tank", T, True))
        for j in range(0, len(xt), max(1, len(xt) // 8)):
            b.beams(part, T[j], np.roll(T[j], -1), [1.0, 0, 0], 2e-4, 1e-7, part, "tank")
        tip_ring = ring[-1] if sgn > 0 else ring[0]
        for xa, which in zip(x_att, ("front", "rear")):
            wpos = np.array([xa, sgn * p.semi_span, z_tip])
            tpos = wpos + np.array([0.0, sgn * L_att, 0.0])
            wn = b.pool(wpos, 100 + grp)[0]
            tn = b.pool(tpos, 200 + grp)[0]
            b.spider("wing", wn, tip_ring, 0.3, "wing", max_n=8)
            b.spider(part, tn, T.ravel(), 0.3, "tank", max_n=10)
            fe.add_beams("attachments", [wn], [tn], [0, 0, 1.0], p.E, G, A_att, I_att, I_att,
                         J_att, rho=0.0, shear_factor=kappa)
            b.categories["attachments"] = "tank"
            retained += [wn, tn]
        b.sections[f"tank {side}"] = T.ravel()
    return retained


def add_landing_gears(b: StructureBuilder, fus_nodes, wing_nodes):
    """Nose gear under the fuselage and two main gears under the wing: 3D springs to ground and
    point masses.  Returns the gear nodes (nose, right main, left main)."""
    p, fe = b.p, b.fe
    gear_nodes = []
    xg = p.nose_gear_x
    zg = geo.fuselage_profile(xg)[2] - geo.fuselage_profile(xg)[1]
    gn = b.pool(np.array([xg, 0.0, zg]), 300)[0]
    b.spider("fuselage", gn, fus_nodes, 0.35, "fuselage", max_n=10)
    fe.add_bushing("gear", gn, None, list(p.nose_gear_k) + [0.0] * 3)
    fe.add_point_mass("gear mass", gn, p.mass_gear_nose)
    gear_nodes.append(gn)
    for sgn in (1.0, -1.0):
        yg = sgn * p.main_gear_y
        zc = p.z_wing_root + np.tan(np.radians(p.dihedral_deg)) * p.main_gear_y
        gn = b.pool(np.array([p.main_gear_x, yg, zc]), 301 if sgn > 0 else 302)[0]
        b.spider("wing", gn, wing_nodes, 0.35, "wing", max_n=10)
        fe.add_bushing("gear", gn, None, list(p.main_gear_k) + [0.0] * 3)
        fe.add_point_mass("gear mass", gn, p.mass_gear_main)
        gear_nodes.append(gn)
    b.categories["gear"] = "gear"
    b.categories["gear mass"] = "gear"
    return gear_nodes
