"""The model layer's settings: every threshold and size of model/, written once, with its reason.

``MODEL`` is the instance the code reads (``MODEL.max_dense_dof``); the names of earlier releases (``MAX_DENSE_DOF``,
``PWL_EPS``, ``BLOCK``, ``LANCZOS_TOL``, ``CUTOFF_FACTOR``) stay importable as aliases of its fields.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ModelSettings", "MODEL"]


@dataclass(frozen=True)
class ModelSettings:
    """Thresholds and sizes of the model layer."""

    #: largest model the shooting solver accepts (it works in the full modal basis); above it, the Ritz basis
    #: (ritz.py) takes its modes by the block Lanczos instead of the dense eigensolution
    max_dense_dof: int = 6000
    #: default regularisation of PiecewiseLinearSpring: kink width eps * d1
    pwl_eps: float = 1e-3
    #: relative asymmetry of the tangent dg/dd above which a PolynomialStiffness is refused as non-conservative
    symmetry_tol: float = 1e-8
    #: block size of the block Lanczos (modes_below): a sparse Cholesky solve of 32 right-hand sides costs about a
    #: quarter of 32 single solves (the factor is read once), and the re-orthogonalisation is matrix-matrix work
    lanczos_block: int = 32
    #: convergence of a Ritz pair of K^-1 M: residual / value below this (what ARPACK's tol means)
    lanczos_tol: float = 1e-10
    #: the block Lanczos keeps at most this many vectors (and at most lanczos_bytes of them: n x 8 bytes each; 1.5 GB
    #: is 2,900 vectors of the 64,446-DOF aircraft, which needs ~2,000) before ritz_basis falls back to ARPACK's
    #: restarted Lanczos (lowest_modes)
    lanczos_max_vectors: int = 4096
    lanczos_bytes: float = 1.5e9
    #: the Ritz basis keeps the modes below cutoff_factor x (highest harmonic) x (the followed mode's frequency)
    cutoff_factor: float = 2.0
    #: SparseSolver refines its solves (x += solve(b - A x)) when the componentwise backward error of a probe solve
    #: is above this (CHOLMOD's is ~1e-13 on the aircraft's K, SuperLU's 1e-7), with at most this many steps
    solve_backward_error: float = 1e-12
    solve_refinement_steps: int = 2


#: the model layer's settings (the defaults above, written once)
MODEL = ModelSettings()
