"""Structure assembly helpers of the aircraft builder: node pool, shells, beams, spiders,
lifting surfaces (closed box + spar web + caps + ribs + trailing-edge plates), hinges and
non-structural mass."""
from __future__ import annotations

import numpy as np

from nnm_solver.errors import NNMInputError
from nnm_fem import FEModel
from . import geometry as geo
from .params import ParisParams


class NodePool:
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


def grid_quads(ids, periodic):
    """Quads (n, 4) of a structured (S, R) grid of node ids; ``periodic`` closes the rings."""
    a = ids if not periodic else np.concatenate([ids, ids[:, :1]], axis=1)
    return np.stack([a[:-1, :-1], a[1:, :-1], a[1:, 1:], a[:-1, 1:]], -1).reshape(-1, 4)


class StructureBuilder:
    """FE model under construction, with per-group structural mass, display grids, sections, categories."""

    def __init__(self, p: ParisParams):
        self.p = p
        self.fe = FEModel()
        self.pool = NodePool(self.fe)
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
        self.shells(f"{name}", grid_quads(ring, True), tsk, tb_skin, mass_group, cat,
                    ex_scale={"wing": p.wing_skin_ex, "fin": p.fin_skin_ex, "htail": p.htail_skin_ex}.get(name, 1.0))
        self.grids.append((name, ring, True))
        # front spar web
        wf = np.linspace(-1, 1, n_web + 1)
        ztf = np.array([geo.naca_half_thickness(x_spar, tau[j]) for j in range(S)])
        Xw = (P_le[:, None, :] + (x_spar * chord)[:, None, None] * ex
              + (wf[None, :] * ztf[:, None] * chord[:, None])[:, :, None] * tdir[:, None, :])
        web = self.pool(Xw.reshape(-1, 3), 0).reshape(S, n_web + 1)
        self.shells(f"{name}", grid_quads(web, False), t_web, max(t_web, 0.004), mass_group, cat)
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
            q = grid_quads(ids, False).reshape(S - 1, n_te, 4)[rows].reshape(-1, 4)
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

