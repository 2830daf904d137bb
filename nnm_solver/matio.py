"""Moved to ``nnm_solver.importers.matlab`` (v5 and v7.3 .mat files); kept so old imports work."""
from .files.importers.matlab import load_mat_model, read_mat

__all__ = ["load_mat_model", "read_mat"]
