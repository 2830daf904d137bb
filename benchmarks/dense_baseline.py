"""Dense textbook baseline: NNMs by shooting + pseudo-arclength continuation.

This is a deliberately plain implementation of the method of the seed paper
(Peeters/Kerschen et al., section 3), kept in ``benchmarks/`` as the reference the
project's optimised solver (``nnm_solver``) is measured against.  It is *not*
part of the package and must not be imported by it.

Model:  M x'' + K x + f_nl(x) = 0,  f_nl = sum_s k3_s d_s^3 (dd_s/dx),
        d_s = x[dof] - x[other]   (or x[dof] for a grounded spring).

What it does, step by step (all dense, physical coordinates, state z = [x; v]):

* Time integration: Newmark average acceleration (beta = 1/4, gamma = 1/2) with
  ``steps_per_period`` steps per period, h = T / N.  Each step solves the implicit
  equilibrium M a_{k+1} + K x_{k+1} + f_nl(x_{k+1}) = 0 by Newton iterations on the
  full n x n tangent S = 4/h^2 M + K + K_nl(x) with ``np.linalg.solve``.
* Sensitivities (seed eq. 13-14): the full 2n x 2n matrix dz_k/dz0 is propagated in
  the same sweep, by differentiating the Newmark step itself, so that dz_N/dz0 is the
  exact derivative of the discrete map z0 -> z_N (not merely an O(h^2) approximation
  of the continuous monodromy).  One extra column carries dz_N/dT (derivative of the
  discrete map w.r.t. the step h = T/N, divided by N), so dH/dT is exact too.
* Shooting (eq. 4): H(z0, T) = z(T, z0) - z0, with the phase condition
  h(z0) = v0[j] = 0, j = DOF of largest |component| of the starting linear mode.
  The monodromy matrix is dz(T)/dz0; its eigenvalues are the Floquet multipliers.
* Continuation in (z0, T):
  - tangent (eq. 8): [dH/dz0 dH/dT; dh/dz0 0; p_prev^T] p = [0; 0; 1] solved with
    ``np.linalg.lstsq`` (Moore-Penrose), then normalised -- the previous tangent as
    extra row fixes the length and keeps the direction of travel;
  - predictor (eq. 7): y~ = y_j + s p_j;
  - corrector (eq. 9-10): at every iteration a fresh integration with sensitivities
    and the overdetermined system [dH/dz0 dH/dT; dh/dz0 0; p_j^T] dy = [-H; -h; 0]
    solved with ``np.linalg.lstsq``; converged when ||H|| / ||z0|| < tol (eq. 11);
  - step control: s *= 2 when the corrector converged in <= 3 iterations; on
    failure (more than 10 iterations, a non-finite / failed integration, or a point
    that lies behind the current one along the tangent) s /= 2 and retry; stop at ``energy_max``, ``max_points``, or when s falls below a
    minimum.
* Start: linear mode k (1-based), mass-normalised, scaled to a small amplitude,
  with T = 2 pi / omega_k; corrected once on the hyperplane orthogonal to the mode.

Complexity (n DOFs, N = steps_per_period):
* memory: O(n^2) -- the n x (2n+1) sensitivity blocks X, V, A and the n x n tangent
  (about 3 * 8 * n * (2n+1) bytes; 14 MB for n = 548);
* time: O(n^3) per time step (dense solve of the n x n tangent with 2n+1 right-hand
  sides plus M times an n x 2n block), so O(N n^3) per shooting iteration and
  O(iterations * N n^3) per continuation point.  Each corrector iteration pays the
  full price: nothing is reused.

Public function: :func:`dense_continue`.  Helpers :func:`newmark_shoot` (one
integration over a period, with or without sensitivities, optionally returning the
orbit) and :func:`energy` are used by the tests.
"""
from __future__ import annotations

import time

import numpy as np
import scipy.linalg


# ---------------------------------------------------------------------- model pieces
def spring_arrays(springs, n):
    """Dense B (n_s, n) with d = B x, and k3 (n_s,) from ``(dof, other_or_None, k3)`` tuples."""
    springs = list(springs)
    B = np.zeros((len(springs), n))
    k3 = np.zeros(len(springs))
    for s, (dof, other, k) in enumerate(springs):
        B[s, dof] += 1.0
        if other is not None:
            B[s, other] -= 1.0
        k3[s] = k
    return B, k3


def nonlinear_force(B, k3, x):
    """f_nl(x) = B^T (k3 d^3), d = B x."""
    d = B @ x
    return B.T @ (k3 * d ** 3)


def nonlinear_tangent(B, k3, x):
    """K_nl(x) = d f_nl / dx = B^T diag(3 k3 d^2) B  (dense n x n)."""
    d = B @ x
    return B.T @ ((3.0 * k3 * d ** 2)[:, None] * B)


def energy(M, K, B, k3, x, v):
    """Total energy (J): 1/2 v^T M v + 1/2 x^T K x + sum k3 d^4 / 4."""
    d = B @ x
    return 0.5 * v @ (M @ v) + 0.5 * x @ (K @ x) + np.sum(0.25 * k3 * d ** 4)


# ---------------------------------------------------------------------- integration
def _newmark_step(M, K, B, k3, x, v, a, h, newton_tol=1e-10, newton_maxit=30):
    """One Newmark average-acceleration step; returns x1, v1, a1 and the tangent at x1.

    Newton stops at ||dx|| <= newton_tol (||x|| + h ||v||); 1e-10 sits above the round-off
    floor of stiff FE models (~1e-12 relative on assets/paris.h5), which 1e-12 did not.
    """
    c0 = 4.0 / h ** 2
    x1 = x + h * v + 0.5 * h ** 2 * a            # predictor (constant acceleration)
    base = M @ (c0 * (x + h * v) + a)            # a1 = c0 (x1 - x - h v) - a
    scale = np.linalg.norm(x) + h * np.linalg.norm(v) + 1e-300
    for _ in range(newton_maxit):
        r = c0 * (M @ x1) - base + K @ x1 + nonlinear_force(B, k3, x1)
        S = c0 * M + K + nonlinear_tangent(B, k3, x1)
        dx = np.linalg.solve(S, -r)
        x1 = x1 + dx
        if np.linalg.norm(dx) <= newton_tol * scale:
            break
    else:
        raise RuntimeError("Newmark Newton iterations did not converge")
    a1 = c0 * (x1 - x - h * v) - a
    v1 = v + 0.5 * h * (a + a1)
    S1 = c0 * M + K + nonlinear_tangent(B, k3, x1)   # tangent at the converged state
    return x1, v1, a1, S1


def newmark_shoot(M, K, B, k3, z0, T, steps, sensitivity=True, orbit=False):
    """Integrate one period T from z0 = [x0; v0] with ``steps`` Newmark steps.

    Returns a dict with ``zT`` (2n,), and if ``sensitivity``: ``monodromy`` = dz_N/dz0
    (2n, 2n) and ``dzdT`` = dz_N/dT (2n,), both exact derivatives of the discrete
    map; if ``orbit``: ``x`` and ``v`` of shape (steps+1, n).
    """
    n = M.shape[0]
    z0 = np.asarray(z0, dtype=float)
    x, v = z0[:n].copy(), z0[n:].copy()
    h = T / steps
    c0 = 4.0 / h ** 2
    a = np.linalg.solve(M, -(K @ x + nonlinear_force(B, k3, x)))
    if sensitivity:
        # columns 0..2n-1: d/dz0 ; column 2n: d/dh
        X = np.zeros((n, 2 * n + 1))
        V = np.zeros((n, 2 * n + 1))
        X[:, :n] = np.eye(n)
        V[:, n:2 * n] = np.eye(n)
        A = np.linalg.solve(M, -(K + nonlinear_tangent(B, k3, x)) @ X)
    xs, vs = ([x.copy()], [v.copy()]) if orbit else (None, None)
    for _ in range(steps):
        x1, v1, a1, S1 = _newmark_step(M, K, B, k3, x, v, a, h)
        if sensitivity:
            # differentiate  S-equilibrium  M a1 + K x1 + f(x1) = 0  with
            # a1 = c0 (x1 - x - h v) - a,  v1 = v + h/2 (a + a1)
            rhs = M @ (c0 * (X + h * V) + A)
            rhs[:, -1] += M @ (c0 * v + (2.0 / h) * (a + a1))
            X1 = np.linalg.solve(S1, rhs)
            A1 = c0 * (X1 - X - h * V) - A
            A1[:, -1] -= c0 * v + (2.0 / h) * (a + a1)
            V1 = V + 0.5 * h * (A + A1)
            V1[:, -1] += 0.5 * (a + a1)
            X, V, A = X1, V1, A1
        x, v, a = x1, v1, a1
        if orbit:
            xs.append(x.copy())
            vs.append(v.copy())
    out = {"zT": np.concatenate([x, v])}
    if sensitivity:
        D = np.vstack([X, V])
        out["monodromy"] = D[:, :2 * n]
        out["dzdT"] = D[:, 2 * n] / steps
    if orbit:
        out["x"] = np.array(xs)
        out["v"] = np.array(vs)
    return out


# ---------------------------------------------------------------------- continuation
def _evaluate(M, K, B, k3, y, steps, j):
    """Residual [H; h] and full Jacobian (2n+1, 2n+1) at y = [z0; T]."""
    n = M.shape[0]
    z0, T = y[:-1], y[-1]
    r = newmark_shoot(M, K, B, k3, z0, T, steps, sensitivity=True)
    H = r["zT"] - z0
    J = np.zeros((2 * n + 1, 2 * n + 1))
    J[:2 * n, :2 * n] = r["monodromy"] - np.eye(2 * n)
    J[:2 * n, 2 * n] = r["dzdT"]
    J[2 * n, n + j] = 1.0                    # phase condition h = v0[j]
    F = np.concatenate([H, [z0[n + j]]])
    return F, J, r["monodromy"]


def _correct(M, K, B, k3, y_pred, p, steps, j, tol, maxit, verbose=False):
    """Pseudo-arclength corrector (eq. 9-10). Returns (y, J, monodromy, iterations) or None."""
    y = y_pred.copy()
    for it in range(maxit + 1):
        try:
            F, J, mono = _evaluate(M, K, B, k3, y, steps, j)
        except (RuntimeError, np.linalg.LinAlgError, FloatingPointError):
            return None
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(J))):
            return None
        nz = np.linalg.norm(y[:-1])
        if verbose:
            print(f"    corrector it {it}: ||H||/||z0|| = {np.linalg.norm(F[:-1]) / nz:.3e}, T = {y[-1]:.6g}",
                  flush=True)
        if np.linalg.norm(F[:-1]) < tol * nz and y[-1] > 0:
            return y, J, mono, it
        if it == maxit:
            return None
        A = np.vstack([J, p[None, :]])
        rhs = np.concatenate([-F, [0.0]])
        dy = np.linalg.lstsq(A, rhs, rcond=None)[0]
        y = y + dy
    return None


def _tangent(J, p_prev):
    """Tangent (eq. 8): null vector of J, length fixed by the extra row p_prev^T p = 1."""
    A = np.vstack([J, p_prev[None, :]])
    rhs = np.zeros(A.shape[0])
    rhs[-1] = 1.0
    p = np.linalg.lstsq(A, rhs, rcond=None)[0]
    return p / np.linalg.norm(p)


def dense_continue(M, K, springs, mode, energy_max, steps_per_period=200, tol=1e-6,
                   max_points=500, energy_start=None, step_initial=None, step_min=None,
                   step_max=None, max_corrector_iterations=10, verbose=False):
    """Continue the NNM of linear mode ``mode`` (1-based) from small energy to ``energy_max``.

    Parameters
    ----------
    M, K : (n, n) arrays (dense; sparse inputs are densified).
    springs : list of ``(dof, other_or_None, k3)``: force k3 d^3 on d = x[dof] - x[other]
        (or x[dof] when grounded).
    mode : 1-based linear mode number to start from.
    energy_max : stop after the first converged point with energy >= energy_max (J).
    steps_per_period : Newmark steps per period.
    tol : corrector tolerance on ||H|| / ||z0||  (eq. 11).
    max_points : maximum number of converged points (the starting point included).
    energy_start : energy (J) of the starting point; default: the amplitude at which the
        nonlinear potential is 1e-4 of the linear one (frequency shift ~1e-4).
    step_initial : first arclength step in (z0, T) space; default 0.2 * ||z0_start||.
    step_min : stop when the step falls below it; default 1e-6 * step_initial.
    step_max : cap on the step (default: none -- the textbook doubling is unbounded).

    Returns
    -------
    dict of numpy arrays, one entry per converged point: ``energy`` (J), ``frequency_hz``,
    ``period`` (s), ``x0`` (P, n), ``v0`` (P, n), ``floquet`` (P, 2n) complex,
    ``iterations`` (corrector iterations), ``seconds_per_point`` (wall time spent to
    obtain each point, failed attempts included); plus ``stop_reason`` (str),
    ``seconds_total`` and ``phase_dof`` (j).

    Memory O(n^2) (dense 2n x 2n sensitivity), time O(n^3) per time step; see the
    module docstring.
    """
    t_start = time.perf_counter()
    M = np.asarray(M.toarray() if hasattr(M, "toarray") else M, dtype=float)
    K = np.asarray(K.toarray() if hasattr(K, "toarray") else K, dtype=float)
    n = M.shape[0]
    B, k3 = spring_arrays(springs, n)
    steps = int(steps_per_period)

    # starting linear mode, mass-normalised, largest component positive
    lam, Phi = scipy.linalg.eigh(K, M)
    k = mode - 1
    omega = np.sqrt(lam[k])
    phi = Phi[:, k]
    j = int(np.argmax(np.abs(phi)))
    phi = phi * np.sign(phi[j])
    if energy_start is None:
        # ratio (nonlinear / linear potential) at amplitude a: a^2 sum k3 (B phi)^4 / (2 omega^2)
        c = np.sum(np.abs(k3) * (B @ phi) ** 4) / (2.0 * omega ** 2)
        amp = np.sqrt(1e-4 / c) if c > 0 else 1.0
    else:
        amp = np.sqrt(2.0 * energy_start) / omega
    y = np.concatenate([amp * phi, np.zeros(n), [2.0 * np.pi / omega]])
    p = np.concatenate([phi, np.zeros(n), [0.0]])
    p /= np.linalg.norm(p)

    pts = {key: [] for key in ("energy", "frequency_hz", "period", "x0", "v0", "floquet",
                               "iterations", "seconds_per_point")}

    def record(y, mono, its, t0):
        x0, v0, T = y[:n], y[n:2 * n], y[-1]
        E = energy(M, K, B, k3, x0, v0)
        pts["energy"].append(E)
        pts["frequency_hz"].append(1.0 / T)
        pts["period"].append(T)
        pts["x0"].append(x0.copy())
        pts["v0"].append(v0.copy())
        pts["floquet"].append(np.linalg.eigvals(mono))
        pts["iterations"].append(its)
        pts["seconds_per_point"].append(time.perf_counter() - t0)
        if verbose:
            print(f"point {len(pts['energy']):4d}  E={E:.6e}  f={1 / T:.8f} Hz  it={its}")
        return E

    # first point: correct the linear-mode guess on the hyperplane orthogonal to the mode
    t0 = time.perf_counter()
    res = _correct(M, K, B, k3, y, p, steps, j, tol, max_corrector_iterations, verbose)
    if res is None:
        raise RuntimeError("could not converge the starting point from the linear mode")
    y, J, mono, its = res
    E = record(y, mono, its, t0)
    p = _tangent(J, p)
    s = 0.2 * np.linalg.norm(y[:-1]) if step_initial is None else float(step_initial)
    s_min = 1e-6 * s if step_min is None else float(step_min)

    stop = "energy_max" if E >= energy_max else None
    t0 = time.perf_counter()
    while stop is None:
        if len(pts["energy"]) >= max_points:
            stop = "max_points"
            break
        res = _correct(M, K, B, k3, y + s * p, p, steps, j, tol, max_corrector_iterations, verbose)
        if res is not None and np.dot(res[0] - y, p) <= 0.0:
            res = None          # converged behind the current point (curved branch, long step)
        if res is None:
            s *= 0.5
            if verbose:
                print(f"  corrector failed: step halved to {s:.3e}", flush=True)
            if s < s_min:
                stop = "step_min"
            continue
        y, J, mono, its = res
        E = record(y, mono, its, t0)
        t0 = time.perf_counter()
        p = _tangent(J, p)
        if its <= 3:
            s *= 2.0
            if step_max is not None:
                s = min(s, float(step_max))
        if E >= energy_max:
            stop = "energy_max"

    out = {key: np.array(val) for key, val in pts.items()}
    out["stop_reason"] = stop
    out["seconds_total"] = time.perf_counter() - t_start
    out["phase_dof"] = j
    return out


if __name__ == "__main__":  # small demonstration: 2-DOF benchmark, NNM1
    Mx = np.eye(2)
    Kx = np.array([[2.0, -1.0], [-1.0, 2.0]])
    r = dense_continue(Mx, Kx, [(0, None, 0.5)], mode=1, energy_max=10.0, verbose=True)
    print(f"{len(r['energy'])} points, stop: {r['stop_reason']}, {r['seconds_total']:.2f} s")
