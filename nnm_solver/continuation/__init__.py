"""The generic pseudo-arclength engine: a generator of converged points of any problem R(u) = 0 in a
balanced step norm (``engine``), and the ``EngineDriver`` that runs it points ahead of the caller
(``engine_driver``), Newton's method at a fixed parameter (``newton``) and natural-parameter stepping
(``natural``).  It knows no orbit method, no model and no stability.

Layer: imports nothing of nnm_solver but the base modules.
"""
from .engine import (REFUSE, ContinuationPoint, ContinuationSettings, CorrectorFailure, LeastSquares, correct,
                     correct_factored, pseudo_arclength, stacked, tangent, tangent_factored)
from .engine_driver import EngineDriver
from .natural import NaturalResult, natural_parameter
from .newton import NewtonResult, NewtonSettings, newton, newton_solve

__all__ = ["ContinuationSettings", "ContinuationPoint", "stacked", "LeastSquares", "tangent", "tangent_factored",
           "CorrectorFailure", "correct", "correct_factored", "pseudo_arclength", "REFUSE", "EngineDriver", "newton",
           "newton_solve", "NewtonSettings", "NewtonResult", "natural_parameter", "NaturalResult"]
