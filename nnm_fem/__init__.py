"""Small finite-element kit: 3D Timoshenko beams, flat MITC4 shells, springs, rigid links.

6 DOF per node (ux, uy, uz, rx, ry, rz); SI units.  See FEModel for assembly.
"""
from .assembly import DOF_NAMES, FEModel
from .beam import beam_matrices
from .shell import shell_matrices
from .solve import modes

__all__ = ["DOF_NAMES", "FEModel", "beam_matrices", "shell_matrices", "modes"]
