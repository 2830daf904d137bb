"""nnm_solver: nonlinear normal modes by shooting and pseudo-arclength continuation.

Public API (SI units, frequencies in Hz, energies in J, 1-based mode numbers)::

    import nnm_solver as nnm
    model = nnm.Model(M, K, springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    branch = nnm.continue_nnm(model, mode=1, energy_max=1e2)
"""
from .errors import NNMFileError, NNMInputError
from .model import CubicSpring, DisplayMesh, Model
from .io import load_extra, load_model, save_model

__version__ = "0.1.0"
from .branch import Branch, mac
from .nnm_continuation import continue_nnm
from .jobs import Job, start_branch
from .io import load_branches, save_branch
from .floquet import STABILITY_TOL
from .matio import load_mat_model
from .plotting import plot_fep
from . import hb
