"""Computing NNM branches: the public entry points (``api``: argument checks,
``iter_nnm``, ``continue_nnm``; ``problems``: the first orbit and each method's problem), a tongue as its own branch (``tongue_branch``: ``continue_tongue``), the ``NNMIterator`` of one branch (events
located, stop reasons), finer time steps where the error asks (``refinement``), tongue skipping
(nnm_solver/backbone/, acted on by the iterator), branch switching (``switching``) and background jobs (``jobs``).

Layer: imports ``nnm_solver.backbone``, ``analysis``, ``results``, ``orbits``, ``stability``, ``continuation``,
``integrators``, ``model`` and the base modules.
"""
from .api import NNMIterator, check_branch_arguments, continue_nnm, from_keywords, iter_nnm
from .settings import Continuation, HarmonicBalance, Shooting
from .problems import HILL_AUTO_SIZE, METHODS, START_NONLINEARITY, check_positive, start_amplitude
from .tongue_branch import continue_tongue
from .jobs import Job, start_branch
from .switching import switch_branch

__all__ = ["Shooting", "HarmonicBalance", "Continuation", "from_keywords", "iter_nnm", "continue_nnm", "continue_tongue", "NNMIterator", "METHODS", "HILL_AUTO_SIZE",
           "START_NONLINEARITY", "check_positive", "check_branch_arguments", "start_amplitude", "Job",
           "start_branch", "switch_branch"]
