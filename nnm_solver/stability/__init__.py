"""Floquet stability along a branch, for any orbit method: multipliers sorted and deflated, the
stability flag and its test functions (``floquet``), the branch between two points parametrised by
the arclength (``locator``), Krein collisions (``krein``) and the Krein signatures of a reversible orbit's
collision coordinates (``krein_signature``), and the located, classified events (``events``: folds, branch points,
period doublings, tori).

Layer: imports ``nnm_solver.continuation`` and the base modules; it sees orbit problems only
through their protocol (``orbits/__init__.py``).
"""
from .floquet import STABILITY_TOL, deflate, is_stable, sort_multipliers

__all__ = ["STABILITY_TOL", "deflate", "is_stable", "sort_multipliers"]
