"""Conservative structural models  M x'' + K x + f_nl(x) = 0  (nonlinear elements: elements.py).

Units are SI throughout: M in kg (or kg m^2 for rotations), K in N/m, k3 in N/m^3,
frequencies in Hz, energies in J.  Mode numbers seen by users are 1-based (as in the
seed paper's Table 2); DOF indices are 0-based array indices.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .element_set import ElementSet
from .elements import CubicSpring, check_element  # noqa: F401 (CubicSpring: first-release import path)
from ..errors import NNMInputError
from .mesh import DisplayMesh  # noqa: F401 (first-release import path)
from .settings import MODEL

#: Largest model the shooting solver accepts (it works in the full modal basis): settings.py's MODEL.max_dense_dof
MAX_DENSE_DOF = MODEL.max_dense_dof


def _as_matrix(name, A):
    if np.iscomplexobj(A.data if sp.issparse(A) else A):
        if np.any(np.imag(A.data if sp.issparse(A) else np.asarray(A)) != 0):
            raise NNMInputError(f"{name} has complex entries; conservative models need real symmetric matrices")
        A = A.real if sp.issparse(A) else np.real(np.asarray(A))
    if sp.issparse(A):
        A = A.tocsr().astype(float)
        data = A.data
    else:
        try:
            A = np.asarray(A, dtype=float)
        except (TypeError, ValueError) as exc:
            raise NNMInputError(f"{name} must be a numeric matrix ({exc})") from None
        data = A
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise NNMInputError(f"{name} must be a non-empty square matrix, got shape {A.shape}")
    if not np.all(np.isfinite(data)):
        raise NNMInputError(f"{name} contains NaN or infinite entries; fix the matrix before building the model")
    return A


def _dense(A):
    return A.toarray() if sp.issparse(A) else A


def _check_symmetric(name, A):
    if sp.issparse(A):                 # without the dense form (a 64,000-DOF FE model's would be 33 GB)
        A = sp.csr_matrix(A)
        scale = float(np.max(np.abs(A.data))) if A.nnz else 0.0
        S = (A - A.T).tocsr()
        asym = float(np.max(np.abs(S.data))) if S.nnz else 0.0
    else:
        D = A
        scale = np.max(np.abs(D)) if D.size else 0.0
        asym = np.max(np.abs(D - D.T)) if D.size else 0.0
    if asym > 1e-8 * max(scale, 1e-300):
        raise NNMInputError(
            f"{name} is not symmetric (max |{name}-{name}^T| = {asym:.3g} vs max |{name}| = {scale:.3g}); "
            f"conservative models need symmetric matrices")


class Model:
    """Conservative model  M x'' + K x + f_nl(x) = 0,  f_nl = sum_s B_s^T g_s(B_s x)  (elements.py).

    Parameters
    ----------
    M, K : (n, n) dense arrays or scipy.sparse matrices (SI units). M symmetric positive
        definite, K symmetric positive semi-definite.  Stored as float (sparse: CSR).
    springs : list of nonlinear elements (CubicSpring, PolynomialSpring, PiecewiseLinearSpring).
        A PiecewiseLinearSpring's slope k0 is part of the linear model: ``K_linear`` = K + k0 b^T b
        (K itself is kept as given and saved as given).
    dof_labels : optional list of n strings (e.g. "node 12 uz").
    mode_labels : optional list of strings, label of linear mode k at index k-1.
    mesh : optional DisplayMesh for viewing.
    name : short model name.  info : dict of provenance strings/numbers.
    """

    def __init__(self, M, K, springs=(), *, dof_labels=None, mode_labels=None, mesh=None,
                 name="", info=None):
        M = _as_matrix("M", M)
        K = _as_matrix("K", K)
        if M.shape != K.shape:
            raise NNMInputError(f"M has shape {M.shape} but K has shape {K.shape}; they must match")
        self.n = M.shape[0]
        _check_symmetric("M", M)
        _check_symmetric("K", K)
        self.M = M
        self.K = K
        if springs is None:
            springs = ()
        elif not isinstance(springs, (list, tuple)):
            springs = [springs] if hasattr(springs, "law") else springs
        try:
            self.springs = list(springs)
        except TypeError:
            raise NNMInputError(f"springs must be a list of nonlinear elements, got {type(springs).__name__}") from None
        for i, s in enumerate(self.springs):
            check_element(i, s, self.n)
        if dof_labels is not None and len(dof_labels) != self.n:
            raise NNMInputError(f"dof_labels has {len(dof_labels)} entries, the model has {self.n} DOFs")
        self.dof_labels = None if dof_labels is None else [str(s) for s in dof_labels]
        self.mode_labels = None if mode_labels is None else [str(s) for s in mode_labels]
        if mesh is not None and mesh.displacement_map.shape[1] != self.n:
            raise NNMInputError(
                f"mesh displacement_map has {mesh.displacement_map.shape[1]} columns, the model has {self.n} DOFs")
        self.mesh = mesh
        self.name = str(name)
        self.info = dict(info or {})

    # ------------------------------------------------------------------ nonlinear elements
    @cached_property
    def elements(self):
        """The springs as an ElementSet (deformation matrix B and force laws)."""
        return ElementSet(self.springs, self.n)

    @property
    def spring_matrix(self):
        """B (n_s, n): spring deformations d = B x."""
        return self.elements.B

    @property
    def k3(self):
        """Cubic coefficients (n_s,) in N/m^3 (0 for an element without a cubic term)."""
        return np.array([s.law().get(3, 0.0) for s in self.springs], dtype=float)

    @cached_property
    def K_linear(self):
        """Stiffness of the linear model: K plus the elements' linear slopes k0 B_s^T B_s
        (PiecewiseLinearSpring); K itself when no element has one."""
        el = self.elements
        if not np.any(el.k0 != 0.0):
            return self.K
        delta = el.B.T @ (el.k0[:, None] * el.B)
        return (self.K + sp.csr_matrix(delta)).tocsr() if sp.issparse(self.K) else self.K + delta

    def nonlinear_force(self, x):
        """f_nl(x) (n,) in N for displacements x (n,) in m (or (k, n) for k states)."""
        el = self.elements
        return el.force(np.asarray(x, dtype=float) @ el.B.T) @ el.B

    def with_springs(self, springs):
        """Same linear model and metadata with other springs."""
        return Model(self.M, self.K, springs, dof_labels=self.dof_labels, mode_labels=self.mode_labels,
                     mesh=self.mesh, name=self.name, info=self.info)

    def scaled(self, factor):
        """Same model with every spring's force multiplied by ``factor``."""
        return self.with_springs([s.scaled(factor) for s in self.springs])

    # ------------------------------------------------------------------ energy
    def energy(self, x, v):
        """Total conserved energy (J): kinetic + linear potential + the elements' potential.

        x, v : (n,) displacement (m) and velocity (m/s); or (k, n) for k states at once.
        """
        x = np.asarray(x, dtype=float)
        v = np.asarray(v, dtype=float)
        if x.shape[-1] != self.n or v.shape != x.shape:
            raise NNMInputError(f"x and v must both have last dimension {self.n}, got {x.shape} and {v.shape}")
        kin = 0.5 * np.sum(v * _apply(self.M, v), axis=-1)
        pot = 0.5 * np.sum(x * _apply(self.K_linear, x), axis=-1)
        el = self.elements
        return kin + pot + np.sum(el.potential(x @ el.B.T), axis=-1)

    # ------------------------------------------------------------------ linear modes
    @cached_property
    def eigensolution(self):
        """(lam (n,), Phi (n, n)): K_linear Phi = M Phi diag(lam), Phi^T M Phi = I, ascending (rad^2/s^2).

        Computed once; shared, do not modify (``linear_modes`` returns copies)."""
        if self.n > MODEL.max_dense_dof:
            raise NNMInputError(
                f"the model has {self.n} DOFs; the NNM solver works in the full modal basis and accepts at most "
                f"{MODEL.max_dense_dof}: reduce it first (nnm_solver.craig_bampton)")
        Md, Kd = _dense(self.M), _dense(self.K_linear)
        try:
            lam, Phi = sla.eigh(Kd, Md)
        except np.linalg.LinAlgError:
            raise NNMInputError(
                "M is not positive definite (Cholesky failed); check for massless DOFs or a sign error") from None
        scale = max(np.max(np.abs(lam)), 1e-300)
        if lam[0] < -1e-9 * scale:
            k0 = " plus the piecewise-linear springs' slopes k0" if np.any(self.elements.k0 != 0.0) else ""
            raise NNMInputError(
                f"K{k0} is not positive semi-definite (eigenvalue {lam[0]:.3g} of K x = w^2 M x); "
                f"the linear structure is unstable")
        lam = np.maximum(lam, 0.0)
        # fix the sign of each shape: largest-magnitude component positive
        idx = np.argmax(np.abs(Phi), axis=0)
        Phi = Phi * np.sign(Phi[idx, np.arange(self.n)])
        lam.flags.writeable = False
        Phi.flags.writeable = False
        return lam, Phi

    def linear_modes(self):
        """Linear normal modes: (freqs_hz (n,), shapes (n, n)), ascending.

        ``shapes[:, k-1]`` is mode k, mass-normalised (shapes^T M shapes = I).
        """
        lam, Phi = self.eigensolution
        return np.sqrt(lam) / (2 * np.pi), Phi.copy()

    def check_mode(self, mode):
        """Validate a 1-based mode number for continuation; return its 0-based index."""
        if not isinstance(mode, (int, np.integer)) or isinstance(mode, bool):
            raise NNMInputError(f"mode must be an integer (1-based), got {mode!r}")
        if not 1 <= mode <= self.n:
            raise NNMInputError(f"mode {mode} is out of range: this model has modes 1..{self.n}")
        lam, _ = self.eigensolution
        bound = self._rigid_bounds.get(mode - 1)
        if bound is None:
            bound = self._rigid_bounds[mode - 1] = self._zero_frequency_bound(mode - 1)
        if lam[mode - 1] <= bound:
            raise NNMInputError(
                f"mode {mode} is a rigid-body (zero-frequency) mode: its eigenvalue {lam[mode - 1]:.2e} is within "
                f"its round-off error bound {bound:.2e} of zero (highest eigenvalue {lam[-1]:.2e}); it has no "
                f"periodic NNM: pick an elastic mode or ground the structure (a mode meant to be elastic needs a "
                f"smaller stiffness range, e.g. a coarser mesh)")
        return mode - 1

    @cached_property
    def _rigid_bounds(self):
        """The modes' _zero_frequency_bound, by 0-based index, as check_mode computed them (O(n^2) each: 1.2 ms for
        the aircraft's 548 DOFs, 3 % of a condensed-HB branch of 34 points; the matrices do not change, as for
        eigensolution)."""
        return {}

    def _zero_frequency_bound(self, index):
        """Largest eigenvalue (rad^2/s^2) mode ``index`` (0-based) can have and still be a rigid-body mode.

        The old test, lam <= 10 n eps lam_max, refused elastic modes of fine FE meshes (300 beam elements:
        lam_1 = 1.9e3 eps lam_max < 6e3 eps lam_max).  Now the larger of
        (1) 2 (eta + eps |phi|^T |K| |phi|), this mode's own error bound.  Krylov-Weinstein: with
            phi^T M phi = 1 the pencil (K, M) has an eigenvalue within eta = ||K phi - lam M phi||_{M^-1}
            (= ||Phi^T r||, M^-1 = Phi Phi^T) of lam, so a computed rigid mode has lam <= eta however the
            solver erred (a floating part of a stiff mesh: lam ~ 0.1 eps lam_max but far above eps times its
            own stiffness); eps |phi|^T |K| |phi| is what relative changes of eps in K's entries move lam by
            (first order) and covers the round-off of r itself (a singular K can give r = 0, lam ~ 1e-17);
            times 2 because the computed bound is an estimate.  A fine mesh's elastic modes have
            lam / bound ~ 1e3..1e5 and their frequencies are right to eta / (2 lam).
        (2) 10 eps lam_max, the eigen-solver's resolution (LAPACK's approximate bound is eps lam_max on every
            eigenvalue): below it the computed low spectrum is not resolved, and when elastic eigenvalues
            lie there too the rigid mode can come out as any of them with a small residual of its own
            (random spring networks with stiffness ranges 1e14: lam_1 = 1.7 eps lam_max > bound (1)).
            No factor n: that is what refused the fine meshes.
        Cost: products with K, |K| and M, and Phi^T r: O(n^2) dense, O(nnz + n^2) sparse.
        """
        lam, Phi = self.eigensolution
        eps = np.finfo(float).eps
        phi = Phi[:, index]
        K = self.K_linear
        r = K @ phi - lam[index] * (self.M @ phi)
        eta = float(np.linalg.norm(Phi.T @ r))
        a = np.abs(phi)
        s = float(a @ _abs_apply(K, a))
        return max(2.0 * (eta + eps * s), 10.0 * eps * lam[-1])

    def __repr__(self):
        return f"Model(n={self.n}, springs={len(self.springs)}{', name=' + repr(self.name) if self.name else ''})"


def _apply(A, x):
    """A x for every row x of (..., n), A dense or sparse."""
    return (A @ x.T).T if sp.issparse(A) else x @ A.T


def _abs_apply(A, x):
    """|A| x (x (n,)), A dense or sparse; a dense A is taken in row blocks (no n x n temporary)."""
    if sp.issparse(A):
        return abs(A) @ x
    out = np.empty(A.shape[0])
    for i in range(0, A.shape[0], 512):
        out[i:i + 512] = np.abs(A[i:i + 512]) @ x
    return out
