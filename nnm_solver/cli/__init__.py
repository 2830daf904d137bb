"""The command line: ``nnm-solve`` (``solve``: a branch, a sweep, the list of modes) and its
``import`` / ``export`` subcommands (``exchange``).  ``python -m nnm_solver.cli`` is ``nnm-solve``.

Layer: the top; imports any layer of nnm_solver.
"""
from .modes import list_modes
from .outputs import SHIPPED_EXAMPLES
from .solve import accuracy_line, main

__all__ = ["main", "list_modes", "accuracy_line", "SHIPPED_EXAMPLES"]
