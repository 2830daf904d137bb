"""Small finite-element kit: 3D Timoshenko beams, flat MITC4 shells, springs, rigid links; geometrically
nonlinear (von Karman) beams and plates.

6 DOF per node (ux, uy, uz, rx, ry, rz) for FEModel; SI units.  See FEModel for assembly and
docs/geometric.md for the von Karman structures.
"""
from .assembly import DOF_NAMES, FEModel
from .beam import beam_matrices
from .geometric import GeometricStructure, StaticSolution, internal_force, static_solve, tangent_stiffness
from .rom import ReducedModel, condensed_rom, constrained_static
from .rom_static import rom_from_static_solutions, static_load_cases
from .shell import shell_matrices
from .solve import modes
from .vk_beam import beam_structure, von_karman_beam
from .vk_plate import plate_structure, von_karman_plate

__all__ = ["DOF_NAMES", "FEModel", "beam_matrices", "shell_matrices", "modes", "von_karman_beam",
           "beam_structure", "GeometricStructure", "StaticSolution", "internal_force", "tangent_stiffness",
           "static_solve", "von_karman_plate", "plate_structure",
           "condensed_rom", "ReducedModel", "constrained_static", "static_load_cases",
           "rom_from_static_solutions"]
