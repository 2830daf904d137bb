"""The time-stepping kernels' settings: every threshold of integrators/, written once, with its reason.

``KERNELS`` is the instance the code reads (``KERNELS.volterra_block``).  The compiled kernels (newmark.py,
general.py) read ``newton_max`` and ``newton_rtol`` as compile-time constants (numba freezes a module global when it
compiles; they bind them to module names from ``KERNELS``); numba's disk cache is keyed on each kernel's own source
file, so after changing them here touch newmark.py, step_newton.py, general.py and general_band.py (jit.py says so
for laws.py).
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["KernelSettings", "KERNELS"]


@dataclass(frozen=True)
class KernelSettings:
    """Thresholds and sizes of the time-stepping kernels."""

    #: Newton iterations of an implicit step (the n_s spring deformations, or the n modal coordinates of the
    #: general kernels) before the step is judged on its residual alone
    newton_max: int = 40
    #: an implicit step's Newton iteration has converged when its residual is within this of its scale (round-off)
    newton_rtol: float = 1e-13
    #: a shifted solve by Woodbury is refused (the caller takes another shift or route) when a diagonal entry lies
    #: within this distance (relative to the largest) of the shift: the identity's two terms would then cancel
    near_diagonal: float = 1e-10
    #: time steps per block of the Volterra solve: one block (one triangular solve) for the usual 200 steps per
    #: period, bounded memory (O((block n_s)^2)) and (N / block)^2 / 2 matrix products for long sweeps
    volterra_block: int = 128
    #: Gauss step constants kept for reuse (gauss.py): a shooting iterate's residual, its Jacobian and its point's
    #: stability maps use one step h (1/3 to 1/2 of the constructions of a run on the aircraft; ~10 % of its time)
    gauss_constants_kept: int = 4
    #: the general Gauss kernel solves its stages in physical coordinates by band LU (general_band.py) from this many
    #: DOFs on (a complete modal basis; below it the dense modal LU is as fast: measured in benchmarks/README.md)
    band_min_dofs: int = 24
    #: ... and while the tangent's half-bandwidth w (DOFs renumbered by reverse Cuthill-McKee) is at most this
    #: fraction of n (the band LU's O(n s^3 w^2) against the dense O((s n)^3) and its solves' O(s^2 n^2 w) against
    #: O(s^2 n^3))
    band_max_fraction: float = 0.2

    def band_solver(self, n, w):
        """True when a Gauss step on n DOFs whose tangent has the half-bandwidth w is solved as one band matrix."""
        return n >= self.band_min_dofs and w <= self.band_max_fraction * n


#: the kernels' settings (the defaults above, written once)
KERNELS = KernelSettings()
