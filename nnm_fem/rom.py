r"""Reduced-order models of geometrically nonlinear structures from nonlinear static solutions (issue 55).

``condensed_rom(structure, modes, scale)`` builds a model in the modal coordinates q of a few linear
modes Phi (mass-normalised, ``modes`` 1-based), q'' + Lambda q + grad V(q) = 0, whose potential V is the
strain energy of the full model *condensed* on those modes:

    U_c(q) = min { U(x) : Phi^T M x = q },      grad U_c(q) = mu,   f(x*) = M Phi mu,

the equilibrium x*(q) of the full model under modal forces M Phi mu (the implicit condensation of
Hollkamp & Gordon; the applied-displacement STEP of Muravyov & Rizzi with every other DOF relaxed).  The
in-plane (membrane) DOFs and the other modes follow q statically, which is what makes the beam or plate
soften from the stiff "u = 0" energy to the stretched one; the neglected in-plane inertia is small when
the in-plane frequencies are far above the retained ones.  For a flat von Karman structure whose modes
are purely transverse U_c is even and, when the other transverse modes are not excited, exactly quartic.

Each x*(q) is one non-intrusive static solution (``constrained_static``: only f(x), K_t(x) and M are used,
so another FE code's static solver could supply them).  The samples (STEP's combinations: each mode at
+-scale and +-scale/2, pairs, triples and quadruples at +-scale) give gradients mu - Lambda q; a least-squares
fit of the cubic and quartic terms of V (the quadratic and cubic stiffness tensors) makes the ROM
conservative by construction.  The same samples fit the expansion x*(q) = Phi q + sum_{i<=j} Y_ij q_i q_j
(the membrane expansion), so the physical motion, in-plane part included, can be shown.

Convergence check (docs/geometric.md): the ROM's backbone (or its coefficients) should not move when a mode
is added or when ``scale`` is halved; ``fit_residual`` says how far U_c is from a quartic at that scale.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from itertools import combinations, combinations_with_replacement, product

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from nnm_solver.errors import NNMInputError
from .geometric import _structure
from .polynomial import force_law

__all__ = ["ReducedModel", "condensed_rom", "constrained_static", "membrane_static", "linear_modes",
           "fit_condensed", "step_samples"]


def linear_modes(structure, modes):
    """(omega^2 (m,), Phi (n, m) mass-normalised) of the 1-based ``modes`` of the structure's M, K."""
    s = _structure(structure)
    modes = [int(k) for k in np.atleast_1d(modes)]
    if not modes or min(modes) < 1 or max(modes) > s.n or len(set(modes)) != len(modes):
        raise NNMInputError(f"modes must be distinct 1-based mode numbers in 1..{s.n}, got {modes}")
    lam, Phi = sla.eigh(s.K.toarray(), s.M.toarray(), subset_by_index=[0, max(modes) - 1])
    Phi = Phi[:, [k - 1 for k in modes]]
    Phi = Phi * np.sign(Phi[np.argmax(np.abs(Phi), axis=0), np.arange(len(modes))])
    return lam[[k - 1 for k in modes]], Phi


def constrained_static(structure, Phi, q, *, steps=4, tol=1e-10, max_iter=30):
    """x*(q) with Phi^T M x = q and f(x) = M Phi mu: (x (n,), mu (m,), converged).  Newton on the bordered
    system over ``steps`` equal increments of q, from x = 0."""
    s = _structure(structure)
    MPhi = np.asarray(s.M @ Phi)
    m = Phi.shape[1]
    x, mu, ok = np.zeros(s.n), np.zeros(m), True
    fscale = max(np.linalg.norm(s.K @ (Phi @ q)), 1e-300)
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        x = x + Phi @ (t * q - MPhi.T @ x)
        for _ in range(max_iter):
            r = np.concatenate([s.internal_force(x) - MPhi @ mu, MPhi.T @ x - t * q])
            if np.linalg.norm(r[:s.n]) <= tol * fscale and np.linalg.norm(r[s.n:]) <= tol * np.linalg.norm(q):
                break
            J = sp.bmat([[s.tangent(x), sp.csr_matrix(-MPhi)], [sp.csr_matrix(MPhi.T), None]]).tocsc()
            step = sp.linalg.spsolve(J, r)
            x, mu = x - step[:s.n], mu - step[s.n:]
        else:
            ok = False
    return x, mu, ok


def membrane_static(structure, Phi, q, membrane, *, tol=1e-10, max_iter=30):
    """x*(q) with the non-membrane DOFs at Phi q and the ``membrane`` DOFs in equilibrium, f(x)[membrane] = 0:
    (x (n,), mu = Phi^T f(x) (m,), converged).  For a von Karman structure f[membrane] is linear in the
    membrane DOFs and one Newton step solves it."""
    s = _structure(structure)
    P = np.asarray(membrane, dtype=np.int64)
    x = Phi @ q
    x[P] = 0.0
    fscale = max(np.linalg.norm(s.K @ (Phi @ q)), 1e-300)
    for _ in range(max_iter):
        r = s.internal_force(x)[P]
        if np.linalg.norm(r) <= tol * fscale:
            return x, Phi.T @ s.internal_force(x), True
        x[P] -= sp.linalg.spsolve(s.tangent(x)[P][:, P].tocsc(), r)
    return x, Phi.T @ s.internal_force(x), False


def _potential_monomials(m):
    """Exponents (K, m) of every monomial of degree 3 and 4 in m variables."""
    out = []
    for deg in (3, 4):
        for c in combinations_with_replacement(range(m), deg):
            out.append(np.bincount(c, minlength=m))
    return np.array(out, dtype=np.int64)


def step_samples(m):
    """STEP-like sample points in scaled modal coordinates (each |q_i| <= 1): each mode at +-1 and +-1/2, pairs,
    triples and quadruples at +-1 (S, m)."""
    pts = []
    for i in range(m):
        for a in (1.0, -1.0, 0.5, -0.5):
            p = np.zeros(m)
            p[i] = a
            pts.append(p)
    for k in (2, 3, 4):
        for idx in combinations(range(m), k):
            for signs in product((1.0, -1.0), repeat=k):
                if k > 2 and signs[0] < 0:
                    continue                      # the potential's odd part is fixed by the others' signs
                p = np.zeros(m)
                p[list(idx)] = signs
                pts.append(p)
    return np.array(pts)


@dataclass
class ReducedModel:
    """A condensed ROM in the modal coordinates q of the full structure's ``modes`` (1-based).

    omega2 (m,) rad^2/s^2; exponents (n_z, m), coefficients (n_z, m): the fitted modal force grad V(q) =
    coefficients^T z(q) (NLvib's convention); Phi (n, m) the basis; Y (n, P) the quadratic (membrane)
    expansion on the pairs ``pairs`` (P, 2): x ~ Phi q + Y (q_i q_j); scale (m) the largest displacement of
    each mode in the samples; fit_residual the relative least-squares misfit of the modal forces; samples the
    number of static solutions.  ``model`` is the nnm.Model (M = I, K = diag(omega2), one PolynomialStiffness,
    the structure's display mesh times Phi, so the viewer shows the linear part of the physical motion).
    """

    omega2: np.ndarray
    exponents: np.ndarray
    coefficients: np.ndarray
    Phi: np.ndarray
    modes: list
    Y: np.ndarray
    pairs: np.ndarray
    scale: float
    fit_residual: float
    samples: int
    mesh: object = None
    name: str = "ROM"
    info: dict = None

    def force(self, q):
        """Nonlinear modal force grad V(q) (m,) for q (m,)."""
        q = np.asarray(q, dtype=float)
        return np.prod(q[None, :] ** self.exponents, axis=1) @ self.coefficients

    def potential(self, q):
        """Nonlinear modal potential V(q) (J) (each term of degree p + 1 = 3 or 4: Euler's theorem)."""
        q = np.asarray(q, dtype=float)
        z = np.prod(q[None, :] ** self.exponents, axis=1)
        return float(np.sum(z * (self.coefficients @ q) / (self.exponents.sum(axis=1) + 1)))

    def expand(self, q):
        """Physical displacements x (n,) (or (k, n)) of modal coordinates q (m,) (or (k, m)), membrane expansion
        included."""
        q = np.asarray(q, dtype=float)
        quad = q[..., self.pairs[:, 0]] * q[..., self.pairs[:, 1]]
        return q @ self.Phi.T + quad @ self.Y.T

    @cached_property
    def model(self):
        import nnm_solver as nnm
        m = len(self.omega2)
        return nnm.Model(np.eye(m), np.diag(self.omega2), [nnm.PolynomialStiffness(self.exponents, self.coefficients)],
                         dof_labels=[f"mode {k} q" for k in self.modes], mesh=self.mesh, name=self.name,
                         info=dict(self.info or {}))


def fit_condensed(omega2, Phi, q, mu, x, q0):
    """The condensed potential's fit from static samples: q (S, m) modal coordinates, mu (S, m) the condensed
    energy's gradient there (the modal load Phi^T F of the equilibrium; linear part omega2 q included), x (S, n)
    the physical equilibria, q0 (m,) the modal scale of the samples.  Least squares on the cubic and quartic
    monomials of V in the scaled coordinates q / q0 (conditioning), the membrane expansion x - Phi q on the
    products q_i q_j.  Returns (exponents F, coefficients C: grad V = C^T z(q); Y, pairs; the relative misfit of
    the modal forces)."""
    m = Phi.shape[1]
    E = _potential_monomials(m)
    pairs = np.array([(i, j) for i in range(m) for j in range(i, m)])
    rows, rhs, quad = [], [], []
    for qk, muk in zip(q, mu):
        p = qk / q0
        for j in range(m):              # gradient of each monomial of the scaled potential V(p) at p: dV/dp_j
            e = E.copy()
            coef = e[:, j].astype(float)
            e[:, j] = np.maximum(e[:, j] - 1, 0)
            rows.append(coef * np.prod(p[None, :] ** e, axis=1))
            rhs.append((muk[j] - omega2[j] * qk[j]) * q0[j])       # dV/dp_j = q0_j dV/dq_j
        quad.append(p[pairs[:, 0]] * p[pairs[:, 1]])
    A, bvec = np.array(rows), np.array(rhs)
    if np.linalg.matrix_rank(A) < A.shape[1]:
        raise NNMInputError(f"{len(q)} static solutions in {m} modes do not determine the {A.shape[1]} cubic and "
                            f"quartic terms of the potential: add load cases combining the modes (the STEP set: "
                            f"each mode at +-1 and +-1/2, pairs, triples and quadruples at +-1 of the scale)")
    c, *_ = np.linalg.lstsq(A, bvec, rcond=None)
    resid = float(np.linalg.norm(A @ c - bvec) / max(np.linalg.norm(bvec), 1e-300))
    c_q = c / np.prod(q0[None, :] ** E, axis=1)                  # back to unscaled q
    Yp, *_ = np.linalg.lstsq(np.array(quad), np.asarray(x) - np.asarray(q) @ Phi.T, rcond=None)
    Y = Yp.T / (q0[pairs[:, 0]] * q0[pairs[:, 1]])
    keep = np.abs(c) > 1e-12 * np.max(np.abs(c))
    F, C = force_law(E[keep], c_q[keep])
    return F, C, Y, pairs, resid


def condensed_rom(structure, modes, scale, *, relax="membrane", steps=4):
    """Condensed ROM of a GeometricStructure (or an nnm.Model built from one) on its 1-based linear ``modes``.

    scale (m): each mode is sampled up to a largest physical displacement ``scale`` (typically the amplitudes
    of interest, e.g. one or two thicknesses).  relax: "membrane" (default) relaxes the in-plane DOFs only
    (labels ending " ux" / " uy"; the transverse DOFs follow Phi q exactly, so a flat von Karman structure's
    condensed energy is exactly quartic and the fit does not depend on ``scale``); "all" relaxes every other DOF,
    the other modes included (implicit condensation: the fit then depends on ``scale``).  Returns a ReducedModel.
    """
    s = _structure(structure)
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise NNMInputError(f"scale must be a positive displacement in m, got {scale}")
    if relax not in ("membrane", "all"):
        raise NNMInputError(f"relax must be 'membrane' or 'all', got {relax!r}")
    membrane = [k for k, lab in enumerate(s.labels) if lab.endswith((" ux", " uy"))]
    if relax == "membrane" and not membrane:
        raise NNMInputError("relax='membrane' needs in-plane DOFs (labels ending ' ux' or ' uy'); use relax='all'")
    omega2, Phi = linear_modes(s, modes)
    m = Phi.shape[1]
    trans = [k for k, lab in enumerate(s.labels) if lab.endswith((" ux", " uy", " uz"))] or list(range(s.n))
    q0 = scale / np.max(np.abs(Phi[trans]), axis=0)              # modal amplitude: largest translation = scale
    pts = step_samples(m)
    qs, mus, xs = [], [], []
    for p in pts:
        q = p * q0
        if relax == "membrane":
            x, mu, ok = membrane_static(s, Phi, q, membrane)
        else:
            x, mu, ok = constrained_static(s, Phi, q, steps=steps)
        if not ok:
            raise NNMInputError(f"condensed_rom: no static solution at modal amplitudes {q} (scale {scale} m); "
                                f"lower the scale")
        qs.append(q)
        mus.append(mu)
        xs.append(x)
    F, C, Y, pairs, resid = fit_condensed(omega2, Phi, np.array(qs), np.array(mus), np.array(xs), q0)
    mesh = None
    if s.mesh is not None:
        import nnm_solver as nnm
        mesh = nnm.DisplayMesh(s.mesh.vertices, s.mesh.faces, np.asarray(s.mesh.displacement_map @ Phi),
                               part_ids=s.mesh.part_ids, part_names=list(s.mesh.part_names))
    modes = [int(k) for k in np.atleast_1d(modes)]
    info = dict(s.info, rom=f"condensed (STEP samples, {relax} relaxed)", rom_modes=",".join(map(str, modes)),
                rom_scale_m=scale, rom_fit_residual=resid)
    return ReducedModel(omega2, F, C, Phi, modes, Y, pairs, scale, resid, len(pts), mesh,
                        f"ROM of {s.name}" if s.name else "ROM", info)
