"""From the test lab to the model: identification of nonlinear connections from measured signals.

The restoring force surface of a connection from two accelerations (``rfs``, the seed's §4.1.3, eq. 20-22,
Fig. 7), force laws fitted to it and handed to a model as elements (``rfs_fit``), and the factor on a
model's nonlinear coefficients that best matches a measured backbone (``backbone_fit``).

Layer: imports ``nnm_solver.files`` and the layers below it (the driver computes the backbones).
"""
from .backbone_fit import BackboneFit, fit_backbone, scale_nonlinear
from .frf_peaks import frf_peaks
from .rfs import RestoringForceSurface, rfs
from .rfs_fit import LAWS, FittedLaw

__all__ = ["rfs", "RestoringForceSurface", "FittedLaw", "LAWS", "fit_backbone", "BackboneFit", "scale_nonlinear",
           "frf_peaks"]
