"""nnm_solver: nonlinear normal modes by shooting and pseudo-arclength continuation.

Public API (SI units, frequencies in Hz, energies in J, 1-based mode numbers)::

    import nnm_solver as nnm
    model = nnm.Model(M, K, springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    branch = nnm.continue_nnm(model, mode=1, energy_max=1e2)      # method="shooting" or "hb"
    for point in nnm.iter_nnm(model, 1, 1e2): ...                 # the same, one Point at a time
    job = nnm.start_branch(model, 1, 1e2)                         # in a background thread
    nnm.save_branch("file.h5", branch); nnm.load_branches("file.h5")
"""
from .errors import NNMFileError, NNMInputError
from .model import (CubicSpring, DisplayMesh, ElementSet, ModalSystem, Model, PiecewiseLinearSpring,
                    PolynomialSpring, PolynomialStiffness, Variant, craig_bampton, cubic_scaling, mac, modal_system, variant_grid)
from .integrators import INTEGRATORS
from .stability import STABILITY_TOL
from .results import STATUSES, Branch, HarmonicBalanceSettings, MethodSettings, Point, ShootingSettings, plot_atlas, plot_fep
from .fourier import fourier_amplitudes, fourier_coefficients
from .driver import Continuation, HarmonicBalance, Shooting
from .backbone import Follow, Skip
from .results import TongueRecord
from .driver import METHODS, Job, NNMIterator, continue_nnm, continue_tongue, iter_nnm, start_branch, switch_branch
from .files import (Backbone, amplitude_backbone, export_backbone_csv, export_csv, export_uff, export_uff_orbit,
                    load_branches, load_extra, load_model, save_branch, save_model, store_ritz_basis)
from .files.importers import DofMap, import_model
from .files.importers.matlab import load_mat_model
from .files.importers.toml import load_toml_model
from .files.importers.ansys import load_full_model
from .sweeps import SweepProgress, load_sweep, load_sweep_file, sweep
from . import analysis, hb
from .analysis import (HarmonicContent, Tongue, describe_orbit, dominant_harmonic, find_tongues, mac_orbits,
                       mass_mac, orbit_shape)
from ._moved import MOVED as _MOVED
from ._moved import install as _install_moved
from .results.forced import ForcedResponse
from .analysis.energy_balance import energy_balance
from .driver.forced import forced_response
from .files.forced_io import load_forced_responses, save_forced_response
from .identification import BackboneFit, FittedLaw, RestoringForceSurface, fit_backbone, rfs

_install_moved()


def __getattr__(name):
    """The modules' old places as attributes (``nnm_solver.io``, ``nnm_solver.importers``): _moved.py."""
    if name in _MOVED:
        import importlib
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    # models
    "Model", "CubicSpring", "PolynomialSpring", "PiecewiseLinearSpring", "PolynomialStiffness", "ElementSet", "DisplayMesh", "ModalSystem", "modal_system", "craig_bampton", "mac",
    # computing branches
    "continue_nnm", "iter_nnm", "NNMIterator", "METHODS", "start_branch", "Job", "hb", "switch_branch",
    "continue_tongue", "INTEGRATORS", "Shooting", "HarmonicBalance", "Continuation", "Follow", "Skip", "TongueRecord",
    # sweeps and atlases (Dask, imported only when a sweep runs)
    "sweep", "Variant", "variant_grid", "load_sweep_file", "load_sweep", "SweepProgress", "plot_atlas",
    # results
    "Branch", "Point", "STATUSES", "MethodSettings", "ShootingSettings", "HarmonicBalanceSettings",
    "STABILITY_TOL", "cubic_scaling", "fourier_coefficients", "fourier_amplitudes",
    # files and plots
    "load_model", "save_model", "load_branches", "save_branch", "load_extra", "load_mat_model", "plot_fep",
    "store_ritz_basis",
    # importing FE models, exporting to the test lab (docs/import.md)
    "import_model", "load_toml_model", "load_full_model", "DofMap",
    "export_csv", "export_uff", "export_uff_orbit", "amplitude_backbone", "export_backbone_csv", "Backbone",
    # reading branches
    "analysis", "HarmonicContent", "Tongue", "describe_orbit", "dominant_harmonic", "find_tongues",
    "mac_orbits", "mass_mac", "orbit_shape",
    # errors
    "NNMInputError", "NNMFileError",
    # forced responses (docs/forced.md)
    "forced_response", "energy_balance", "ForcedResponse", "save_forced_response", "load_forced_responses",
    # identification from test data (docs/testlab.md)
    "rfs", "RestoringForceSurface", "FittedLaw", "fit_backbone", "BackboneFit",
]

__version__ = "0.1.0"
