"""Independent reference models and continuous-time Floquet references (helpers, not tests).

Nothing here uses the solver's integrators, its modal system or ``nnm_fem``: the beam is assembled
directly in numpy, and orbits, monodromy matrices and multipliers are computed with
``scipy.integrate.solve_ivp`` (DOP853) on the state equations  x' = v,  M v' = -K x - f_nl(x)
and their variational equations.  These are references for the *continuous-time* orbits; the
solver's Newmark orbits differ from them by the O(steps_per_period^-2) discretisation error.

Only ``nnm_solver.Model`` and ``nnm_solver.CubicSpring`` are required (the helpers also work with an
older ``nnm_solver`` whose models have no ``elements``): ``cantilever_beam`` builds the model,
the other functions read ``model.M``, ``model.K``, ``model.nonlinear_force`` and the elements'
selection matrix and tangent (``model.elements``, or ``model.spring_matrix`` and ``model.k3`` of
cubic springs in older versions).

    from reference_models import cantilever_beam, monodromy_ivp, multipliers_ivp, periodic_orbit_ivp
    beam = cantilever_beam()                       # hardening steel strip, tip spring k3 = 1e7 N/m^3
    x0, T = periodic_orbit_ivp(beam, x0_guess, np.zeros(beam.n), T_guess)
    mu = multipliers_ivp(beam, x0, np.zeros(beam.n), T)
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse
from scipy.integrate import solve_ivp

import nnm_solver as nnm

__all__ = ["STRIP", "cantilever_beam", "beam_matrices", "cantilever_frequencies_analytic", "tip_dof",
           "monodromy_ivp", "multipliers_ivp", "periodic_orbit_ivp", "force_jacobian"]

# ---------------------------------------------------------------------- cantilever beam

#: the default beam: a 1 m x 20 mm x 5 mm steel strip bending about its thin axis
STRIP = dict(length=1.0, width=0.020, thickness=0.005, E=210e9, rho=7800.0)
_I = STRIP["width"] * STRIP["thickness"] ** 3 / 12.0        # 2.083e-10 m^4
EI_STRIP = STRIP["E"] * _I                                  # 43.75 N m^2
RHOA_STRIP = STRIP["rho"] * STRIP["width"] * STRIP["thickness"]   # 0.78 kg/m
#: default tip cubic spring (N/m^3): NNM1 hardens by ~10 % at ~2 mm tip amplitude
K3_STRIP = 1e7

#: beta_k L of the clamped-free Euler-Bernoulli beam (roots of cos(bL) cosh(bL) = -1)
CANTILEVER_BETA_L = (1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349)


def beam_matrices(n_el=12, length=1.0, EI=EI_STRIP, rhoA=RHOA_STRIP):
    """Dense (M, K) of a clamped-free Euler-Bernoulli beam, Hermite cubic elements, consistent mass.

    DOFs: (w_1, theta_1, ..., w_n_el, theta_n_el) of nodes 1..n_el (node 0, at x = 0, is clamped);
    w in m, theta in rad.
    """
    n_el = int(n_el)
    if n_el < 1:
        raise ValueError(f"n_el={n_el}: need at least one element")
    h = float(length) / n_el
    ke = EI / h ** 3 * np.array([[12.0, 6 * h, -12.0, 6 * h],
                                 [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                                 [-12.0, -6 * h, 12.0, -6 * h],
                                 [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    me = rhoA * h / 420.0 * np.array([[156.0, 22 * h, 54.0, -13 * h],
                                      [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                      [54.0, 13 * h, 156.0, -22 * h],
                                      [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    N = 2 * (n_el + 1)
    K = np.zeros((N, N))
    M = np.zeros((N, N))
    for e in range(n_el):
        idx = np.arange(2 * e, 2 * e + 4)
        K[np.ix_(idx, idx)] += ke
        M[np.ix_(idx, idx)] += me
    free = slice(2, N)                      # clamp w_0 and theta_0
    return M[free, free].copy(), K[free, free].copy()


def tip_dof(n_el=12):
    """Index of the tip deflection w in the cantilever's DOF vector."""
    return 2 * int(n_el) - 2


def cantilever_frequencies_analytic(k=3, length=1.0, EI=EI_STRIP, rhoA=RHOA_STRIP):
    """First k natural frequencies (Hz) of the clamped-free beam: (beta L)^2 / (2 pi L^2) sqrt(EI/rhoA)."""
    bl = np.asarray(CANTILEVER_BETA_L[:k])
    return bl ** 2 / (2 * np.pi * length ** 2) * np.sqrt(EI / rhoA)


def cantilever_beam(n_el=12, length=1.0, EI=EI_STRIP, rhoA=RHOA_STRIP, k3=K3_STRIP, tip_spring_k=0.0):
    """Euler-Bernoulli cantilever with a grounded cubic spring on the tip deflection.

    Defaults: the 1 m x 20 mm x 5 mm steel strip (E = 210 GPa, rho = 7800 kg/m^3: EI = 43.75 N m^2,
    rhoA = 0.78 kg/m; linear frequencies 4.19, 26.2, 73.5 Hz), 12 elements (24 DOFs), tip spring
    k3 = 1e7 N/m^3 (hardening; pass k3 < 0 for softening).  ``tip_spring_k`` (N/m) adds a linear
    grounded spring at the tip.  Returns ``nnm.Model(M, K, [nnm.CubicSpring(dof=tip, k3=k3)])``.
    """
    M, K = beam_matrices(n_el, length, EI, rhoA)
    tip = tip_dof(n_el)
    if tip_spring_k:
        K[tip, tip] += float(tip_spring_k)
    name = f"cantilever {n_el} el., tip k3={k3:g}"
    return nnm.Model(M, K, [nnm.CubicSpring(dof=tip, k3=float(k3))], name=name)


def static_tip_stiffness(model, dof):
    """Linear static stiffness (N/m) seen at ``dof``: 1 / (K^-1)[dof, dof]."""
    K = _dense(model.K)
    e = np.zeros(model.n)
    e[dof] = 1.0
    return 1.0 / np.linalg.solve(K, e)[dof]


def softening_saddle_energy(model, dof, k3):
    """Energy (J) of the static saddle of a softening (k3 < 0) grounded cubic spring at ``dof``.

    The other DOFs relax statically: the potential along the tip deflection w is
    k w^2 / 2 + k3 w^4 / 4 with k the static tip stiffness; its maximum, k^2 / (4 |k3|) at
    w^2 = k / |k3|, is the energy at which the NNM family that deforms the spring escapes.
    """
    k = static_tip_stiffness(model, dof)
    return k * k / (4.0 * abs(k3)), np.sqrt(k / abs(k3))


# ---------------------------------------------------------------------- model access (old and new APIs)

def _dense(A):
    if scipy.sparse.issparse(A):
        return A.toarray()
    return np.asarray(A, dtype=float)


def _element_jacobian_parts(model):
    """(B, tangent): d = B x and g'(d), from model.elements or (older nnm_solver) cubic springs."""
    el = getattr(model, "elements", None)
    if el is not None and hasattr(el, "B") and hasattr(el, "tangent"):
        return np.asarray(el.B, dtype=float), el.tangent
    B = np.asarray(model.spring_matrix, dtype=float)
    k3 = np.array([s.k3 for s in model.springs], dtype=float)
    return B, (lambda d: 3.0 * k3 * np.asarray(d) ** 2)


def force_jacobian(model, x):
    """df_nl/dx (n, n) = B^T diag(g'(B x)) B."""
    B, tangent = _element_jacobian_parts(model)
    if B.shape[0] == 0:
        return np.zeros((model.n, model.n))
    g1 = tangent(B @ np.asarray(x, dtype=float))
    return B.T @ (g1[:, None] * B)


class _Equations:
    """Right-hand sides of the state and variational equations of one model (dense)."""

    def __init__(self, model):
        self.model = model
        self.n = model.n
        self.M = _dense(model.M)
        self.K = _dense(model.K)
        self.Minv = np.linalg.inv(self.M)
        self.MinvK = self.Minv @ self.K
        self.B, self.tangent = _element_jacobian_parts(model)

    def acceleration(self, x):
        return -(self.MinvK @ x + self.Minv @ np.asarray(self.model.nonlinear_force(x), dtype=float))

    def stiffness(self, x):
        """M^-1 (K + df_nl/dx)."""
        if self.B.shape[0] == 0:
            return self.MinvK
        g1 = self.tangent(self.B @ x)
        return self.MinvK + self.Minv @ (self.B.T @ (g1[:, None] * self.B))

    def state(self, t, y):
        n = self.n
        return np.concatenate([y[n:2 * n], self.acceleration(y[:n])])

    def variational(self, t, y):
        """y = [x, v, vec(Phi)] with Phi (2n, 2n) row-major; Phi' = [[0, I], [-M^-1 (K + J), 0]] Phi."""
        n = self.n
        x, v = y[:n], y[n:2 * n]
        Phi = y[2 * n:].reshape(2 * n, 2 * n)
        dPhi = np.empty_like(Phi)
        dPhi[:n] = Phi[n:]
        dPhi[n:] = -self.stiffness(x) @ Phi[:n]
        return np.concatenate([v, self.acceleration(x), dPhi.ravel()])


def _atol(rtol, z0, n_state, n_total, atol):
    if atol is not None:
        return atol
    scale = max(float(np.max(np.abs(z0))), 1e-300)
    a = np.full(n_total, 1e-3 * rtol)               # monodromy entries are O(1) or larger
    a[:n_state] = 1e-3 * rtol * scale
    return a


def _flow(model, x0, v0, t_end, rtol, atol, variational):
    eq = model if isinstance(model, _Equations) else _Equations(model)
    n = eq.n
    z0 = np.concatenate([np.asarray(x0, dtype=float).reshape(n), np.asarray(v0, dtype=float).reshape(n)])
    if variational:
        y0 = np.concatenate([z0, np.eye(2 * n).ravel()])
        fun = eq.variational
    else:
        y0 = z0
        fun = eq.state
    sol = solve_ivp(fun, (0.0, float(t_end)), y0, method="DOP853", rtol=rtol,
                    atol=_atol(rtol, z0, 2 * n, y0.size, atol))
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    y = sol.y[:, -1]
    z = y[:2 * n]
    Phi = y[2 * n:].reshape(2 * n, 2 * n) if variational else None
    return eq, z, Phi


# ---------------------------------------------------------------------- monodromy, multipliers, orbits

def monodromy_ivp(model, x0, v0, period, rtol=1e-12, atol=None, half=False):
    """Monodromy matrix (2n, 2n) of the orbit from (x0, v0) over ``period``, physical state [x; v].

    Integrates the state and variational equations with solve_ivp (DOP853) over one period.
    ``atol`` defaults to 1e-3 rtol times the largest |component| of (x0, v0) for the state and
    1e-3 rtol for the sensitivities.

    ``half=True`` integrates only to T/2 and uses time reversibility, valid for a reversible
    periodic orbit (v0 = 0 and v(T/2) = 0): with R = diag(I, -I),
    Phi(T) = R Phi(T/2)^-1 R Phi(T/2).  Half the cost; the cost grows with the highest natural
    frequency times T (explicit integrator), e.g. ~15-25 s per half period for the 12-element beam.
    """
    if not half:
        _, _, Phi = _flow(model, x0, v0, period, rtol, atol, variational=True)
        return Phi
    if v0 is not None and np.any(np.asarray(v0) != 0.0):
        raise ValueError("half=True needs a reversible orbit starting at rest (v0 = 0)")
    _, _, P = _flow(model, x0, np.zeros(model.n), 0.5 * period, rtol, atol, variational=True)
    n = model.n
    R = np.ones(2 * n)
    R[n:] = -1.0
    return R[:, None] * np.linalg.solve(P, R[:, None] * P)


def multipliers_ivp(model, x0, v0, period, rtol=1e-12, atol=None, half=False):
    """Floquet multipliers (2n,) of the orbit: eigenvalues of ``monodromy_ivp``, by decreasing modulus."""
    mu = np.linalg.eigvals(monodromy_ivp(model, x0, v0, period, rtol, atol, half))
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def periodic_orbit_ivp(model, x0, v0=None, T=None, *, fix="energy", rtol=1e-12, atol=None, tol=1e-10,
                       max_iter=30, return_info=False):
    """Newton refinement of a reversible periodic orbit (starting at rest) in continuous time.

    An orbit of the conservative system with v(0) = 0 is periodic with period T when also
    v(T/2) = 0 (time reversibility: x(t) = x(-t) and x(T/2 + s) = x(T/2 - s)).  Unknowns (x0, T);
    equations v(T/2; x0) = 0 (n, integrated with solve_ivp DOP853 and its variational equations)
    plus one condition that picks the orbit in its one-parameter family:

    * ``fix="energy"`` (default): the energy stays that of the initial guess (x0, 0);
    * ``fix="period"``: T stays the given period (only x0 is refined).

    ``v0`` must be None or zero (reversible orbits).  Converged when the residual
    ||v(T/2)|| / (omega ||x0||)  (omega = 2 pi / T) or the Newton update (relative, in x0 and T)
    is below ``tol``; the update reaches the integration noise (~rtol) first on stiff models, whose
    residual stalls at a few hundred times rtol.  Returns (x0, T), or (x0, T, info) with
    ``return_info`` (iterations, (residual, update) history, energy).
    """
    eq = _Equations(model)
    n = eq.n
    x = np.asarray(x0, dtype=float).reshape(n).copy()
    if v0 is not None and np.any(np.asarray(v0) != 0.0):
        raise ValueError("periodic_orbit_ivp refines reversible orbits: v0 must be zero")
    if T is None:
        raise ValueError("a period guess T is needed")
    T = float(T)
    zeros = np.zeros(n)
    E_target = float(model.energy(x, zeros))
    history = []
    for it in range(1, max_iter + 1):
        _, z, Phi = _flow(eq, x, zeros, 0.5 * T, rtol, atol, variational=True)
        r = z[n:]
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = Phi[n:, :n]                   # d v(T/2) / d x0
        J[:n, n] = 0.5 * eq.acceleration(z[:n])   # d v(T/2) / d T
        if fix == "energy":
            rE = float(model.energy(x, zeros)) - E_target
            J[n, :n] = eq.K @ x + np.asarray(model.nonlinear_force(x), dtype=float)
            R = np.concatenate([r, [rE]])
        elif fix == "period":
            J[n, n] = 1.0
            R = np.concatenate([r, [0.0]])
        else:
            raise ValueError(f"fix={fix!r}: use 'energy' or 'period'")
        omega = 2 * np.pi / T
        res = float(np.linalg.norm(r)) / max(omega * np.linalg.norm(x), 1e-300)
        # scale the unknowns so the Newton system is well conditioned: x by ||x||, T by T
        sx = max(np.linalg.norm(x), 1e-300)
        S = np.concatenate([np.full(n, sx), [T]])
        d = -np.linalg.lstsq(J * S[None, :], R, rcond=None)[0] * S
        x += d[:n]
        T += d[n]
        step = float(np.linalg.norm(d[:n]) / sx + abs(d[n]) / T)
        history.append((res, step))
        if res <= tol or step <= tol:
            break
    else:
        raise RuntimeError(f"periodic_orbit_ivp: no convergence in {max_iter} iterations "
                           f"(last residual {history[-1][0]:.3g}, step {history[-1][1]:.3g})")
    if return_info:
        return x, T, dict(iterations=len(history), history=history, energy=float(model.energy(x, zeros)))
    return x, T
