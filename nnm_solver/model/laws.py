"""Force laws of the nonlinear elements as numbers: the smoothed kinks of piecewise-linear springs
(numpy, for the model's energy, harmonic balance and Hill) and the numba kernels that evaluate the
element table (powers, coefficients, kinks) of ``elements.ElementSet`` inside the time integrator.

Table: g_s(d) = sum_p coefficients[s, p] d^powers[p] + sum_j dk [r_w(d - b) - r_w(-d - b)], with
kinks[s, j] = (dk, b, w[, side]): a slope change dk (N/m) at |d| = b (m) smoothed over a width w (m)
by the softplus ramp r_w(x) = w log(1 + exp(x / w)).  The optional fourth column ``side`` makes a
kink one-sided (asymmetric springs, tension != compression): side = 0 (or a 3-column table) both
signs of d, the odd pair above; side = +1 only d = +b, the term dk r_w(d - b); side = -1 only
d = -b, the term -dk r_w(-d - b).  In every case the slope of g grows by dk as |d| passes b on the
kink's side.  The kernels are inlined into their callers (jit.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import jit_inline

__all__ = ["law_force", "law_force_tangent", "law_scalar", "softplus", "sigmoid", "ramp_integral"]


def softplus(x, w):
    """r_w(x) = w log(1 + exp(x / w)), evaluated without overflow."""
    u = x / w
    return np.maximum(x, 0.0) + w * np.log1p(np.exp(-np.abs(u)))


def sigmoid(x, w):
    """r_w'(x) = 1 / (1 + exp(-x / w))."""
    u = x / w
    e = np.exp(-np.abs(u))
    return np.where(u >= 0, 1.0 / (1.0 + e), e / (1.0 + e))


def ramp_integral(x, w):
    """R(x) = int_{-inf}^x r_w = -w^2 Li2(-exp(x / w)) (Li2(z) = scipy.special.spence(1 - z)); for x > 0
    the reflection Li2(-e^u) = -pi^2/6 - u^2/2 - Li2(-e^-u) keeps the argument bounded."""
    from scipy.special import spence

    u = np.asarray(x / w, dtype=float)
    e = np.exp(-np.abs(u))
    neg = -w * w * spence(1.0 + e)                                    # u <= 0
    pos = 0.5 * x * x + w * w * (np.pi ** 2 / 6.0 + spence(1.0 + e))  # u > 0
    return np.where(u > 0, pos, neg)


@jit_inline
def _ipow(x, p):
    """x ** p for an integer p >= 0 by repeated squaring (faster than pow for the small powers here)."""
    r = 1.0
    while p > 0:
        if p & 1:
            r *= x
        x *= x
        p >>= 1
    return r


@jit_inline
def _softplus1(x, w):
    """r_w(x) = w log(1 + exp(x / w)) for one number (numba kernel)."""
    if x > 0.0:
        return x + w * math.log1p(math.exp(-x / w))
    return w * math.log1p(math.exp(x / w))


@jit_inline
def _sigmoid1(x, w):
    """r_w'(x) for one number (numba kernel)."""
    if x > 0.0:
        return 1.0 / (1.0 + math.exp(-x / w))
    e = math.exp(x / w)
    return e / (1.0 + e)


@jit_inline
def law_force(d, powers, coeffs, kinks):
    """g(d) (n_s,) of the element laws (numba kernel; see ElementSet)."""
    ns = d.shape[0]
    g = np.empty(ns)
    for s in range(ns):
        g[s] = law_scalar(d[s], s, powers, coeffs, kinks)[0]
    return g


@jit_inline
def law_scalar(x, s, powers, coeffs, kinks):
    """(g_s(x), g_s'(x)) of element s at the deformation x, as two numbers (numba kernel)."""
    sided = kinks.shape[2] > 3
    acc = 0.0
    dacc = 0.0
    for j in range(powers.shape[0]):
        c = coeffs[s, j]
        if c != 0.0:
            p = powers[j]
            xp1 = x ** (p - 1)
            acc += c * xp1 * x
            dacc += p * c * xp1
    for j in range(kinks.shape[1]):
        dk = kinks[s, j, 0]
        if dk != 0.0:
            b = kinks[s, j, 1]
            w = kinks[s, j, 2]
            side = kinks[s, j, 3] if sided else 0.0
            if side >= 0.0:
                acc += dk * _softplus1(x - b, w)
                dacc += dk * _sigmoid1(x - b, w)
            if side <= 0.0:
                acc -= dk * _softplus1(-x - b, w)
                dacc += dk * _sigmoid1(-x - b, w)
    return acc, dacc


@jit_inline
def law_force_tangent(d, powers, coeffs, kinks):
    """(g(d), g'(d)) (n_s,) each, of the element laws (numba kernel)."""
    ns = d.shape[0]
    g = np.empty(ns)
    t = np.empty(ns)
    for s in range(ns):
        g[s], t[s] = law_scalar(d[s], s, powers, coeffs, kinks)
    return g, t
