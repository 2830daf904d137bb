r"""Krein signatures of the collision coordinates c of a symmetric reversible orbit, from a few eigenvectors.

The half-period map A = [[A11, A12], [A21, A22]] of a symmetric reversible orbit is symplectic and reversible, so
A21 = dv(T/2)/dq0 is symmetric and A21 A11 = A11^T A21: A11 is self-adjoint in the indefinite form <x, y> = x^H A21 y.
An eigenvalue c = cos(theta) of A11 in (-1, 1) with eigenvector x belongs to the eigenvalue lambda = c + i sin(theta)
(sin > 0) of A with eigenvector z = [x; -i A21 x / sin(theta)], whose symplectic form -i z^H J z equals
-2 x^H A21 x / sin(theta): the **Krein signature** of c is kappa = -sign(x^H A21 x) (the monodromy's multiplier
mu = lambda^2 has the same eigenvector z, and the same signature).  A linear mode of frequency w has A21 = -w sin(w
T/2) on its coordinate: kappa = sign(sin(w T / 2)), so the modes' coordinates c = cos(w T / 2) carry both signs.

Two real c of the same signature cannot leave the real axis where they meet (A11 restricted to their span is
self-adjoint in a definite form: they pass through each other); a Krein collision (a torus bifurcation) needs two
adjacent c of opposite signatures.  Eigenvectors of nearly equal c (the aircraft's symmetric pairs, 1e-15 to 1e-10
apart) are any basis of their invariant subspace, so the signatures of such a cluster are the inertia of the
Hermitian matrix X^H A21 X on it (Sylvester: the same for every basis): all one sign, or mixed (undetermined, 0: the
pair can collide).  The form comes from ShootingStability.krein_form (one half-period sweep along the vectors), the
vectors from ShootingStability.local_eigenpairs (shift-invert Arnoldi near a shift: the few coordinates near a
collision, not the full spectrum).
"""
from __future__ import annotations

import numpy as np

__all__ = ["signatures", "opposite_neighbours"]


def signatures(c, F, cluster=1e-6, imag_tol=1e-12):
    """Krein signature (+1, -1; 0 where undetermined) of each eigenvalue c (k,) of A11, from F = X^H A21 X (k, k) of
    its eigenvectors X (ShootingStability.krein_form).

    Real c (|Im c| <= imag_tol) within ``cluster`` of each other form one cluster (consecutive in sorted order):
    its signature is minus the sign of F's restriction to it when that is definite, else 0 (mixed: the cluster can
    hold a colliding pair).  A complex c (a pair off the axis, after a collision) has no signature (0): its form
    vanishes.  A form smaller than 1e-12 of F's largest entry counts as zero (c at +-1, where sin(theta) -> 0)."""
    c = np.asarray(c, dtype=complex)
    F = np.asarray(F, dtype=complex)
    out = np.zeros(len(c), dtype=int)
    real = np.flatnonzero(np.abs(c.imag) <= imag_tol)
    if not len(real):
        return out
    small = 1e-12 * max(float(np.max(np.abs(F))), np.finfo(float).tiny)
    order = real[np.argsort(c.real[real], kind="stable")]
    groups, group = [], [order[0]]
    for i, j in zip(order[:-1], order[1:]):
        if c.real[j] - c.real[i] <= cluster:
            group.append(j)
        else:
            groups.append(group)
            group = [j]
    groups.append(group)
    for g in groups:
        w = np.linalg.eigvalsh(F[np.ix_(g, g)])
        if np.all(w > small):
            out[g] = -1
        elif np.all(w < -small):
            out[g] = 1
    return out


def opposite_neighbours(c, kappa, imag_tol=1e-12):
    """Pairs (i, j) of eigenvalues c that can collide: neighbours on the real axis (consecutive in sorted order of
    the real c) whose signatures kappa (``signatures``) are opposite or undetermined (0), as (i, j, gap) with
    c[i] < c[j] and gap = c[j] - c[i], nearest first.  Same-signature neighbours pass through each other."""
    c = np.asarray(c, dtype=complex)
    real = np.flatnonzero(np.abs(c.imag) <= imag_tol)
    order = real[np.argsort(c.real[real], kind="stable")]
    pairs = [(int(i), int(j), float(c.real[j] - c.real[i])) for i, j in zip(order[:-1], order[1:])
             if kappa[i] * kappa[j] <= 0]
    return sorted(pairs, key=lambda t: t[2])
