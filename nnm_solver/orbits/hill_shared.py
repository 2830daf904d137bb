r"""What the Hill routes beyond the dense one share (hill.py explains the routes): the exp(i k theta) form of the
harmonic basis, the orbit's setup (its velocity: the trivial pair's eigenvector; the touched modes; the classes of
exponents to find, one per touched mode but the continued one), the overlaps of vectors with the velocity and its
copies, the dense route's rule for the kept exponents (central_pool: the smallest |mean harmonic|) and for the
trivial pair (_trivial_pair: the two exponents nearest 0 on the velocity)."""
from __future__ import annotations

import functools
import threading
import weakref

import numpy as np

from .settings import ORBITS

__all__ = ["CENTROID_MAX", "TRIVIAL_COS", "central_pool", "distinct", "velocity_overlaps", "warm_start",
           "set_warm_start", "forget_warm_starts"]

#: an alias of settings.py's ORBITS.centroid_max (the code reads that)
CENTROID_MAX = ORBITS.centroid_max


#: an alias of settings.py's ORBITS.trivial_cos (the code reads that)
TRIVIAL_COS = ORBITS.trivial_cos


def _exp_transform(H):
    """T (N_b, N_b) complex: real-basis coefficients a = T c of the exp(i k theta) coefficients c, k = -H..H
    (column k + H); the real basis is 1, cos 1, sin 1, ..., cos H, sin H."""
    nb = 2 * H + 1
    T = np.zeros((nb, nb), dtype=complex)
    T[0, H] = 1.0
    for h in range(1, H + 1):
        T[2 * h - 1, H + h] = T[2 * h - 1, H - h] = 1.0       # a_cos = c_h + c_-h
        T[2 * h, H + h], T[2 * h, H - h] = 1j, -1j           # a_sin = i (c_h - c_-h)
    return T


@functools.lru_cache(maxsize=16)
def _exp_inverse(H):
    """T^-1 (N_b, N_b) of _exp_transform(H): the exp(i k theta) coefficients of the real-basis ones (read-only)."""
    Tinv = np.linalg.inv(_exp_transform(H))
    Tinv.setflags(write=False)
    return Tinv


def _setup(problem, A, w, bp):
    """What the structured and secular routes share: (T^-1, omega2 / w^2, touched modes tm, the averaged stiffness's
    (beta2, Vbar), the classes to find (every touched class but the continued one), the untouched modes' exact
    exponents, the orbit's velocity in exp(i k theta) (N_b, n))."""
    s, n = problem.sys, problem.n
    H = bp.harmonics
    nb = 2 * H + 1
    Tinv = _exp_inverse(H)
    omega2 = s.omega2 / w ** 2
    Bq = s.Bq
    touched = np.linalg.norm(Bq, axis=0) > 0
    # the orbit's velocity in exp(i k theta): the trivial pair's eigenvector (dq/dtheta = sum i k c_k e^{ik theta})
    Ah = np.zeros((nb, n))
    orbit = problem.basis
    for j in np.flatnonzero(orbit.h <= H):
        hj = orbit.h[j]
        row = 0 if hj == 0 else (2 * hj if orbit.sine[j] else 2 * hj - 1)
        Ah[row] += A[j]
    vel = (1j * np.arange(-H, H + 1))[:, None] * (Tinv @ Ah)                  # (N_b, n)
    return Tinv, omega2, touched, Ah, vel


def _classes(omega2, Bq, Cexp, touched, Ah, H):
    """(tm, beta2, Vbar, classes, nu_exact): the touched modes, the averaged stiffness Omega^2 + Bq^T <g'> Bq on
    them (eigenvalues, vectors), the classes to find (all but the continued one's: the trivial pair), and the
    untouched modes' exponents +- i omega_j (exact)."""
    Gbar = Cexp[:, H, H].real                                                 # <g'> (n_s,) / omega^2
    tm = np.flatnonzero(touched)
    Kbar = np.diag(omega2[tm]) + (Bq[:, tm].T * Gbar) @ Bq[:, tm]
    beta2, Vbar = np.linalg.eigh(Kbar)
    shape = np.abs(Ah[1, tm]) + np.abs(Ah[2, tm])                             # the fundamental's shape
    own = int(np.argmax(np.abs(Vbar.T @ shape))) if len(tm) else -1
    classes = [j for j in range(len(tm)) if j != own]
    nu_exact = []
    for j in np.flatnonzero(~touched):                                        # +- i omega_j, exact
        nu_exact += [1j * np.sqrt(omega2[j]), -1j * np.sqrt(omega2[j])]
    return tm, beta2, Vbar, classes, nu_exact


@functools.lru_cache(maxsize=16)
def _offsets(nb):
    """D (N_b^2, 2 N_b - 1): column p + N_b - 1 of G.ravel() @ D sums the entries G[k, k - p] of an (N_b, N_b)
    matrix (its p-th diagonal: vectors moved by p harmonics against each other)."""
    k, l = np.divmod(np.arange(nb * nb), nb)
    D = np.zeros((nb * nb, 2 * nb - 1))
    D[np.arange(nb * nb), k - l + nb - 1] = 1.0
    return D


def velocity_overlaps(x1, vel):
    """|cos| (..., 2 N_b - 1) between vectors x1 (..., N_b, n) and the orbit's velocity vel (N_b, n) moved by p
    harmonics (column p + N_b - 1, p = -2H..2H): the trivial pair's eigenvector and its copies."""
    nb = vel.shape[0]
    D = _offsets(nb)
    G = x1 @ np.conj(vel).T                                                  # <vel_l, x1_k>
    ip = np.abs(G.reshape(G.shape[:-2] + (nb * nb,)) @ D)                   # sum_k <vel_{k-p}, x1_k>
    vk = (np.abs(vel) ** 2).sum(axis=1)
    nv = np.sqrt(np.tile(vk, nb) @ D)                                        # |vel| over the overlapping k
    nrm = np.sqrt((x1.real ** 2 + x1.imag ** 2).sum(axis=(-2, -1)))[..., None]
    return np.where(nv > 0, ip / np.maximum(nv * nrm, 1e-300), 0.0)


def _trivial_pair(cos, theta):
    """The trivial pair among converged eigenpairs, e.g. a structured block's Ritz pairs (|cos| (b,) of the vectors
    with the velocity, exponents theta (b,)): the two exponents nearest 0 among the vectors near the velocity
    (|cos| > 0.5), as the dense route sets the two multipliers nearest +1 to 1.  Not the two vectors nearest the
    velocity: next to an energy fold the
    pair that passes through +1 there joins the trivial pair's Jordan chain, its eigenvectors turn towards the
    velocity too (a four-fold exponent 0 at the fold), and the vectors alone no longer tell the pairs apart (NLvib's
    beam, example 09, just past its 5:1 tongue's energy maximum: a real pair +-3.7e-7 kept as trivial, the orbit
    called stable).  Fewer than two when fewer vectors are near the velocity (the caller checks)."""
    out = np.zeros(len(cos), dtype=bool)
    near = np.flatnonzero(cos > 0.5)
    two = near[np.argsort(np.abs(theta[near]), kind="stable")[:2]]
    out[two] = True
    return out


def central_pool(nu, cc, need, tie=0.0):
    """The ``need`` kept exponents among the eigenvalues nu (units of omega) whose eigenvectors have |mean harmonic|
    cc, as the dense route keeps them: with their conjugates and Hamiltonian partners -conj, -nu (exact eigenvalues
    too: the Hill matrix is that of a gyroscopic system), ordered by |mean harmonic|, repeats dropped.  None when
    fewer than ``need`` are central (|mean harmonic| <= ORBITS.centroid_max), or when the next one's |mean harmonic| is
    within ``tie`` of the last kept one's (an ordering too close to call)."""
    nu = np.concatenate([nu, np.conj(nu), -np.conj(nu), -nu])
    cc = np.tile(cc, 4)
    order = np.argsort(cc, kind="stable")
    nu, cc = nu[order], cc[order]
    first = distinct(nu, 1e-8)                      # not a repeat of an earlier (more central) one
    pool, pool_c = nu[first], cc[first]
    if len(pool) < need or pool_c[need - 1] > ORBITS.centroid_max:
        return None
    if tie > 0 and len(pool) > need and pool_c[need] - pool_c[need - 1] < tie:
        return None
    return np.array(pool[:need])


def distinct(z, rtol):
    """Mask of the points of z (complex) that are not a repeat, within rtol relative to max(1, |z|), of an earlier
    one."""
    same = np.abs(z[:, None] - z[None, :]) <= rtol * np.maximum(1.0, np.abs(z))[None, :]
    return ~np.any(np.tril(same, -1), axis=1)


#: the structured and secular Hill routes' warm starts, per orbit problem: {problem: {route: value}}, kept beside the
#: problem (weakly: they go with it) rather than hung on it; the next orbit of the same problem starts from them
_WARM = weakref.WeakKeyDictionary()
_WARM_LOCK = threading.Lock()


def warm_start(problem, route):
    """The last warm start that ``route`` ("structured" / "secular") stored for this problem, or None."""
    with _WARM_LOCK:
        return _WARM.get(problem, {}).get(route)


def set_warm_start(problem, route, value):
    with _WARM_LOCK:
        _WARM.setdefault(problem, {})[route] = value


def forget_warm_starts(problem):
    """Cold starts from now on for this problem's next orbit (tests compare cold and warm)."""
    with _WARM_LOCK:
        _WARM.pop(problem, None)
