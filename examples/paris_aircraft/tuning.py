"""Scripted tuning of the aircraft parameters against Table 2 of the seed paper.

1. Suspension and control-surface stiffnesses (modes 1-9) from a rigid-body model built
   with the FE mass matrix (6 rigid motions on the gear springs) and the hinge inertias.
2. Structural parameters by a damped Newton loop in log-log space on a coarse mesh:
   wing spar caps -> 1st symmetric wing bending, tail skins -> 1st tail bending,
   wing-fuselage joint stiffness -> symmetric wing torsion, wing skin -> anti-symmetric
   wing torsion.  The fine mesh is then corrected by the same loop (one Jacobian reused).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as sla
from scipy.optimize import least_squares

from nnm_fem import modes
from .builder import build_paris
from .labels import label_modes

TABLE2_HZ = np.array([0.0936, 0.7260, 0.9606, 1.2118, 1.2153, 1.7951, 2.1072, 2.5157, 3.5736,
                      8.1913, 9.8644, 16.1790, 21.2193, 22.7619, 23.6525, 25.8667, 28.2679, 29.3309,
                      31.0847, 34.9151, 39.5169, 40.8516, 47.3547, 52.1404])

#: suspension-mode targets (Hz), sorted, and control-surface rotation targets (Hz)
GEAR_TARGETS = np.array([0.0936, 0.7260, 0.9606, 1.2118, 1.7951, 3.5736])
HINGE_TARGETS = {"rudder": 1.2153, "aileron": 2.1072, "elevator": 2.5157}

#: (parameter, mode class, target Hz); mode class = (part, kind, symmetry or None)
#: bounds of the primary parameters
BOUNDS = {"mass_tank": (15.0, 150.0), "wing_skin_ex": (0.02, 1.0), "tail_tau": (0.08, 0.16), "wf_rear_k": (1e4, 3e8),
          "wing_skin_t": (1e-3, 3.4e-3)}

PRIMARY = [("wing_skin_ex", ("wing", "bending", "symmetric"), 8.1913),
           ("tail_tau", ("tail", "bending", None), 21.2193),
           ("wf_rear_k", ("wing", "torsion", "symmetric"), 31.0847),
           ("wing_skin_t", ("wing", "torsion", "anti-symmetric"), 34.9151)]


def rigid_modes(ac, X0=None):
    """Rigid-body displacement fields (n, 6) about X0 (default: the mass centre)."""
    X = ac.fe.nodes
    if X0 is None:
        m = ac.M.diagonal()[0::6]
        X0 = (m[:, None] * X).sum(0) / m.sum()
    r = X - X0
    n = len(X)
    R = np.zeros((n, 6, 6))
    for d in range(3):
        R[:, d, d] = 1.0
        R[:, 3 + d, 3 + d] = 1.0
    # u = theta x r
    R[:, 0, 4], R[:, 0, 5] = r[:, 2], -r[:, 1]
    R[:, 1, 3], R[:, 1, 5] = -r[:, 2], r[:, 0]
    R[:, 2, 3], R[:, 2, 4] = r[:, 1], -r[:, 0]
    return R.reshape(6 * n, 6)


def gear_frequencies(ac, main_k, nose_k, R=None, Mrb=None):
    """Suspension frequencies (Hz) of the rigid aircraft on its gear springs."""
    R = rigid_modes(ac) if R is None else R
    Mrb = R.T @ (ac.M @ R) if Mrb is None else Mrb
    Krb = np.zeros((6, 6))
    for g, k in zip(ac.sections["gear"], (nose_k, main_k, main_k)):
        B = R[6 * g:6 * g + 3]
        Krb += B.T @ np.diag(k) @ B
    lam = sla.eigh(Krb, Mrb, eigvals_only=True)
    return np.sqrt(np.maximum(lam, 0)) / (2 * np.pi)


def tune_gears(ac, targets=GEAR_TARGETS):
    """Gear spring stiffnesses (main (kx, ky, kz), nose (kx, ky, kz)) in N/m fitting the targets."""
    R = rigid_modes(ac)
    Mrb = R.T @ (ac.M @ R)
    prior = np.log([300.0, 5e3, 6e4, 200.0, 3e3, 2e4])   # rolling tyres are soft fore-aft
    x0 = prior.copy()

    def res(x):
        k = np.exp(x)
        r = np.log(gear_frequencies(ac, k[:3], k[3:], R, Mrb)) - np.log(targets)
        return np.concatenate([r, 0.01 * (x - prior)])

    sol = least_squares(res, x0, bounds=(np.log(10.0), np.log(1e7)), max_nfev=2000)
    k = np.exp(sol.x)
    return tuple(float(v) for v in k[:3]), tuple(float(v) for v in k[3:]), gear_frequencies(ac, k[:3], k[3:], R, Mrb)


def tune_low_modes(ac, low=TABLE2_HZ[:9], gear_modes=None):
    """Choose which 6 of the 9 lowest Table-2 modes are suspension modes (best rigid-body fit;
    mode 1, 0.09 Hz, is kept as the rolling fore-aft mode on the tyres) and fit gear and hinge
    stiffnesses.  ``gear_modes`` (0-based indices) skips the search.
    Returns (dict of parameter values, gear Hz, hinge Hz)."""
    from itertools import combinations
    best = None
    cands = [tuple(gear_modes)] if gear_modes is not None else \
        [c for c in combinations(range(len(low)), 6) if 0 in c]
    for idx in cands:
        mk, nk, fg = tune_gears(ac, low[list(idx)])
        err = np.max(np.abs(np.log(fg / low[list(idx)])))
        if best is None or err < best[0]:
            best = (err, idx, mk, nk, fg)
    err, idx, mk, nk, fg = best
    rest = [low[i] for i in range(len(low)) if i not in idx]
    # control surfaces: the lightest/stiffest ordering is free; keep aileron < elevator < rudder
    hz = dict(zip(("aileron", "elevator", "rudder"), sorted(rest)))
    vals = dict(main_gear_k=mk, nose_gear_k=nk, **tune_hinges(ac, hz))
    return vals, fg, hz


def hinge_inertia(ac, part):
    """Rotary inertia (kg m^2) of a control surface about its hinge line and its hinge count."""
    fe = ac.fe
    nodes = np.unique(np.concatenate([dofs[:, ::6].ravel() // 6 for dofs in fe.element_dofs(part)]))
    hb = [dofs for dofs in fe.element_dofs(f"hinge {part.split()[0]}") if dofs.shape[1] == 12 and dofs[0, 0] % 6 == 0]
    hn = [dofs[0, 0] // 6 for dofs in hb if dofs[0, 0] // 6 in set(nodes)]
    a = fe.nodes[hn[-1]] - fe.nodes[hn[0]]
    a /= np.linalg.norm(a)
    r = fe.nodes[nodes] - fe.nodes[hn[0]]
    phi = np.zeros((fe.n_nodes, 6))
    phi[nodes, :3] = np.cross(a, r)
    phi[nodes, 3:] = a
    phi = phi.ravel()
    return float(phi @ (ac.M @ phi)), len(hn)


def tune_hinges(ac, targets=HINGE_TARGETS):
    """Hinge rotational stiffnesses (N m/rad per hinge point) for the rotation targets."""
    out = {}
    for cs, f in targets.items():
        if cs == "aileron":
            I = sum(hinge_inertia(ac, f"aileron {s}")[0] for s in "RL")
            n = 2 * hinge_inertia(ac, "aileron R")[1]
        else:
            I, n = hinge_inertia(ac, cs)
        out[f"k_{cs}"] = I * (2 * np.pi * f) ** 2 / n
    return out


def find_class(kinds, cls):
    part, kind, sym = cls
    for i, (p, k, s, _, _, _, score, tail) in enumerate(kinds):
        pp = "tail" if p in ("horizontal tail", "fin") or (tail > 0.3 and part == "tail") else p
        ok = sym is None or (score > 0 if sym == "symmetric" else score < 0)
        if pp == part and k == kind and ok:
            return i
    return None


def evaluate(params, n_modes=40, verbose=False):
    """Build, solve and label: (freqs_hz, labels, primary frequencies (4,) or nan)."""
    ac = build_paris(params)
    f, V = modes(ac.K, ac.M, n_modes, sigma=-1.0, xyz=ac.fe.nodes)
    labels, kinds = label_modes(ac, V)
    prim = np.array([f[i] if (i := find_class(kinds, cls)) is not None else np.nan for _, cls, _ in PRIMARY])
    if verbose:
        print("  primary:", np.round(prim, 3), "targets", [t for *_, t in PRIMARY], flush=True)
    return f, labels, prim, ac


def _with(params, logp):
    kw = {name: float(np.exp(v)) for (name, _, _), v in zip(PRIMARY, logp)}
    return dataclasses.replace(params, **kw)


def tune_primary(params, iterations=4, jac=None, tol=0.005, verbose=True):
    """Damped Newton on log(params) -> log(primary frequencies).  Returns (params, jac, history)."""
    targets = np.log([t for *_, t in PRIMARY])
    logp = np.log([getattr(params, name) for name, _, _ in PRIMARY])
    hist = []
    f, lab, prim, _ = evaluate(params, verbose=verbose)
    for it in range(iterations):
        r = targets - np.log(prim)
        hist.append((np.exp(logp).copy(), prim.copy()))
        if verbose:
            print(f"iter {it}: params {np.round(np.exp(logp), 8)} err % {np.round(100 * (np.exp(-r) - 1), 2)}",
                  flush=True)
        if np.all(np.abs(r) < tol):
            break
        if jac is None:
            jac = np.zeros((len(PRIMARY), len(PRIMARY)))
            for j in range(len(PRIMARY)):
                lp = logp.copy()
                lp[j] += 0.2
                _, _, pj, _ = evaluate(_with(params, lp))
                jac[:, j] = (np.log(pj) - np.log(prim)) / 0.2
            jac = np.nan_to_num(jac)
            if verbose:
                print("  jacobian:\n", np.round(jac, 3), flush=True)
        step = np.linalg.lstsq(jac, r, rcond=1e-2)[0]
        step = np.clip(step, -0.5, 0.5)
        lo = np.log([BOUNDS[name][0] for name, _, _ in PRIMARY])
        hi = np.log([BOUNDS[name][1] for name, _, _ in PRIMARY])
        logp = np.clip(logp + step, lo, hi)
        params = _with(params, logp)
        f, lab, prim, _ = evaluate(params, verbose=verbose)
    return params, jac, hist
