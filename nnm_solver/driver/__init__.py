"""Computing NNM branches: the public entry points (``api``: argument checks, the first orbit,
``iter_nnm``, ``continue_nnm``), a tongue as its own branch (``tongue_branch``: ``continue_tongue``), the ``NNMIterator`` of one branch (events
located, stop reasons), finer time steps where the error asks (``refinement``), tongue skipping
(``tongue_skip``), branch switching (``switching``) and background jobs (``jobs``).

Layer: imports ``nnm_solver.analysis``, ``results``, ``orbits``, ``stability``, ``continuation``,
``integrators``, ``model`` and the base modules.
"""
from .api import (HILL_AUTO_SIZE, METHODS, START_NONLINEARITY, NNMIterator, check_branch_arguments, check_positive,
                  continue_nnm, iter_nnm, start_amplitude)
from .tongue_branch import continue_tongue
from .jobs import Job, start_branch
from .switching import switch_branch

__all__ = ["iter_nnm", "continue_nnm", "continue_tongue", "NNMIterator", "METHODS", "HILL_AUTO_SIZE",
           "START_NONLINEARITY", "check_positive", "check_branch_arguments", "start_amplitude", "Job",
           "start_branch", "switch_branch"]
