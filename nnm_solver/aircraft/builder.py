"""Parametric finite-element model of a Paris-like jet trainer (SI units).

Axes: x aft from the nose (x = 0 at the nose, x = 10.4 m at the tail), y towards the
right wing, z up (ground at z = 0).  Skins are MITC4 shells, spar caps, ribs, frames,
longerons and attachments are beams, gears are 3D springs to ground, control surfaces
hang on soft hinge bushings, and rigid connections are penalty stiff beams.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..errors import NNMInputError
from ..fem import FEModel
from . import geometry as geo

BUILDER_VERSION = "1.0"

#: The retained (interface) nodes, in reduced-model order: 4 per wing.
ATTACHMENT_NAMES = ["wing R front (wing side)", "wing R front (tank side)",
                    "wing R rear (wing side)", "wing R rear (tank side)",
                    "wing L front (wing side)", "wing L front (tank side)",
                    "wing L rear (wing side)", "wing L rear (tank side)"]


@dataclass
class ParisParams:
    """Builder parameters (SI units: m, kg, Pa, N/m, N m/rad).  ``mesh`` scales all mesh counts."""

    mesh: float = 1.0
    E: float = 71e9
    nu: float = 0.33
    rho: float = 2800.0
    # wing planform
    semi_span: float = 4.55
    root_chord: float = 2.6
    tip_chord: float = 1.2
    x_le_root: float = 3.8
    le_sweep_deg: float = 3.0
    dihedral_deg: float = 5.0
    z_wing_root: float = 0.45
    tau_root: float = 0.15
    tau_tip: float = 0.12
    # wing structure
    wing_skin_t: float = 3.30072e-3
    wing_skin_tb: float = 0.012
    wing_web_t: float = 2.5e-3
    wing_skin_ex: float = 0.382
    wing_cap_area: float = 2e-4
    wing_rib_area: float = 1.5e-4
    # fuselage structure
    fus_skin_t: float = 1.2e-3
    fus_rear_skin_t: float = 3.0e-3
    fus_skin_tb: float = 0.012
    fus_frame_area: float = 4e-4
    fus_longeron_area: float = 4e-4
    # tail structure
    tail_skin_t: float = 2.5e-3
    fin_skin_t: float = 5.5e-3
    tail_skin_tb: float = 0.010
    tail_cap_area: float = 2e-4
    tail_tau: float = 0.1365
    # tip tanks and attachments
    tank_length: float = 2.9
    tank_radius: float = 0.225
    tank_gap: float = 0.05
    att_spacing: float = 0.8
    att_kz: float = 1.0e7
    att_kx: float = 8.0e5
    tank_skin_t: float = 1.5e-3
    # joints and suspensions
    wf_k: float = 5e7
    wf_rear_k: float = 1.9e6
    main_gear_k: tuple = (252.0, 66834.0, 83337.0)
    nose_gear_k: tuple = (169.0, 51964.0, 395228.0)
    k_aileron: float = 6.169
    k_aileron_sym: float = 8.5e3
    k_elevator: float = 18.82
    k_rudder: float = 47.72
    # masses (kg, structure included); the fuselage takes the rest of total_mass
    total_mass: float = 1945.0
    mass_wing: float = 380.0
    mass_htail: float = 60.0
    mass_fin: float = 65.0
    mass_aileron: float = 9.0
    mass_elevator: float = 14.0
    mass_rudder: float = 9.0
    mass_tank: float = 40.0
    mass_gear_nose: float = 35.0
    mass_gear_main: float = 55.0

    tank_mass_sigma: float = 0.5

    @property
    def mass_fuselage(self):
        """Fuselage mass (kg): the rest of total_mass."""
        return self.total_mass - (self.mass_wing + self.mass_htail + self.mass_fin + 2 * self.mass_aileron
                                  + self.mass_elevator + self.mass_rudder + 2 * self.mass_tank
                                  + self.mass_gear_nose + 2 * self.mass_gear_main)


@dataclass
class Aircraft:
    """The assembled aircraft: FE model, special nodes and bookkeeping for labels and display."""

    fe: FEModel
    params: ParisParams
    K: object = None
    M: object = None
    retained_nodes: list = field(default_factory=list)
    mirror: np.ndarray = None          # node -> mirror node
    grids: list = field(default_factory=list)   # (display part, ids (S, R), periodic ring?)
    sections: dict = field(default_factory=dict)  # name -> node ids for labelling
    categories: dict = field(default_factory=dict)  # FE part -> label category
    build_seconds: float = 0.0

    @property
    def retained_dofs(self):
        return (6 * np.asarray(self.retained_nodes)[:, None] + np.arange(6)).ravel()


class _Pool:
    """Node pool merging coincident nodes of the same group."""

    def __init__(self, fe):
        self.fe = fe
        self.keys = {}
        self.group = []

    def __call__(self, xyz, group):
        xyz = np.atleast_2d(xyz)
        out = np.empty(len(xyz), np.int64)
        new = []
        for i, p in enumerate(xyz):
            key = (group, *np.round(p * 1e5).astype(np.int64))
            j = self.keys.get(key)
            if j is None:
                j = self.fe.n_nodes + len(new)
                self.keys[key] = j
                new.append(p)
                self.group.append(group)
            out[i] = j
        if new:
            self.fe.add_nodes(np.array(new))
        return out


def _quads(ids, periodic):
    a = ids if not periodic else np.concatenate([ids, ids[:, :1]], axis=1)
    return np.stack([a[:-1, :-1], a[1:, :-1], a[1:, 1:], a[:-1, 1:]], -1).reshape(-1, 4)


class _Builder:
    def __init__(self, p: ParisParams):
        self.p = p
        self.fe = FEModel()
        self.pool = _Pool(self.fe)
        self.mass_groups = {}   # name -> [structural mass, list of (quads, area, weights)]
        self.grids = []
        self.sections = {}
        self.categories = {}

    def n(self, base, minimum=2):
        return max(minimum, int(round(base * self.p.mesh)))

    # ---------------------------------------------------------------- helpers
    def shells(self, part, quads, t, tb, mass_group, cat, weight=None, ex_scale=1.0):
        p = self.p
        area = self.fe.add_shells(part, quads, p.E, p.nu, t, tb, rho=p.rho, ex_scale=ex_scale)
        g = self.mass_groups.setdefault(mass_group, [0.0, []])
        g[0] += float(np.sum(p.rho * np.broadcast_to(t, area.shape) * area))
        g[1].append((quads, area if weight is None else area * weight))
        self.categories[part] = cat

    def beams(self, part, n1, n2, orient, A, I, mass_group, cat, J=None):
        p = self.p
        n1, n2 = np.asarray(n1), np.asarray(n2)
        if len(n1) == 0:
            return
        A = np.broadcast_to(A, n1.shape).astype(float)
        I = np.broadcast_to(I, n1.shape).astype(float)
        J = 2 * I if J is None else np.broadcast_to(J, n1.shape)
        self.fe.add_beams(part, n1, n2, orient, p.E, p.E / (2 * (1 + p.nu)), A, I, I, J, rho=p.rho)
        L = np.linalg.norm(self.fe.nodes[n2] - self.fe.nodes[n1], axis=1)
        g = self.mass_groups.setdefault(mass_group, [0.0, []])
        g[0] += float(np.sum(p.rho * A * L))
        self.categories[part] = cat

    def spider(self, part, centre, xyz_pool_nodes, radius, cat, max_n=12):
        """Rigid links from node ``centre`` to the candidate nodes within ``radius``."""
        X = self.fe.nodes[xyz_pool_nodes]
        d = np.linalg.norm(X - self.fe.nodes[centre], axis=1)
        order = np.argsort(d)
        sel = [i for i in order[:max_n] if d[i] < radius and d[i] > 1e-9]
        if len(sel) < 3:
            raise NNMInputError(f"spider at node {centre} found only {len(sel)} nodes within {radius} m")
        self.fe.add_rigid_links(part, centre, np.asarray(xyz_pool_nodes)[sel])
        self.categories[part] = cat

    # ---------------------------------------------------------------- lifting surface
    def lifting_surface(self, name, cat, P_le, chord, tau, tdir, n_le, n_box, n_web, x_spar, x_rear,
                        n_te, t_skin, tb_skin, t_web, cap_area, rib_stations, te_parts, mass_group, n_rib=1):
        """Closed box (LE to rear web) + front spar web + caps + ribs + trailing-edge plates.

        te_parts : list of (part, group, mass_group, cat, interval mask (S-1,)).
        Returns dict of ring ids (S, R), section index info and TE ids per part.
        """
        p = self.p
        xc, frac, idx = geo.box_section(n_le, n_box, n_web, x_spar, x_rear)
        S = len(P_le)
        ex = np.array([1.0, 0.0, 0.0])
        zt = np.stack([geo.naca_half_thickness(xc, tau[j]) for j in range(S)])  # (S, R)
        X = (P_le[:, None, :] + (xc[None, :, None] * chord[:, None, None]) * ex
             + (frac[None, :] * zt * chord[:, None])[:, :, None] * tdir[:, None, :])
        ring = self.pool(X.reshape(-1, 3), 0).reshape(S, len(xc))
        taper = (chord / chord.max())
        tsk = np.repeat(t_skin * (0.55 + 0.45 * taper[:-1]), len(xc))
        self.shells(f"{name}", _quads(ring, True), tsk, tb_skin, mass_group, cat,
                    ex_scale=p.wing_skin_ex if name == "wing" else 1.0)
        self.grids.append((name, ring, True))
        # front spar web
        wf = np.linspace(-1, 1, n_web + 1)
        ztf = np.array([geo.naca_half_thickness(x_spar, tau[j]) for j in range(S)])
        Xw = (P_le[:, None, :] + (x_spar * chord)[:, None, None] * ex
              + (wf[None, :] * ztf[:, None] * chord[:, None])[:, :, None] * tdir[:, None, :])
        web = self.pool(Xw.reshape(-1, 3), 0).reshape(S, n_web + 1)
        self.shells(f"{name}", _quads(web, False), t_web, max(t_web, 0.004), mass_group, cat)
        # caps along the four spar lines
        ca = cap_area * taper ** 2
        for k in (idx["spar_up"], idx["spar_low"], idx["rear_up"], idx["rear_low"]):
            A = 0.5 * (ca[:-1] + ca[1:])
            self.beams(f"{name}", ring[:-1, k], ring[1:, k], tdir[0], A, A * 1e-4, mass_group, cat)
        # ribs: verticals and diagonals between upper and lower skins
        n_up = idx["n_up"]
        fwd = len(xc[:n_up])
        for j in rib_stations:
            up = ring[j, n_up - 1 - np.arange(1, fwd)]
            lo = ring[j, n_up + np.arange(0, fwd - 1)]
            n1 = np.concatenate([up, up[:-1]])
            n2 = np.concatenate([lo, lo[1:]])
            self.beams(f"{name}", n1, n2, ex, p.wing_rib_area * n_rib if name == "wing" else p.wing_rib_area * 0.5,
                       1e-8, mass_group, cat)
        # trailing-edge plates on the chord plane
        tex = np.linspace(x_rear, 1.0, n_te + 1)
        te_ids = {}
        for part, group, mg, pcat, mask in te_parts:
            Xt = P_le[:, None, :] + (tex[None, :, None] * chord[:, None, None]) * ex
            rows = np.flatnonzero(mask)
            if len(rows) == 0:
                continue
            st = np.unique(np.concatenate([rows, rows + 1]))
            ids = np.full((S, n_te + 1), -1, np.int64)
            ids[st] = self.pool(Xt[st].reshape(-1, 3), group).reshape(len(st), n_te + 1)
            q = _quads(ids, False).reshape(S - 1, n_te, 4)[rows].reshape(-1, 4)
            self.shells(part, q, 1.5e-3, 0.04, mg, pcat)
            # contiguous runs for display
            runs = np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1)
            for r in runs:
                self.grids.append((part.split(" ")[0], ids[r[0]:r[-1] + 2], False))
            te_ids[part] = (ids, st)
        return dict(ring=ring, web=web, xc=xc, frac=frac, idx=idx, te=te_ids, X=X)

    def hinge(self, part, cat, cs_nodes, wing_nodes, k_rot):
        """Hinge bushings (stiff translations, soft rotation about the hinge line)."""
        a = self.fe.nodes[cs_nodes[-1]] - self.fe.nodes[cs_nodes[0]]
        a /= np.linalg.norm(a)
        e2 = np.cross(a, [0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.cross(a, [1.0, 0.0, 0.0])
        e2 /= np.linalg.norm(e2)
        frame = np.array([a, e2, np.cross(a, e2)])
        for c, w in zip(cs_nodes, wing_nodes):
            self.fe.add_bushing(part, c, w, [1e9, 1e9, 1e9, k_rot, 0.0, 0.0], frame)
        self.categories[part] = cat
        return a

    def add_nsm(self):
        """Non-structural mass per group, spread over its shell nodes, to reach the target masses."""
        p = self.p
        targets = {"fuselage": p.mass_fuselage, "wing": p.mass_wing, "htail": p.mass_htail, "fin": p.mass_fin,
                   "aileron R": p.mass_aileron, "aileron L": p.mass_aileron, "elevator": p.mass_elevator,
                   "rudder": p.mass_rudder, "tank R": p.mass_tank, "tank L": p.mass_tank}
        n = self.fe.n_nodes
        for g, target in targets.items():
            struct, quads_list = self.mass_groups[g]
            extra = target - struct
            if extra < 0:
                raise NNMInputError(f"{g}: structural mass {struct:.1f} kg exceeds the target {target:.1f} kg; "
                                    f"thin its skins or raise mass_{g.split()[0]}")
            w = np.zeros(n)
            for q, a in quads_list:
                np.add.at(w, q.ravel(), np.repeat(a / 4, 4))
            nodes = np.flatnonzero(w)
            m = extra * w[nodes] / w.sum()
            diag = np.zeros((len(nodes), 6, 6))
            for d in range(3):
                diag[:, d, d] = m
            self.fe.add_block(f"nsm {g}", self.fe.node_dofs(nodes[:, None]), None, diag)


def _wing_stations(p, n_half):
    y = p.semi_span * np.linspace(-1, 1, 2 * n_half + 1)
    return y


def build_paris(params: ParisParams | None = None, assemble=True) -> Aircraft:
    """Build the Paris-like aircraft FE model (see ParisParams); K, M assembled if ``assemble``."""
    t0 = time.perf_counter()
    p = params or ParisParams()
    if p.mesh <= 0:
        raise NNMInputError(f"mesh scale must be positive, got {p.mesh}")
    b = _Builder(p)
    fe = b.fe
    ez = np.array([0.0, 0.0, 1.0])
    ey = np.array([0.0, 1.0, 0.0])

    # ------------------------------------------------------------ fuselage
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
    b.shells("fuselage", _quads(F, True), tf, p.fus_skin_tb, "fuselage", "fuselage",
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

    # ------------------------------------------------------------ wing (one surface, tip to tip)
    nh = b.n(40, 4)
    y = _wing_stations(p, nh)
    s = np.abs(y) / p.semi_span
    chord = p.root_chord + (p.tip_chord - p.root_chord) * s
    P_le = np.column_stack([p.x_le_root + np.tan(np.radians(p.le_sweep_deg)) * np.abs(y), y,
                            p.z_wing_root + np.tan(np.radians(p.dihedral_deg)) * np.abs(y)])
    tau = p.tau_root + (p.tau_tip - p.tau_root) * s
    tdir = np.tile(ez, (len(y), 1))
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
    tree = cKDTree(fe.nodes[fus_nodes])
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

    # ------------------------------------------------------------ fin (vertical tail)
    fin_root_z, fin_top_z = 1.35, 2.55
    z = np.linspace(fin_root_z, fin_top_z, b.n(14, 3) + 1)
    sf = (z - fin_root_z) / (fin_top_z - fin_root_z)
    fch = 1.8 + (1.1 - 1.8) * sf
    Pf = np.column_stack([8.0 + 1.0 * sf, np.zeros_like(z), z])
    Fn = b.lifting_surface("fin", "fin", Pf, fch, np.full_like(z, 1.1 * p.tail_tau), np.tile(ey, (len(z), 1)),
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
    H = b.lifting_surface("htail", "htail", Ph, hch, np.full_like(yh, p.tail_tau), np.tile(ez, (len(yh), 1)),
                          b.n(4, 2), b.n(6, 2), 2, 0.2, 0.7, b.n(3, 1), p.tail_skin_t, p.tail_skin_tb,
                          p.tail_skin_t * 1.5, p.tail_cap_area, range(0, len(yh), max(1, int(round(2 * p.mesh)))),
                          [("elevator", 4, "elevator", "elevator", np.ones(len(yh) - 1, bool))], "htail")
    b.sections["htail tip R"] = H["ring"][-1]
    b.sections["htail tip L"] = H["ring"][0]
    # T-tail junction: a rigid body joining the fin tip rib and the HT centre section
    jt = b.pool(np.array([Pf[-1, 0] + 0.35 * fch[-1], 0.0, fin_top_z]), 400)[0]
    centre_h = np.flatnonzero(np.abs(yh) <= 0.3)
    legs = np.unique(np.concatenate([Fn["ring"][-1], H["ring"][centre_h].ravel()]))
    fe.add_rigid_links("tail joints", jt, legs)
    ids, st = H["te"]["elevator"]
    pick = st[[0, len(st) // 2, -1]]
    mid = H["idx"]["n_up"] + H["idx"]["n_low"] + H["idx"]["n_web"] // 2
    b.hinge("hinge elevator", "elevator", ids[pick, 0], H["ring"][pick, mid], p.k_elevator)

    # ------------------------------------------------------------ tip tanks and attachments
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
        b.shells(part, _quads(T, True), p.tank_skin_t, 0.01, part, "tank", weight=wt)
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
    # order: R front (w, t), R rear (w, t), L front (w, t), L rear (w, t)
    # ------------------------------------------------------------ landing gears
    gear_nodes = []
    xg, zg = 2.0, geo.fuselage_profile(2.0)[2] - geo.fuselage_profile(2.0)[1]
    gn = b.pool(np.array([xg, 0.0, zg]), 300)[0]
    b.spider("fuselage", gn, fus_nodes, 0.35, "fuselage", max_n=10)
    fe.add_bushing("gear", gn, None, list(p.nose_gear_k) + [0.0] * 3)
    fe.add_point_mass("gear mass", gn, p.mass_gear_nose)
    gear_nodes.append(gn)
    for sgn in (1.0, -1.0):
        yg = sgn * 1.6
        zc = p.z_wing_root + np.tan(np.radians(p.dihedral_deg)) * 1.6
        gn = b.pool(np.array([4.9, yg, zc]), 301 if sgn > 0 else 302)[0]
        b.spider("wing", gn, wing_nodes, 0.35, "wing", max_n=10)
        fe.add_bushing("gear", gn, None, list(p.main_gear_k) + [0.0] * 3)
        fe.add_point_mass("gear mass", gn, p.mass_gear_main)
        gear_nodes.append(gn)
    b.categories["gear"] = "gear"
    b.categories["gear mass"] = "gear"
    b.add_nsm()

    # ------------------------------------------------------------ mirror map
    groups = np.asarray(b.pool.group)
    mirror_group = {1: 2, 2: 1, 5: 6, 6: 5, 105: 106, 106: 105, 205: 206, 206: 205, 301: 302, 302: 301}
    mg = np.array([mirror_group.get(g, g) if g < 1000 else -1 for g in groups])
    key = {}
    X = fe.nodes
    for i, (g, p_) in enumerate(zip(groups, X)):
        if g < 1000:
            key[(g, *np.round(p_ * 1e4).astype(np.int64))] = i
    mirror = np.full(fe.n_nodes, -1)
    for i, (g, p_) in enumerate(zip(mg, X)):
        if g < 0:
            continue
        mirror[i] = key.get((g, *np.round(np.array([p_[0], -p_[1], p_[2]]) * 1e4).astype(np.int64)), -1)
    ac = Aircraft(fe=fe, params=p, retained_nodes=retained, mirror=mirror, grids=b.grids, sections=b.sections,
                  categories=b.categories)
    ac.sections["gear"] = np.array(gear_nodes)
    if assemble:
        ac.K, ac.M = fe.assemble()
    ac.build_seconds = time.perf_counter() - t0
    return ac
