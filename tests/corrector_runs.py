"""Shared by the per-point tests (rounds 4 and 5): one corrector run as its result or its failure's message, and the
comparison of two such runs bit for bit (the point, Jacobian, iteration count and error, or the same message)."""
import numpy as np

from nnm_solver.continuation.engine import CorrectorFailure, correct_factored


def corrected(prob, u_pred, p, settings, tol, w, start=None, refresh=True):
    """correct_factored's result, or the message of its CorrectorFailure."""
    try:
        return correct_factored(prob, u_pred, p, settings, tol, w, start=start, refresh=refresh)
    except CorrectorFailure as exc:
        return str(exc)


def same_run(a, b):
    """Two ``corrected`` results equal bit for bit (arrays equal, None where the other is None), or the same message."""
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return all((x is None and y is None) or (x is not None and y is not None and
                                            (np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y))
               for x, y in zip(a[:4], b[:4]))
