"""Airframe of the aircraft builder: fuselage, wing (with ailerons and wing-fuselage joints),
fin (with rudder) and T-tail (with elevator)."""
from __future__ import annotations

import numpy as np

from . import geometry as geo
from .structure import StructureBuilder, grid_quads

EY = np.array([0.0, 1.0, 0.0])
EZ = np.array([0.0, 0.0, 1.0])


def _wing_stations(p, n_half):
    y = p.semi_span * np.linspace(-1, 1, 2 * n_half + 1)
    return y


def add_fuselage(b: StructureBuilder):
    """Fuselage skin, frames and longerons; returns the fuselage node ids."""
    p = b.p
    nc = 2 * b.n(24, 6)
    xs = np.linspace(0.15, 9.9, b.n(90, 12) + 1)
    rings = []
    for x in xs:
        bb, hh, zc = geo.fuselage_profile(x)
        rings.append(geo.superellipse_ring(nc, bb, hh, zc, x))
    F = b.pool(np.concatenate(rings), 0).reshape(len(xs), nc)
    wfus = np.interp(0.5 * (xs[:-1] + xs[1:]), [0.0, 1.0, 6.0, 8.0, 9.9], [0.8, 1.6, 1.2, 0.4, 0.2])
    xm = 0.5 * (xs[:-1] + xs[1:])
    tf = np.repeat(np.interp(xm, [6.0, 7.0], [p.fus_skin_t, p.fus_rear_skin_t]), nc)
    b.shells("fuselage", grid_quads(F, True), tf, p.fus_skin_tb, "fuselage", "fuselage",
             weight=np.repeat(wfus, nc))
    b.grids.append(("fuselage", F, True))
    fr_every = max(1, int(round(4 * p.mesh)))
    for j in range(0, len(xs), fr_every):
        b.beams("fuselage", F[j], np.roll(F[j], -1), [1.0, 0, 0], p.fus_frame_area, 4e-7, "fuselage", "fuselage")
    for k in np.arange(0, nc, nc // 8):
        b.beams("fuselage", F[:-1, k], F[1:, k], [0, 0, 1.0] if k % (nc // 2) else [0, 1.0, 0],
                p.fus_longeron_area, 1e-7, "fuselage", "fuselage")
    fus_nodes = F.ravel()
    b.sections["fuselage"] = fus_nodes
    return fus_nodes


def add_wing(b: StructureBuilder, fus_nodes, tree):
    """One wing surface tip to tip, aileron hinges and coupling, wing-fuselage joints.

    tree : cKDTree of the fuselage node coordinates.  Returns (skin ring ids (S, R), wing node ids).
    """
    p, fe = b.p, b.fe
    nh = b.n(40, 4)
    y = _wing_stations(p, nh)
    s = np.abs(y) / p.semi_span
    chord = p.root_chord + (p.tip_chord - p.root_chord) * s
    P_le = np.column_stack([p.x_le_root + np.tan(np.radians(p.le_sweep_deg)) * np.abs(y), y,
                            p.z_wing_root + np.tan(np.radians(p.dihedral_deg)) * np.abs(y)])
    tau = p.tau_root + (p.tau_tip - p.tau_root) * s
    tdir = np.tile(EZ, (len(y), 1))
    ym = 0.5 * (y[:-1] + y[1:])
    ail_R = (ym > 2.55) & (ym < 4.35)
    ail_L = (ym < -2.55) & (ym > -4.35)
    flap = np.abs(ym) < 2.45
    rib_every = max(1, int(round(0.455 / (y[1] - y[0]))))
    ribs = sorted(set(range(0, len(y), rib_every)) | {0, len(y) - 1, nh})
    W = b.lifting_surface("wing", "wing", P_le, chord, tau, tdir, b.n(6, 2), b.n(10, 3), 2, 0.2, 0.75, b.n(3, 1),
                          p.wing_skin_t, p.wing_skin_tb, p.wing_web_t, p.wing_cap_area, ribs,
                          [("flap", 0, "wing", "wing", flap),
                           ("aileron R", 1, "aileron R", "aileron", ail_R),
                           ("aileron L", 2, "aileron L", "aileron", ail_L)], "wing")
    ring = W["ring"]
    b.sections["wing tip R"] = ring[-1]
    b.sections["wing tip L"] = ring[0]
    b.sections["wing y"] = y
    wing_nodes = np.unique(np.concatenate([ring.ravel(), W["web"].ravel()]))
    # ailerons: hinges at three stations, anti-symmetric circuit coupling
    axes = {}
    for part, grp in (("aileron R", 1), ("aileron L", 2)):
        ids, st = W["te"][part]
        pick = st[[0, len(st) // 2, -1]]
        cs = ids[pick, 0]
        wn = ring[pick, W["idx"]["n_up"] + W["idx"]["n_low"] + W["idx"]["n_web"] // 2]
        if part == "aileron L":
            cs, wn = cs[::-1], wn[::-1]
        axes[part] = (b.hinge("hinge aileron", "aileron", cs, wn, p.k_aileron), cs[1], wn[1])
    (aR, cR, wR), (aL, cL, wL) = axes["aileron R"], axes["aileron L"]
    dofs = np.concatenate([6 * cR + np.arange(3, 6), 6 * wR + np.arange(3, 6),
                           6 * cL + np.arange(3, 6), 6 * wL + np.arange(3, 6)])
    fe.add_dof_spring("hinge aileron", dofs, np.concatenate([aR, -aR, -aL, aL]), p.k_aileron_sym)

    # wing-fuselage joints: main-spar fittings (stiff, k = wf_k) and rear-spar fittings
    # (pitch restraint, k = wf_rear_k) on the centre section: rigid arm from the wing node to a
    # node at the fuselage node + translational bushing
    wing_box = np.unique(np.concatenate([ring[:, :W["idx"]["n_up"]].ravel(), W["web"].ravel()]))
    n_up = W["idx"]["n_up"]
    xc_up = W["xc"][:n_up]
    k_main = int(np.argmin(np.abs(xc_up - 0.35)))
    k_rear = int(np.argmin(np.abs(xc_up - 0.75)))
    centre = [j for j in range(len(y)) if abs(y[j]) < 0.62]
    for j in centre:
        for k, kk in ((k_main, p.wf_k), (k_rear, p.wf_rear_k)):
            w = ring[j, k]
            d, i = tree.query(fe.nodes[w])
            f = fus_nodes[i]
            jn = b.pool(fe.nodes[f], 1000 + w)[0]
            fn = b.pool(fe.nodes[f], 5000 + w)[0]
            b.spider("wing", jn, wing_box, 0.35, "wing", max_n=8)
            b.spider("fuselage", fn, fus_nodes, 0.3, "fuselage", max_n=8)
            fe.add_bushing("wing-fuselage joint", jn, fn, [kk] * 3 + [0.0] * 3)
    b.categories["wing-fuselage joint"] = "wing"
    return ring, wing_nodes


def add_tail(b: StructureBuilder, fus_nodes, tree):
    """Fin with rudder, linked to the fuselage (tree: cKDTree of its nodes), and the horizontal
    tail with elevator on top of the fin (T-tail)."""
    p, fe = b.p, b.fe
    # ------------------------------------------------------------ fin (vertical tail)
    fin_root_z, fin_top_z = 1.35, 2.55
    z = np.linspace(fin_root_z, fin_top_z, b.n(14, 3) + 1)
    sf = (z - fin_root_z) / (fin_top_z - fin_root_z)
    fch = 1.8 + (1.1 - 1.8) * sf
    Pf = np.column_stack([8.0 + 1.0 * sf, np.zeros_like(z), z])
    Fn = b.lifting_surface("fin", "fin", Pf, fch, np.full_like(z, 1.1 * p.tail_tau), np.tile(EY, (len(z), 1)),
                           b.n(4, 2), b.n(6, 2), 2, 0.2, 0.7, b.n(3, 1), p.fin_skin_t, p.tail_skin_tb,
                           p.fin_skin_t * 1.5, p.tail_cap_area, range(0, len(z), max(1, int(round(2 * p.mesh)))),
                           [("rudder", 3, "rudder", "rudder", np.ones(len(z) - 1, bool))], "fin")
    b.sections["fin tip"] = Fn["ring"][-1]
    # fin root to fuselage: stiff links
    for w in Fn["ring"][0]:
        d, i = tree.query(fe.nodes[w])
        fe.add_rigid_links("tail joints", w, [fus_nodes[i]])
    for w in Fn["ring"][1]:
        d, i = tree.query(fe.nodes[w])
        if d < 0.25:
            fe.add_rigid_links("tail joints", w, [fus_nodes[i]])
    b.categories["tail joints"] = "fin"
    ids, st = Fn["te"]["rudder"]
    pick = st[[0, len(st) // 2, -1]]
    mid = Fn["idx"]["n_up"] + Fn["idx"]["n_low"] + Fn["idx"]["n_web"] // 2
    b.hinge("hinge rudder", "rudder", ids[pick, 0], Fn["ring"][pick, mid], p.k_rudder)

    # ------------------------------------------------------------ horizontal tail on top of the fin
    yh = np.linspace(-1.9, 1.9, 2 * b.n(15, 2) + 1)
    sh = np.abs(yh) / 1.9
    hch = 1.0 + (0.6 - 1.0) * sh
    Ph = np.column_stack([9.1 + 0.28 * sh, yh, np.full_like(yh, fin_top_z + 0.02)])  # straight hinge
    H = b.lifting_surface("htail", "htail", Ph, hch, np.full_like(yh, p.tail_tau), np.tile(EZ, (len(yh), 1)),
                          b.n(4, 2), b.n(6, 2), 2, 0.2, 0.7, b.n(3, 1), p.tail_skin_t, p.tail_skin_tb,
                          p.tail_skin_t * 1.5, p.tail_cap_area, range(0, len(yh), max(1, int(round(2 * p.mesh)))),
                          [("elevator", 4, "elevator", "elevator", np.ones(len(yh) - 1, bool))], "htail")
    b.sections["htail tip R"] = H["ring"][-1]
    b.sections["htail tip L"] = H["ring"][0]
    jt = np.array([Pf[-1, 0] + 0.35 * fch[-1], 0.0, fin_top_z])
    centre_h = np.flatnonzero(np.abs(yh) <= 0.3)
    if p.htail_pitch_k > 0:
        # T-tail fittings (builder 1.2): a rigid body on the fin tip rib and one on the horizontal tail's
        # centre section, joined on the pitch axis (x = htail_pivot_x) by a bushing stiff in translation,
        # roll and yaw and of pitch stiffness htail_pitch_k: the symmetric tail torsion (the horizontal
        # tail twisting and pitching on the fin) is set by htail_pitch_k; the anti-symmetric modes and,
        # with the axis near the tail's mass centre, the symmetric tail bending are not changed
        if p.htail_pivot_x > 0:
            jt[0] = p.htail_pivot_x
        jf, jh = b.pool(jt, 400)[0], b.pool(jt, 401)[0]
        fe.add_rigid_links("tail joints", jf, Fn["ring"][-1])
        fe.add_rigid_links("htail fittings", jh, np.unique(H["ring"][centre_h].ravel()))
        fe.add_bushing("htail fittings", jf, jh, [1e10, 1e10, 1e10, 1e10, p.htail_pitch_k, 1e10])
        b.categories["htail fittings"] = "htail"
    else:
        # T-tail junction (builder <= 1.1): one rigid body joining the fin tip rib and the HT centre section
        jt = b.pool(jt, 400)[0]
        legs = np.unique(np.concatenate([Fn["ring"][-1], H["ring"][centre_h].ravel()]))
        fe.add_rigid_links("tail joints", jt, legs)
    ids, st = H["te"]["elevator"]
    pick = st[[0, len(st) // 2, -1]]
    mid = H["idx"]["n_up"] + H["idx"]["n_low"] + H["idx"]["n_web"] // 2
    b.hinge("hinge elevator", "elevator", ids[pick, 0], H["ring"][pick, mid], p.k_elevator)
