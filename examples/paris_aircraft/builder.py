"""Parametric finite-element model of a Paris-like jet trainer (SI units).

Axes: x aft from the nose (x = 0 at the nose, x = 10.4 m at the tail), y towards the
right wing, z up (ground at z = 0).  Skins are MITC4 shells, spar caps, ribs, frames,
longerons and attachments are beams, gears are 3D springs to ground, control surfaces
hang on soft hinge bushings, and rigid connections are penalty stiff beams.

The parts: params.py (ParisParams, Aircraft), structure.py (assembly helpers), airframe.py
(fuselage, wing, tail), attachments.py (tip tanks and attachments, landing gears); this module
puts them together in a fixed order (node numbering depends on it) and maps mirror nodes.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.spatial import cKDTree

from nnm_solver.errors import NNMInputError
from .airframe import add_fuselage, add_tail, add_wing
from .attachments import add_landing_gears, add_tip_tanks
from .params import ATTACHMENT_NAMES, BUILDER_VERSION, Aircraft, ParisParams
from .structure import StructureBuilder

__all__ = ["ATTACHMENT_NAMES", "BUILDER_VERSION", "Aircraft", "ParisParams", "build_paris"]


def _mirror_map(pool, X):
    """Node -> mirror node (y -> -y, left/right node groups swapped); -1 where there is none."""
    groups = np.asarray(pool.group)
    mirror_group = {1: 2, 2: 1, 5: 6, 6: 5, 105: 106, 106: 105, 205: 206, 206: 205, 301: 302, 302: 301}
    mg = np.array([mirror_group.get(g, g) if g < 1000 else -1 for g in groups])
    key = {}
    for i, (g, p_) in enumerate(zip(groups, X)):
        if g < 1000:
            key[(g, *np.round(p_ * 1e4).astype(np.int64))] = i
    mirror = np.full(len(X), -1)
    for i, (g, p_) in enumerate(zip(mg, X)):
        if g < 0:
            continue
        mirror[i] = key.get((g, *np.round(np.array([p_[0], -p_[1], p_[2]]) * 1e4).astype(np.int64)), -1)
    return mirror


def build_paris(params: ParisParams | None = None, assemble=True) -> Aircraft:
    """Build the Paris-like aircraft FE model (see ParisParams); K, M assembled if ``assemble``."""
    t0 = time.perf_counter()
    p = params or ParisParams()
    if p.mesh <= 0:
        raise NNMInputError(f"mesh scale must be positive, got {p.mesh}")
    b = StructureBuilder(p)
    fe = b.fe
    fus_nodes = add_fuselage(b)
    tree = cKDTree(fe.nodes[fus_nodes])
    ring, wing_nodes = add_wing(b, fus_nodes, tree)
    add_tail(b, fus_nodes, tree)
    retained = add_tip_tanks(b, ring)
    gear_nodes = add_landing_gears(b, fus_nodes, wing_nodes)
    b.add_nsm()
    mirror = _mirror_map(b.pool, fe.nodes)
    ac = Aircraft(fe=fe, params=p, retained_nodes=retained, mirror=mirror, grids=b.grids, sections=b.sections,
                  categories=b.categories)
    ac.sections["gear"] = np.array(gear_nodes)
    if assemble:
        ac.K, ac.M = fe.assemble()
    ac.build_seconds = time.perf_counter() - t0
    return ac
