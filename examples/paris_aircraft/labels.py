"""Mode labels of the aircraft found from the model: strain-energy split by part, the
motion of characteristic sections, and mirror symmetry about the plane y = 0."""
from __future__ import annotations

import numpy as np

_S = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])  # mirror y -> -y on (u, rotation pseudovector)
_ORD = {1: "1st", 2: "2nd", 3: "3rd"}


def category_energies(ac, Phi):
    """Strain-energy fractions (n_cat, n_modes) per label category and the category names."""
    cats = sorted(set(ac.categories.values()))
    if not hasattr(ac, "_kparts"):
        ac._kparts = {part: ac.fe.part_stiffness(part) for part in ac.categories}
    E = np.zeros((len(cats), Phi.shape[1]))
    for part, Kp in ac._kparts.items():
        E[cats.index(ac.categories[part])] += 0.5 * np.einsum("ik,ik->k", Phi, Kp @ Phi)
    return E / np.maximum(E.sum(axis=0), 1e-300), cats


def symmetry(ac, Phi):
    """Mirror-symmetry score per mode in [-1, 1]: +1 symmetric, -1 anti-symmetric about y = 0."""
    ok = np.flatnonzero(ac.mirror >= 0)
    m = ac.M.diagonal().reshape(-1, 6)[ok]
    U = Phi.reshape(-1, 6, Phi.shape[1])
    a = U[ok]
    b = U[ac.mirror[ok]] * _S[None, :, None]
    num = np.einsum("nd,ndk,ndk->k", m, a, b)
    den = np.einsum("nd,ndk,ndk->k", m, a, a)
    return num / np.maximum(den, 1e-300)


def _section_motion(X, U, axis_t, axis_l):
    """Mean translation along axis_t, slope of that translation along x (times half chord)
    and mean translation along x, for section nodes X (n, 3) with translations U (n, 3)."""
    x = X[:, 0] - X[:, 0].mean()
    ut = U[:, axis_t]
    slope = np.sum(x * (ut - ut.mean())) / max(np.sum(x * x), 1e-300)
    half = 0.5 * (X[:, 0].max() - X[:, 0].min())
    return abs(ut.mean()), abs(slope * half), abs(U[:, 0].mean())


def _rigid_fit(X, U):
    """Least-squares rigid motion (tx, ty, tz, rx, ry, rz) of points X with translations U."""
    c = X.mean(axis=0)
    r = X - c
    n = len(X)
    A = np.zeros((3 * n, 6))
    for d in range(3):
        A[d::3, d] = 1.0
    # u = t + rot x r
    A[0::3, 4], A[0::3, 5] = r[:, 2], -r[:, 1]
    A[1::3, 3], A[1::3, 5] = -r[:, 2], r[:, 0]
    A[2::3, 3], A[2::3, 4] = r[:, 1], -r[:, 0]
    sol, *_ = np.linalg.lstsq(A, U.ravel(), rcond=None)
    return sol


def _hinge_share(ac, Phi):
    """Share of the control-surface category energy held by its hinge springs (per surface)."""
    out = {}
    for cs in ("aileron", "elevator", "rudder"):
        Kh = ac._kparts[f"hinge {cs}"]
        eh = 0.5 * np.einsum("ik,ik->k", Phi, Kh @ Phi)
        tot = sum(0.5 * np.einsum("ik,ik->k", Phi, Kp @ Phi) for part, Kp in ac._kparts.items()
                  if ac.categories[part] == cs)
        out[cs] = eh / np.maximum(tot, 1e-300)
    return out


def label_modes(ac, Phi):
    """One label per mode (columns of Phi, full FE DOFs), e.g. 'wing torsion 1 (anti-symmetric)'."""
    frac, cats = category_energies(ac, Phi)
    sym = symmetry(ac, Phi)
    X = ac.fe.nodes
    hs = _hinge_share(ac, Phi)
    labels, counts, kinds = [], {}, []
    for k in range(Phi.shape[1]):
        U = Phi[:, k].reshape(-1, 6)[:, :3]
        e = dict(zip(cats, frac[:, k]))
        s = sym[k]
        stxt = "symmetric" if s > 0.5 else "anti-symmetric" if s < -0.5 else "unsymmetric"
        top = max(e, key=e.get)
        emp = e.get("fin", 0.0) + e.get("htail", 0.0)
        if top not in ("fin", "htail") and emp > e[top]:
            top = "fin" if e.get("fin", 0.0) > e.get("htail", 0.0) else "htail"
        if top == "gear":
            fus = ac.sections["fuselage"]
            t = _rigid_fit(X[fus], U[fus])
            amp = np.abs(t) * np.array([1, 1, 1, 3, 3, 3])
            name = ["fore-aft", "lateral", "heave", "roll", "pitch", "yaw"][int(np.argmax(amp))]
            part, kind = "gear suspension", name
        elif top in ("wing", "htail"):
            tips = [ac.sections[f"{top} tip R"], ac.sections[f"{top} tip L"]]
            m = np.mean([_section_motion(X[t], U[t], 2, 0) for t in tips], axis=0)
            kind = ["bending", "torsion", "in-plane bending"][int(np.argmax(m))]
            part = "wing" if top == "wing" else "horizontal tail"
        elif top == "fin":
            t = ac.sections["fin tip"]
            m = _section_motion(X[t], U[t], 1, 0)
            part, kind = "fin", ["bending", "torsion", "fore-aft bending"][int(np.argmax(m))]
        elif top in ("aileron", "elevator", "rudder"):
            part = top
            kind = "rotation" if hs[top][k] > 0.3 else "bending"
        elif top == "tank":
            part = "tip tanks"
            t = ac.sections["tank R"]
            r = np.abs(_rigid_fit(X[t], U[t])) * np.array([1, 1, 1, 1.5, 1.5, 1.5])
            kind = ["fore-aft", "lateral", "heave", "roll", "pitch", "yaw"][int(np.argmax(r))]
        else:
            fus = ac.sections["fuselage"]
            xs = X[fus, 0]
            tail = fus[xs > xs.max() - 1.5]
            u = np.abs(U[tail].mean(axis=0))
            part, kind = "fuselage", ["axial", "lateral bending", "vertical bending"][int(np.argmax(u))]
        key = (part, kind, stxt if part not in ("gear suspension",) else "")
        counts[key] = counts.get(key, 0) + 1
        if part == "gear suspension":
            lab = f"gear suspension: {kind}"
        elif kind == "rotation":
            lab = f"{part} rotation ({stxt})"
        else:
            lab = f"{part} {kind} {counts[key]} ({stxt})"
        labels.append(lab)
        tail = e.get("fin", 0.0) + e.get("htail", 0.0)
        kinds.append((part, kind, stxt, counts[key], top, e[top], s, tail))
    return labels, kinds


def find_mode(kinds, part, kind, stxt=None, nth=1):
    """Index of the nth mode of a (part, kind[, symmetry]) class, or None."""
    c = 0
    for i, (p, k, s, *_) in enumerate(kinds):
        if p == part and k == kind and (stxt is None or s == stxt):
            c += 1
            if c == nth:
                return i
    return None
