r"""Reduced-order models from another FE code's nonlinear static solutions (implicit condensation and expansion).

A structure modelled in another FE code (Abaqus, Nastran SOL 106, Code_Aster, ...) needs only its mass matrix M,
a few mass-normalised linear modes Phi (n, m) with their omega^2, and nonlinear static solutions under modal
loads, the non-intrusive route of Hollkamp & Gordon's implicit condensation:

1. ``static_load_cases(M, Phi, omega2, scale)``: the load cases F_s = M Phi (omega^2 q_s) (N), the STEP set of
   combinations q_s (each mode at +-1 and +-1/2 of its modal scale, pairs, triples and quadruples at +-1), each
   mode's scale giving a linear response whose largest displacement is ``scale`` (m);
2. the FE code solves K x + f_nl(x) = F_s for each (a geometrically nonlinear static step), giving x_s (n,);
3. ``rom_from_static_solutions(M, Phi, omega2, loads, displacements)``: with q_s = Phi^T M x_s and the condensed
   energy's gradient Phi^T F_s (the load lies in the span of M Phi, so x_s minimises the strain energy with its
   modal coordinates held at q_s: grad U_c(q_s) = Phi^T F_s), the cubic and quartic terms of the potential V(q) =
   U_c(q) - q^T Omega^2 q / 2 are fitted (rom.fit_condensed, the same fit as ``condensed_rom``), and x_s - Phi q_s
   on the products q_i q_j (the expansion: the in-plane motion the viewer shows).

The in-plane DOFs and the modes left out follow q statically; check the ROM by adding a mode and halving the
scale (docs/geometric.md); ``fit_residual`` says how far U_c is from a quartic over the samples.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from nnm_solver.errors import NNMInputError
from .rom import ReducedModel, fit_condensed, step_samples

__all__ = ["static_load_cases", "rom_from_static_solutions"]


def _basis(M, Phi, omega2):
    M = M.tocsr() if sp.issparse(M) else np.asarray(M, dtype=float)
    Phi = np.asarray(Phi, dtype=float)
    Phi = Phi[:, None] if Phi.ndim == 1 else Phi
    omega2 = np.atleast_1d(np.asarray(omega2, dtype=float))
    n, m = Phi.shape
    if M.shape != (n, n) or omega2.shape != (m,):
        raise NNMInputError(f"M must be ({n}, {n}) and omega2 ({m},) for modes Phi of shape {Phi.shape}; got M "
                            f"{M.shape}, omega2 {omega2.shape}")
    if not (np.all(np.isfinite(Phi)) and np.all(np.isfinite(omega2)) and np.all(omega2 > 0)):
        raise NNMInputError("Phi and omega2 must be finite, omega2 > 0 (rad^2/s^2)")
    G = Phi.T @ (M @ Phi)
    if np.max(np.abs(G - np.eye(m))) > 1e-6:
        raise NNMInputError(f"the modes Phi must be mass-normalised (Phi^T M Phi = I; off by "
                            f"{np.max(np.abs(G - np.eye(m))):.2g})")
    return M, Phi, omega2


def static_load_cases(M, Phi, omega2, scale):
    """The static load cases (S, n) (N) to run in the FE code: F_s = M Phi (omega^2 q_s), q_s the STEP set in units
    of each mode's modal scale q0 = scale / max |Phi_i| (a linear response whose largest displacement is ``scale``,
    m).  Run each in a geometrically nonlinear static analysis and pass the displacements, in the same order, to
    ``rom_from_static_solutions``."""
    M, Phi, omega2 = _basis(M, Phi, omega2)
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise NNMInputError(f"scale must be a positive displacement in m, got {scale}")
    q0 = scale / np.max(np.abs(Phi), axis=0)
    q = step_samples(Phi.shape[1]) * q0
    return np.asarray((M @ (Phi @ (omega2[:, None] * q.T)))).T


def rom_from_static_solutions(M, Phi, omega2, loads, displacements, *, modes=None, mesh=None, name="ROM",
                              info=None):
    """A ReducedModel from static solutions: loads (S, n) N applied to the full structure (in the span of M Phi, as
    ``static_load_cases`` makes them) and displacements (S, n) m, its nonlinear equilibria, in the DOFs of M and Phi
    (n, m) (mass-normalised modes; omega2 (m,) rad^2/s^2).  modes: their 1-based numbers (for the labels; default
    1..m); mesh: an nnm.DisplayMesh whose displacement map is in the ROM's modal coordinates (or None)."""
    M, Phi, omega2 = _basis(M, Phi, omega2)
    n, m = Phi.shape
    F = np.atleast_2d(np.asarray(loads, dtype=float))
    X = np.atleast_2d(np.asarray(displacements, dtype=float))
    if F.shape != X.shape or F.shape[1] != n:
        raise NNMInputError(f"loads and displacements must both be (cases, {n}); got {F.shape} and {X.shape}")
    if not (np.all(np.isfinite(F)) and np.all(np.isfinite(X))):
        raise NNMInputError("loads and displacements must be finite (a static step that did not converge?)")
    mu = F @ Phi                                              # Phi^T F_s: the condensed energy's gradient
    off = F - np.asarray(M @ (Phi @ mu.T)).T                  # the loads' part outside the span of M Phi
    bad = np.linalg.norm(off, axis=1) > 1e-6 * np.maximum(np.linalg.norm(F, axis=1), 1e-300)
    if bad.any():
        raise NNMInputError(f"load case {int(np.flatnonzero(bad)[0]) + 1} is not a modal load M Phi f (the implicit "
                            f"condensation needs loads in the span of M Phi: static_load_cases makes them)")
    q = np.asarray(M @ X.T).T @ Phi                           # Phi^T M x_s
    q0 = np.max(np.abs(q), axis=0)
    if np.any(q0 <= 0):
        raise NNMInputError("every mode must be loaded in some case (its modal coordinate is zero in all)")
    Fx, C, Y, pairs, resid = fit_condensed(omega2, Phi, q, mu, X, q0)
    modes = list(range(1, m + 1)) if modes is None else [int(k) for k in np.atleast_1d(modes)]
    if len(modes) != m:
        raise NNMInputError(f"modes names {len(modes)} modes for {m} columns of Phi")
    info = dict(info or {}, rom="condensed (external static solutions)", rom_modes=",".join(map(str, modes)),
                rom_fit_residual=resid)
    return ReducedModel(omega2, Fx, C, Phi, modes, Y, pairs, float(np.max(np.abs(X))), resid, len(F), mesh, name,
                        info)
