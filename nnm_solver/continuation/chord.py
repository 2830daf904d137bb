r"""The corrector's chord iterations in one compiled call, for a problem whose residual is a compiled kernel.

The pseudo-arclength corrector (corrector.py ``correct_factored``) iterates, on a factorisation [J; row^T] = Q R kept
from an earlier iterate, u <- u + du with

    [J; row^T] du = [-F(u); -row . (u - u_pred)]        (least squares, F the residual, row = w^2 p)

until the problem's relative error ||F(u)|| / ||u[:-1]|| falls below tol.  In Python each iteration costs ~25 us of
calls around a residual of ~10 us (the finiteness test, the error's two norms, the right-hand side, the solve's checks,
the update).  ``chord_iterations`` runs them (and the step from an iterate whose Jacobian was just evaluated) in one
compiled call, with the corrector's operations in its order: dot products by BLAS's ddot (numba's ``np.dot``: numpy's
``x.dot(y)`` and ``x @ y`` of 1-D arrays call the same routine), the solve by linalg.py's compiled ``_qr_solve`` on
``LeastSquares.compiled_qr`` (``LeastSquares.solve``'s own), so the iterates are the Python loop's bit for bit
(tests/test_per_point_round4.py).  It returns to the corrector wherever it decides something other than the next chord
step: the residual at an iterate that converged, is not finite, or is the last one (``max_iter``); a non-finite step
(a singular system); a step that contracted poorly (the corrector refreshes the Jacobian there).

The residual is the problem's (orbits/ holds it: e.g. condensed_kernels.chord_residual), called as a numba first-class
function: a ``ResidualKernel`` holds the native address of a compiled ``residual(u, args) -> F(u)`` (u and F 1-D float
arrays, args a tuple of the problem's constants), and the loop calls it through that address with the signature
float64[::1](float64[::1], typeof(args)), so this one loop serves every such kernel and stays in numba's disk cache
(its types are an integer and the args' tuple, not the function: a loop compiled around a given function, a closure,
is compiled again in every process; a function object as an argument costs ~8 us of typing a call).  This is the continuation layer's only Newton/chord
loop; a problem offers its kernel as ``problem.residual_kernel`` ((ResidualKernel, args) or None; engine.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import jit, numba
from .linalg import compiled_qr_solve as _qr_solve

__all__ = ["AVAILABLE", "ResidualKernel", "residual_kernel", "chord_iterations", "iterate",
           "JUDGE", "SINGULAR", "REFRESH"]

#: chord_iterations stopped at an iterate whose residual the corrector judges (converged, not finite, or the last one)
JUDGE = 0
#: the step from the iterate is not finite (a singular corrector system)
SINGULAR = 1
#: the step contracted poorly (|du_k| > refresh_ratio |du_k-1|): u is the next iterate, the Jacobian is refreshed there
REFRESH = 2

_ADDRESS = None
if numba is not None and _qr_solve is not None:
    try:   # numba's first-class functions (numba/core/types/function_type.py, numba/experimental/function_type.py)
        from numba.core import cgutils as _cgutils
        from numba.core import types as _types
        from numba.core.extending import intrinsic as _intrinsic
        from numba.experimental.function_type import _get_jit_address as _ADDRESS
    except Exception:  # pragma: no cover - another numba version: the corrector iterates in Python
        _ADDRESS = None

#: the compiled chord iterations can run (numba with its LAPACK and first-class functions)
AVAILABLE = _ADDRESS is not None


class ResidualKernel:
    """A compiled residual ``kernel(u, args) -> F(u)`` (u, F 1-D float arrays) compiled for the signature
    float64[::1](float64[::1], typeof(args)): ``address`` is its native entry point (numba's own calling convention, so
    an exception it raises reaches the caller as from any compiled call), which ``chord_iterations`` calls as a
    first-class function of that signature (``_residual_at``).  An integer argument:
    numba types it without Python (a function object as the argument costs ~8 us of typing and unboxing a call).
    Pickled as the kernel and its signature (the address is this process's: taken again when unpickled)."""

    def __init__(self, kernel, args=None, signature=None):
        if signature is None:
            arr = _types.float64[::1]
            signature = arr(arr, numba.typeof(args))
        kernel.compile(signature.args)
        self.signature = signature
        self.address = _ADDRESS(kernel, signature)
        self.kernel = kernel                   # (kept alive: the address is into its compiled code)

    def __reduce__(self):
        return _residual_kernel_of, (self.kernel, self.signature)


def _residual_kernel_of(kernel, signature):
    """The ResidualKernel of ``kernel`` for ``signature`` in this process (unpickling)."""
    return ResidualKernel(kernel, signature=signature)


if AVAILABLE:
    @_intrinsic
    def _residual_at(typingctx, address, args):
        """The first-class function float64[::1](float64[::1], typeof(args)) at the native address (a
        ResidualKernel's, made for this args type)."""
        arr = _types.float64[::1]
        function = _types.FunctionType(arr(arr, args))

        def codegen(context, builder, signature, llargs):
            value = _cgutils.create_struct_proxy(function)(context, builder)
            value.jit_addr = builder.inttoptr(llargs[0], _cgutils.voidptr_t)      # (called by numba's convention)
            return value._getvalue()
        return function(address, args), codegen
else:  # pragma: no cover
    _residual_at = None


_KERNELS = {}


def _layout(x):
    """What numba's type of an argument depends on: an array's without numba's typeof (~0.3 ms for a condensed
    problem's 18 constants, ~500 Python calls: a problem is made per branch and per larger basis), a scalar's type."""
    if isinstance(x, np.ndarray):
        f = x.flags
        return x.dtype.str, x.ndim, f.c_contiguous, f.f_contiguous, f.writeable, f.aligned
    if isinstance(x, tuple):
        return tuple(_layout(y) for y in x)
    return numba.typeof(x)


def residual_kernel(kernel, args):
    """(ResidualKernel, args) for a compiled ``kernel(u, args)`` and its constants args (a tuple of arrays and
    numbers), one ResidualKernel per kernel and argument types (kept), or None where the chord iterations are not
    compiled (the corrector iterates itself)."""
    if not AVAILABLE:
        return None
    key = (kernel,) + tuple(_layout(x) for x in args)
    found = _KERNELS.get(key)
    if found is None:
        found = _KERNELS[key] = ResidualKernel(kernel, args)
    return found, args


@jit
def chord_iterations(u, u_pred, row, Q, R, last_norm, it, tol, max_iter, refresh_ratio, fresh, address, args):
    """(u, F(u), it, last_norm, code): chord iterations of the corrector from the iterate u (number ``it``), with the
    factorisation Q R of [J; row^T] and the last step's norm ``last_norm`` (NaN: none to compare with), until a code
    (module docstring): JUDGE with the residual at u, SINGULAR with the residual at u, REFRESH with u the next iterate
    (its residual not yet evaluated: the one returned is the previous iterate's).  fresh : the residual at u, evaluated
    with the Jacobian that Q R factorises (its step is not tested for contraction), or an empty array.  address, args:
    the problem's residual kernel (ResidualKernel.address) and its constants; the relative error is ||F|| / ||u[:-1]||."""
    residual = _residual_at(address, args)
    n = u.shape[0] - 1
    first = fresh.shape[0] > 0
    while True:
        if first:
            res = fresh
        else:
            res = residual(u, args)
        for i in range(res.shape[0]):
            if not np.isfinite(res[i]):
                return u, res, it, last_norm, JUDGE
        x = u[:n]
        err = math.sqrt(np.dot(res, res)) / max(math.sqrt(np.dot(x, x)), 1e-300)
        if err < tol or it == max_iter:
            return u, res, it, last_norm, JUDGE
        rhs = np.empty(res.shape[0] + 1)
        for i in range(res.shape[0]):
            rhs[i] = -res[i]
        rhs[-1] = -np.dot(row, u - u_pred)
        du = _qr_solve(Q, R, rhs)
        nrm = math.sqrt(np.dot(du, du))
        if not math.isfinite(nrm):
            return u, res, it, last_norm, SINGULAR
        poor = not first and nrm > refresh_ratio * last_norm          # (False against NaN: no earlier step)
        first = False
        last_norm = nrm
        u = u + du
        it += 1
        if poor:
            return u, res, it, last_norm, REFRESH


_NONE = np.zeros(0)          # (no residual of a fresh Jacobian given)


def iterate(kernel, u, u_pred, row, factor, last_norm, it, tol, settings, fresh=None):
    """(u, r, it, last_norm, code) of ``chord_iterations`` with the problem's ``residual_kernel`` (kernel, args) and the
    corrector's LeastSquares ``factor``, or None where the factorisation has no compiled solve (the corrector iterates
    itself).  fresh : the residual at u evaluated with the factorised Jacobian, or None."""
    qr = factor.compiled_qr
    if qr is None:
        return None
    return chord_iterations(u, u_pred, row, *qr, math.nan if last_norm is None else last_norm, it, tol,
                            settings.max_iter, settings.refresh_ratio, _NONE if fresh is None else fresh,
                            kernel[0].address, kernel[1])
