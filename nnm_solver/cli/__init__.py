"""The command line: ``nnm-solve`` (``solve``: a branch, a sweep, the list of modes) and its
``import`` / ``export`` subcommands (``exchange``).  ``python -m nnm_solver.cli`` is ``nnm-solve``.

Layer: the top; imports any layer of nnm_solver.
"""
from .solve import SHIPPED_EXAMPLES, accuracy_line, list_modes, main

__all__ = ["main", "list_modes", "accuracy_line", "SHIPPED_EXAMPLES"]
