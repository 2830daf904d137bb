"""nnm_solver: nonlinear normal modes by shooting and pseudo-arclength continuation.

Public API (SI units, frequencies in Hz, energies in J, 1-based mode numbers)::

    import nnm_solver as nnm
    model = nnm.Model(M, K, springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    branch = nnm.continue_nnm(model, mode=1, energy_max=1e2)      # or nnm.start_branch(...) in a thread
    nnm.save_branch("file.h5", branch); nnm.load_branches("file.h5")
"""
from .errors import NNMFileError, NNMInputError
from .model import CubicSpring, DisplayMesh, Model
from .io import load_branches, load_extra, load_model, save_branch, save_model
from .matio import load_mat_model
from .branch import Branch
from .floquet import STABILITY_TOL
from .nnm_continuation import continue_nnm
from .jobs import Job, start_branch
from .plotting import plot_fep
from .reduction import craig_bampton, mac
from . import analysis, hb
from .analysis import (HarmonicContent, Tongue, describe_orbit, dominant_harmonic, find_tongues, mac_orbits,
                       orbit_shape)

__version__ = "0.1.0"
