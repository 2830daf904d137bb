"""Scripted tuning of the aircraft parameters against Table 2 of the seed paper.

1. Suspension and control-surface stiffnesses (modes 1-9) from a rigid-body model built
   with the FE mass matrix (6 rigid motions on the gear springs) and the hinge inertias.
2. Structural parameters by a damped Newton loop in log-log space on a coarse mesh:
   wing spar caps -> 1st symmetric wing bending, tail skins -> 1st tail bending,
   wing-fuselage joint stiffness -> symmetric wing torsion, wing skin -> anti-symmetric
   wing torsion.  The fine mesh is then corrected by the same loop (one Jacobian reused).

Builder 1.1 (tune_builder_1_1) re-tunes the whole spectrum on the fine mesh: the main-gear layout
with the gear and hinge stiffnesses corrected on the FE model (tune_gear_layout,
tune_low_modes_fe), then a Levenberg-Marquardt fit of up to 17 structural parameters on all the
Table-2 slots 10-24 (tune_spectrum), the modes followed by their shapes (track_modes).

Builder 1.2 (tune_builder_1_2) adds the T-tail fittings' pitch stiffness, fitted so that a global
symmetric tail torsion sits just under three times mode 19 (tune_tail_torsion): the 3:1 internal
resonance of the seed paper's Fig. 12.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as sla
from scipy.optimize import least_squares

from nnm_fem import modes
from nnm_solver.errors import NNMInputError
from .builder import build_paris
from .labels import label_modes

TABLE2_HZ = np.array([0.0936, 0.7260, 0.9606, 1.2118, 1.2153, 1.7951, 2.1072, 2.5157, 3.5736,
                      8.1913, 9.8644, 16.1790, 21.2193, 22.7619, 23.6525, 25.8667, 28.2679, 29.3309,
                      31.0847, 34.9151, 39.5169, 40.8516, 47.3547, 52.1404])

#: the seed paper's names of its modes 1..24 (Table 2 and its text; '' where it names none): the model's own
#: labels number each kind of mode by frequency ('wing torsion 2 (symmetric)' is the paper's first symmetric
#: wing torsion), so a file of the model carries both (/extra/reference/mode_names, shown next to the labels).
#: build_paris.py writes them, as the shipped assets/paris.h5 has them (tests/test_aircraft.py: SUPERSEDED_BUILDS)
PAPER_MODE_NAMES = [""] * 9 + ["first wing bending", "", "", "first tail bending"] + [""] * 5 + [
    "first (symmetric) wing torsion", "second (anti-symmetric) wing torsion", "", "", "", ""]

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


def labelled_spectrum(params, n_modes=40):
    """Build, solve and label the full FE model: (freqs_hz, labels, kinds, aircraft, mode shapes)."""
    ac = build_paris(params)
    f, V = modes(ac.K, ac.M, n_modes, sigma=-1.0, xyz=ac.fe.nodes)
    labels, kinds = label_modes(ac, V)
    return f, labels, kinds, ac, V


def evaluate(params, n_modes=40, verbose=False):
    """Build, solve and label: (freqs_hz, labels, primary frequencies (4,) or nan, aircraft)."""
    f, labels, kinds, ac, _ = labelled_spectrum(params, n_modes)
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


# ---------------------------------------------------------------------------------------------
# Whole-spectrum tuning (builder 1.1): all 24 modes of Table 2, in order, with the paper's kinds
# ---------------------------------------------------------------------------------------------

#: structural parameters of the whole-spectrum fit and their bounds (the fit is in log space)
SPECTRUM_BOUNDS = {"wing_skin_ex": (0.02, 1.0), "wing_skin_t": (1e-3, 3.4e-3), "wing_cap_area": (5e-5, 1e-3),
                   "wf_rear_k": (1e4, 3e8), "tail_tau": (0.08, 0.16), "fin_skin_ex": (0.05, 2.0),
                   "tail_skin_t": (1e-3, 6e-3), "fin_skin_t": (1.5e-3, 1e-2), "fus_skin_t": (6e-4, 3e-3),
                   "fus_rear_skin_t": (1e-3, 6e-3), "fus_longeron_area": (1e-4, 2e-3), "att_kx": (1e5, 1e7),
                   "mass_tank": (30.0, 80.0), "tank_mass_sigma": (0.2, 1.5), "mass_htail": (40.0, 90.0),
                   "mass_fin": (45.0, 90.0), "k_aileron_sym": (1e2, 1e6)}


#: mode classes (model label without its trailing details) tuned to a Table-2 slot (1-based); the
#: paper names the kinds of slots 10, 13, 19 and 20, the others follow the model's own order
SLOT_PLAN = [("wing bending 1 (symmetric)", 10), ("wing bending 1 (anti-symmetric)", 11),
             ("wing in-plane bending 1 (anti-symmetric)", 12), ("fin bending 1", 13),
             ("wing bending 2 (anti-symmetric)", 14), ("wing in-plane bending 1 (symmetric)", 15),
             ("tip tanks fore-aft 1 (symmetric)", 16), ("fuselage lateral bending 1 (anti-symmetric)", 17),
             ("fuselage vertical bending 1 (symmetric)", 18), ("wing torsion 1 (symmetric)", 19),
             ("wing torsion 1 (anti-symmetric)", 20), ("wing torsion 2 (symmetric)", 21), ("fin torsion 1", 22),
             ("tip tanks fore-aft 1 (anti-symmetric)", 23), ("fuselage vertical bending 2 (symmetric)", 24)]
#: modes pushed above the 24th slot: (mode number at the start of the fit, floor in Hz), one-sided;
#: at builder 1.0 modes 25 and 26 (49.2-49.4 Hz: horizontal-tail bending and a fuselage mode) sit
#: between the paper's 47.35 and 52.14 Hz
ABOVE_PLAN = [(25, 55.0), (26, 55.0)]


def track_modes(V, M, refs):
    """Index of the column of V most like each reference shape (rows of refs), by mass-weighted MAC."""
    MV = M @ V
    vv = np.einsum("ij,ij->j", V, MV)
    return [int(np.argmax((phi @ MV) ** 2 / vv)) for phi in refs]


def reference_shapes(labels, V, by="label"):
    """Shapes (n_classes, n_dof) of the modes followed by the fit: for each class of SLOT_PLAN the
    first mode with that label (``by="label"``) or the mode already in that slot (``by="order"``, for
    a start whose order is right), then the modes of ABOVE_PLAN (by number)."""
    if by == "label":
        idx = [next(i for i, lab in enumerate(labels) if lab.startswith(prefix)) for prefix, _ in SLOT_PLAN]
    else:
        idx = [slot - 1 for _, slot in SLOT_PLAN]
    idx += [k - 1 for k, _ in ABOVE_PLAN]
    return V[:, idx].T.copy()


def spectrum_residual(f, tracked, sorted_weight=0.5):
    """Residuals (log frequency) against Table 2: the modes ``tracked`` (indices, one per class of
    SLOT_PLAN then of ABOVE_PLAN, see track_modes) against their slots, those of ABOVE_PLAN below their
    floors (one-sided), and ``sorted_weight`` times the sorted model frequencies of slots 10-24
    against the paper's (the order)."""
    f = np.asarray(f)
    r = [np.log(f[i] / TABLE2_HZ[slot - 1]) for i, (_, slot) in zip(tracked, SLOT_PLAN)]
    r += [min(0.0, np.log(f[i] / floor)) for i, (_, floor) in zip(tracked[len(SLOT_PLAN):], ABOVE_PLAN)]
    r += [sorted_weight * np.log(f[i] / TABLE2_HZ[i]) for i in range(9, 24)]
    return np.array(r)


def table2_report(f, labels, slots=range(24), tol=0.03):
    """Text table of the first 24 model modes against Table 2; returns (text, slots within tol)."""
    lines, ok = [], []
    for i in slots:
        d = f[i] / TABLE2_HZ[i] - 1
        if abs(d) <= tol:
            ok.append(i + 1)
        lines.append(f"{i + 1:3d} {f[i]:9.4f} {TABLE2_HZ[i]:9.4f} {100 * d:+7.2f} %  {labels[i]}")
    return "\n".join(lines), ok


def _spectrum_params(params, names, logp):
    return dataclasses.replace(params, **{n: float(np.exp(v)) for n, v in zip(names, logp)})


def tune_spectrum(params, names, iterations=6, jac=None, step=0.15, reg=0.02, damping=1e-2, by="label",
                  verbose=True):
    """Levenberg-Marquardt in log(parameters) on spectrum_residual (the classes of SLOT_PLAN on
    their slots, those of ABOVE_PLAN above slot 24, the sorted order), with a weak pull (``reg``)
    towards the starting values.  Modes are followed by their shapes (track_modes; the references
    are the modes of the start chosen by reference_shapes(..., by), renewed at each accepted step),
    so that a label changing with the mixing of two modes does not break the Jacobian.  The
    Jacobian is built once by forward differences (``step`` in log) and then updated by Broyden's
    rank-one formula after each step.

    Returns (params, jac, history of (parameter values, residual norm))."""
    lo = np.log([SPECTRUM_BOUNDS[n][0] for n in names])
    hi = np.log([SPECTRUM_BOUNDS[n][1] for n in names])
    logp0 = np.log([getattr(params, n) for n in names])

    def res(logp, refs):
        try:
            f, labels, _, ac, V = labelled_spectrum(_spectrum_params(params, names, logp), n_modes=40)
        except NNMInputError:     # a part heavier than its target mass
            return None, None, None
        tracked = track_modes(V, ac.M, refs)
        return np.concatenate([spectrum_residual(f, tracked), reg * (logp - logp0)]), f, (labels, V[:, tracked].T)

    logp = logp0.copy()
    f, labels, _, ac, V = labelled_spectrum(params, n_modes=40)
    refs = reference_shapes(labels, V, by)
    r, f, (labels, refs) = res(logp, refs)
    hist = [(np.exp(logp), float(np.linalg.norm(r)))]
    if jac is None:
        jac = np.zeros((len(r), len(names)))
        for j in range(len(names)):
            lp = logp.copy()
            lp[j] += step if lp[j] + step <= hi[j] else -step
            rj, _, _ = res(lp, refs)
            jac[:, j] = 0.0 if rj is None else (rj - r) / (lp[j] - logp[j])
            if verbose:
                print(f"  d/d log {names[j]}: {np.round(jac[:15, j], 2)}", flush=True)
    mu = damping
    for it in range(iterations):
        if verbose:
            print(f"iter {it}: |r| {np.linalg.norm(r):.4f}  slots 10-24 (sorted) % "
                  f"{np.round(100 * (f[9:24] / TABLE2_HZ[9:24] - 1), 1)}", flush=True)
        A = jac.T @ jac
        dx = np.linalg.solve(A + mu * np.diag(np.diag(A) + 1e-9), -jac.T @ r)
        dx = np.clip(dx, -0.5, 0.5)
        trial = np.clip(logp + dx, lo, hi)
        rt, ft, lt = res(trial, refs)
        if rt is None:          # the builder rejected the step: shorter steps
            mu *= 4
            continue
        s = trial - logp
        jac += np.outer(rt - r - jac @ s, s) / max(s @ s, 1e-12)   # Broyden update
        if np.linalg.norm(rt) < np.linalg.norm(r):
            logp, r, f, (labels, refs) = trial, rt, ft, lt
            mu = max(mu / 3, 1e-4)
        else:
            mu *= 4
        hist.append((np.exp(logp), float(np.linalg.norm(r))))
        if verbose:
            print("  params:", {n: float(f"{v:.5g}") for n, v in zip(names, np.exp(logp))}, flush=True)
    return _spectrum_params(params, names, logp), jac, hist


#: FE-model targets of the 6 suspension modes (Table-2 slots 1, 2, 4, 5, 6, 9, sorted) and of the
#: control-surface rotations (slot 3: aileron, anti-symmetric; 7: elevator; 8: rudder).  Slots 4
#: and 5 (1.2118 and 1.2153 Hz, 0.3 % apart) are aimed 3 % apart, both within 1.7 % of the paper,
#: so that the pitch and roll suspension modes do not mix.
FE_GEAR_TARGETS = np.array([0.0936, 0.7260, 1.195, 1.232, 1.7951, 3.5736])
FE_HINGE_TARGETS = {"aileron": 0.9606, "elevator": 2.1072, "rudder": 2.5157}


def tune_low_modes_fe(params, iterations=2, verbose=True):
    """Gear layout, gear and hinge stiffnesses corrected on the full FE model: the rigid-body gear
    fit (tune_gear_layout) is aimed at targets scaled by (rigid-body / FE frequency) of the current
    gears, which removes the airframe's flexibility error; each hinge stiffness is scaled
    by (target / FE frequency)^2.  Returns the corrected parameters."""
    for it in range(iterations):
        f, labels, _, ac, _ = labelled_spectrum(params, n_modes=12)
        gear = np.sort([fi for fi, lab in zip(f, labels) if lab.startswith("gear suspension")])[:6]
        rigid = gear_frequencies(ac, params.main_gear_k, params.nose_gear_k)
        gears, _ = tune_gear_layout(ac, FE_GEAR_TARGETS * rigid / gear)
        hinge, hinge_hz = {}, {}
        for cs, target in FE_HINGE_TARGETS.items():
            i = next(i for i, lab in enumerate(labels) if lab.startswith(f"{cs} rotation"))
            hinge[f"k_{cs}"] = getattr(params, f"k_{cs}") * (target / f[i]) ** 2
            hinge_hz[cs] = round(float(f[i]), 4)
        if verbose:
            print(f"low modes, iteration {it}: gear Hz {np.round(gear, 4)} hinge Hz {hinge_hz}", flush=True)
        params = dataclasses.replace(params, **gears, **hinge)
    return params


def _gear_kinematics(r):
    """(3, 6) map from the rigid motion (t, theta) about the mass centre to the translation of a
    point at offset r from it."""
    B = np.zeros((3, 6))
    B[:, :3] = np.eye(3)
    B[0, 4], B[0, 5] = r[2], -r[1]
    B[1, 3], B[1, 5] = -r[2], r[0]
    B[2, 3], B[2, 4] = r[1], -r[0]
    return B


def tune_gear_layout(ac, targets=FE_GEAR_TARGETS):
    """Main-gear position (x, |y|) and gear spring stiffnesses fitting the six suspension targets
    with the rigid-body model.  With the gears of builder 1.0 (x = 4.9 m, |y| = 1.6 m) the pitch and
    roll modes (slots 4 and 5) cannot both be reached by the six stiffnesses (best 1.15 and 1.30 Hz
    for 1.21 Hz); the track and the gear's fore-aft position free them.
    Returns dict(main_gear_x, main_gear_y, main_gear_k, nose_gear_k) and the fitted Hz."""
    X = ac.fe.nodes
    m = ac.M.diagonal()[0::6]
    X0 = (m[:, None] * X).sum(0) / m.sum()
    R = rigid_modes(ac)
    Mrb = R.T @ (ac.M @ R)
    nose, main = X[ac.sections["gear"][0]], X[ac.sections["gear"][1]]

    def freqs(x):
        k = np.exp(x[:6])
        pos = [(nose, k[3:]), (np.array([x[6], x[7], main[2]]), k[:3]), (np.array([x[6], -x[7], main[2]]), k[:3])]
        K = sum(_gear_kinematics(g - X0).T @ np.diag(kk) @ _gear_kinematics(g - X0) for g, kk in pos)
        return np.sqrt(np.maximum(sla.eigh(K, Mrb, eigvals_only=True), 0)) / (2 * np.pi)

    p = ac.params
    x0 = np.r_[np.log(np.r_[p.main_gear_k, p.nose_gear_k]), main[0], main[1]]
    sol = least_squares(lambda x: np.log(freqs(x) / targets), x0,
                        bounds=(np.r_[[np.log(10.0)] * 6, 4.0, 1.0], np.r_[[np.log(1e7)] * 6, 5.5, 2.5]))
    k = np.exp(sol.x[:6])
    return dict(main_gear_x=float(sol.x[6]), main_gear_y=float(sol.x[7]), main_gear_k=tuple(map(float, k[:3])),
                nose_gear_k=tuple(map(float, k[3:]))), freqs(sol.x)


#: the parameters of the two spectrum fits of tune_builder_1_1
SPECTRUM_NAMES_1 = ["wing_skin_ex", "wing_skin_t", "wing_cap_area", "wf_rear_k", "tail_tau", "fin_skin_ex",
                    "tail_skin_t", "fin_skin_t", "fus_skin_t", "fus_rear_skin_t", "fus_longeron_area", "att_kx",
                    "mass_tank", "tank_mass_sigma", "mass_htail", "mass_fin", "k_aileron_sym"]
SPECTRUM_NAMES_2 = ["wing_skin_ex", "wing_skin_t", "wf_rear_k", "tail_tau", "fin_skin_ex", "tail_skin_t",
                    "fin_skin_t", "fus_skin_t", "fus_rear_skin_t", "fus_longeron_area", "att_kx", "mass_tank",
                    "tank_mass_sigma", "mass_htail", "k_aileron_sym"]


def tune_builder_1_1(params, verbose=True):
    """The re-tuning of builder 1.1 from the builder-1.0 values (about 25 minutes of FE solves):

    1. gear layout and stiffnesses, hinges (tune_gear_layout, then tune_low_modes_fe);
    2. spectrum fit with the classes of SLOT_PLAN found by label (12 iterations, SPECTRUM_NAMES_1);
       it brings slots 10-12 and 15-24 near Table 2 but cannot lower the fin bending (24 Hz) under
       the second anti-symmetric wing bending (21 Hz): the two veer (fuselage torsion couples them);
    3. the crossing by hand: fin skins' spanwise stiffness fin_skin_ex = 0.9 (the fin bending drops
       to 20.3 Hz, below the wing bending, now 23.7 Hz) and the fin mass back to 65 kg (step 2 had
       raised it to its 90 kg bound);
    4. spectrum fit again with the modes followed from their slots (by="order", 8 iterations,
       SPECTRUM_NAMES_2);
    5. tune_low_modes_fe (the masses moved the suspension modes);
    6. ``wing_skin_ex`` x 1.03 by hand (mode 24, the third anti-symmetric wing bending, from -3.1 % to
       -2.7 %; mode 10 from -1.3 % to -0.3 %, mode 16 to +2.9 %).

    The shipped ParisParams are the result of this sequence as run for builder 1.1 (step 2 then
    scaled the fin and horizontal-tail skins together; it left that factor at 1), rounded to 5
    digits; a re-run follows the same path but is not bit-identical."""
    gears, _ = tune_gear_layout(build_paris(params))
    p = tune_low_modes_fe(dataclasses.replace(params, **gears), iterations=3, verbose=verbose)
    p, _, _ = tune_spectrum(p, SPECTRUM_NAMES_1, iterations=12, by="label", verbose=verbose)
    p = dataclasses.replace(p, fin_skin_ex=0.9, mass_fin=65.0)
    p, _, _ = tune_spectrum(p, SPECTRUM_NAMES_2, iterations=8, by="order", verbose=verbose)
    p = tune_low_modes_fe(p, iterations=3, verbose=verbose)
    return dataclasses.replace(p, wing_skin_ex=1.03 * p.wing_skin_ex)


# ---------------------------------------------------------------------------------------------
# Builder 1.2: a global tail torsion for mode 19's 3:1 internal resonance (seed paper, Fig. 12)
# ---------------------------------------------------------------------------------------------

def tail_torsion_index(labels, kinds):
    """Index of the first symmetric mode with most of its strain energy in the empennage labelled a
    horizontal-tail torsion (the tail torsion of builder 1.2), or None."""
    for i, (lab, kind) in enumerate(zip(labels, kinds)):
        if lab.startswith("horizontal tail torsion") and kind[2] == "symmetric":
            return i
    return None


def tune_tail_torsion(params, margin=0.0032, iterations=6, tol=2e-4, n_modes=45, verbose=True):
    """Secant iteration in log(htail_pitch_k) that puts the symmetric tail torsion at
    3 x f19 x (1 - margin), f19 = the frequency of mode 19 (slot 19, the symmetric wing torsion):
    slightly below three times f19, where the softening backbone of mode 19 meets it (the 3:1
    internal resonance of the paper's Fig. 12).  Returns (params, history of (k, f_tail, f19))."""
    hist = []
    logk = np.log(params.htail_pitch_k)
    for it in range(iterations):
        p = dataclasses.replace(params, htail_pitch_k=float(np.exp(logk)))
        f, labels, kinds, _, _ = labelled_spectrum(p, n_modes=n_modes)
        i = tail_torsion_index(labels, kinds)
        if i is None:
            raise NNMInputError(f"no symmetric horizontal-tail torsion below {f[-1]:.0f} Hz at k = {np.exp(logk):.4g}")
        target = 3 * f[18] * (1 - margin)
        hist.append((float(np.exp(logk)), float(f[i]), float(f[18])))
        if verbose:
            print(f"tail torsion, iteration {it}: k {np.exp(logk):.5g} N m/rad -> mode {i + 1} at {f[i]:.4f} Hz, "
                  f"target {target:.4f} Hz (f19 {f[18]:.4f} Hz)", flush=True)
        r = np.log(f[i] / target)
        if abs(r) < tol:
            return p, hist
        if len(hist) < 2:
            step = -2 * r          # f ~ sqrt(k) away from the veering with the fuselage
        else:
            (k0, f0, g0), (k1, f1, g1) = hist[-2], hist[-1]
            slope = (np.log(f1 / (3 * g1)) - np.log(f0 / (3 * g0))) / (np.log(k1) - np.log(k0))
            step = -r / slope if abs(slope) > 1e-3 else -2 * r
        logk += float(np.clip(step, -0.2, 0.2))
    return dataclasses.replace(params, htail_pitch_k=float(np.exp(logk))), hist


def tune_builder_1_2(params, verbose=True):
    """Builder 1.2 from the builder-1.1 values (see docs/aircraft.md, "Tuning", third round):

    1. the horizontal tail on pitch fittings: pitch axis at x = htail_pivot_x = 9.59 m (about the
       mass centre of the horizontal tail with its elevator, so that the symmetric tail bending does
       not pitch: it stays at 53.8 Hz), pitch stiffness htail_pitch_k;
    2. the fuselage skins' bending thickness fus_skin_tb 12 -> 11 mm: the fuselage shell mode at
       94.2 Hz (symmetric ovalisation of the cabin and the rear fuselage) drops to 92.6 Hz, out of
       the way of the tail torsion (they veer with a gap of about 2 Hz);
    3. htail_pitch_k by tune_tail_torsion: the symmetric tail torsion 0.32 % under 3 x f19."""
    p = dataclasses.replace(params, htail_pivot_x=9.59, fus_skin_tb=0.011, htail_pitch_k=1.1e6)
    p, _ = tune_tail_torsion(p, verbose=verbose)
    return p
