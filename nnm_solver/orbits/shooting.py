r"""Shooting formulation of the NNM problem (seed paper, section 3.1 and 3.3).

Unknowns (scaled, dimension 2n + 1), in mass-normalised modal coordinates q (x = Phi q):

    u = [q0 ; v0 / w_r ; T / T_r]

with w_r = 2 pi / T_r the linear angular frequency of the continued mode.

Shooting function (eq. 4).  Full period:  H = [q(T) - q0 ; (v(T) - v0) / w_r].
Half period (``symmetric=True``): cubic springs make the equations odd
(f(-x) = -f(x)), so the orbits that continue a linear mode satisfy z(t + T/2) = -z(t); they are
found by  H = [q(T/2) + q0 ; (v(T/2) + v0) / w_r]  at half the cost, and the full monodromy is
the square of the half-period map (z -> -z commutes with the flow).  Every solution of the
half-period problem is an exact periodic orbit of period T.

Quarter period (the default for reversible orbits of odd systems: ``symmetric`` and ``reversible``):
an orbit that starts at rest (v0 = 0) and has z(t + T/2) = -z(t) is even in time about t = 0 and odd
about t = T/4, so every coordinate passes through zero at T/4.  Conversely q(T/4) = 0 with v0 = 0 gives
such an orbit: the motion -x(T/2 - t) solves the same (odd, time-reversible) equations with the same
state at T/4, so x(t) = -x(T/2 - t), hence v(T/2) = v0 = 0 and x(T/2) = -x0.  The shooting function is

    H = q(T/4)      (n equations in the n + 1 unknowns [q0; T])

at half the cost of the half-period sweep, with a square corrector (LU) instead of a (2n + 1) x (n + 1)
least-squares problem.  The argument holds step by step for the discrete map of a symmetric scheme
(Newmark's average acceleration and Gauss collocation are), so with a number of steps per period divisible
by 4 (it is rounded up to one) the discrete orbits are exactly those of the half-period problem.  The
Floquet multipliers need the half-period map, which one sensitivity sweep over T/2 at the accepted point
gives (shooting_stability.py).

Phase condition (eq. 6).  Default (reversible orbits): v0 = 0, i.e. t = 0 is an instant of zero
velocity, and the unknowns reduce to u = [q0; T / T_r] (see ShootingProblem).  General orbits
(reversible=False): a Poincare section through the previous converged initial state z_ref,
h(u) = <f(z_ref), z0 - z_ref> = 0 with f the vector field ([v; -Omega^2 q - Bq^T g(Bq q)], scaled as u):
t = 0 is where the orbit crosses the hyperplane through z_ref normal to the flow there.  Unlike the
condition <q_ref, v0> = 0 (an extremum of the motion along q_ref, which degenerates when two such
extrema merge as the orbit's shape changes), the section stays transversal along the family.  The
trivial orbit u = 0 is excluded by starting at finite amplitude and by the arclength condition.

Convergence (eq. 11): ||H|| / ||[q0; v0/w_r]|| < tol, for quarter-period shooting too (on the half-period
residual, by N/4 more state steps: ShootingProblem.error).

Half-period shooting needs an odd f_nl (only odd powers in the element laws): the driver checks it.
"""
from __future__ import annotations

import numpy as np

from ..fourier import resample_periodic
from ..integrators.registry import get_integrator, record_orbit
from .shooting_error import ShootingError
from .shooting_stability import ShootingStability


def balanced_max_step(wp, max_rel_state, max_rel_period):
    """Largest step s along a scaled tangent wp = w * p whose last entry is the period's: the relative
    state change s |wp[:-1]| <= max_rel_state and the relative period change s |wp[-1]| <= 0.8
    max_rel_period (a margin for the curvature of the branch, so that the converged point rarely exceeds
    the hard limit that check_step enforces)."""
    return min(max_rel_state / max(np.linalg.norm(wp[:-1]), 1e-300), 0.8 * max_rel_period / max(abs(wp[-1]), 1e-300))


def discrete_linear_period(omega, nsteps_per_period, integrator="newmark"):
    """Period T (s) whose discretisation with N steps closes exactly for frequency omega (rad/s).

    Average-acceleration Newmark rotates by 2 atan(omega h / 2) per step, so N steps close
    when omega T / (2N) = tan(pi / N); Gauss collocation by 2 arg P(i omega h) (gauss.rotation).
    """
    return get_integrator(integrator).linear_period(omega, nsteps_per_period)


class ShootingProblem(ShootingError, ShootingStability):
    """Shooting function + phase condition of one NNM branch, for ``continuation.pseudo_arclength``.

    reversible=True (default with symmetric=True): the orbit starts at rest, v0 = 0, so the
    unknowns are u = [q0; T / T_r] and the time origin is fixed without a phase condition.  The
    NNMs of mechanical systems without gyroscopic terms that continue a linear mode are
    time-reversible (the motion passes through a state of zero velocity, as in the seed paper's
    shapes "with zero initial velocities"); restricting to them also removes the branch points where
    non-reversible orbits would cross the family.  reversible=False keeps v0 free with the phase
    condition of the module docstring.
    """

    def __init__(self, system, mode_index, steps_per_period=200, symmetric=True, max_rel_step=0.4,
                 reversible=None, max_rel_period_step=np.inf, integrator="newmark", quarter=None):
        if steps_per_period < 8:
            raise ValueError("steps_per_period must be at least 8")
        self.sys = system
        self.integrator = get_integrator(integrator)
        self.n = n = system.n
        self.k = mode_index
        self.symmetric = bool(symmetric)
        self.reversible = self.symmetric if reversible is None else bool(reversible)
        # quarter-period shooting (module docstring): for symmetric reversible orbits, unless quarter=False
        self.quarter = self.symmetric and self.reversible and (quarter is None or bool(quarter))
        self.frac = 0.25 if self.quarter else 0.5 if self.symmetric else 1.0
        self.set_steps(steps_per_period)
        self.w_r = float(np.sqrt(system.omega2[mode_index]))
        self.T_r = 2 * np.pi / self.w_r
        self.q_ref = np.zeros(n)
        self.q_ref[mode_index] = 1.0
        self.section = None          # (z_ref, g): the phase section of general orbits, g = f(z_ref) in u units
        self.max_rel_step = max_rel_step
        self.max_rel_period_step = max_rel_period_step
        # unknowns: entries of y = [q0; v0 / w_r; T / T_r] that are free
        self.free = np.r_[0:n, 2 * n] if self.reversible else np.arange(2 * n + 1)
        self.rows = n if self.quarter else 2 * n if self.reversible else 2 * n + 1   # H (+ phase condition)
        # the dv0 columns of the sensitivity are needed for v0 unknowns or the full-size Floquet problem
        self.all_columns = not (self.reversible and self.symmetric)
        self._maps = None         # (dq, dv)(T/4, T/2 or T) / dz0 at the last Jacobian evaluation (half_map)
        self._stages = None       # ... and that sweep's record (Integrator.sensitivity_stages), or None
        #: real-line coordinates of the last multipliers where Krein collisions happen (events.py), or None
        self.collision = None
        self._accepted_maps = None  # ... at the last accepted point (accepted_map)

    def set_steps(self, steps_per_period):
        """Use steps_per_period time steps per period from now on (rounded up to even for half-period
        shooting, to a multiple of 4 for quarter-period shooting)."""
        spp = int(steps_per_period)
        multiple = 4 if self.quarter else 2 if self.symmetric else 1
        spp = -(-spp // multiple) * multiple
        self.spp = spp
        self.nsteps = int(round(spp * self.frac))       # steps of the shooting interval (T/4, T/2 or T)

    # --------------------------------------------------------------- packing
    def pack(self, q0, v0, T):
        """Unknown vector u from the initial state (modal) and the period (s)."""
        return np.concatenate([q0, v0 / self.w_r, [T / self.T_r]])[self.free]

    def from_state(self, q0, v0, T):
        """u of a first guess from a modal state (q0, v0) and a period T (s): ``pack``."""
        return self.pack(q0, v0, T)

    def last_evaluated(self):
        """The unknowns u of the latest Jacobian evaluation (the problem's monodromy is that orbit's), or None."""
        last = getattr(self, "_last_residual", None)
        return None if last is None else last[0]

    def unpack(self, u):
        """(q0, v0, T) from the unknown vector u."""
        n = self.n
        y = np.zeros(2 * n + 1)
        y[self.free] = u
        return y[:n], y[n:2 * n] * self.w_r, y[2 * n] * self.T_r

    def _h(self, T):
        return self.frac * T / self.nsteps

    # --------------------------------------------------------------- problem protocol
    def residual(self, u):
        q0, v0, T = self.unpack(u)
        if not T > 0:
            return np.full(self.rows, np.nan)
        q, v, ok = self.integrator.state(self.sys, q0, v0, self._h(T), self.nsteps)
        if not ok:
            return np.full(self.rows, np.nan)
        self._end_state = (u.copy(), q, v)
        return self._assemble(q, v, q0, v0)

    def _assemble(self, q, v, q0, v0):
        if self.quarter:
            return q.copy()
        sgn = 1.0 if self.symmetric else -1.0
        r = np.concatenate([q + sgn * q0, (v + sgn * v0) / self.w_r, [self._phase(q0, v0)]])
        return r[:self.rows]

    def jacobian(self, u):
        n, w = self.n, self.w_r
        q0, v0, T = self.unpack(u)
        bad = (np.full(self.rows, np.nan), np.eye(self.rows, len(u)))
        if not T > 0:
            return bad
        h = self._h(T)
        # (quarter-period shooting needs no velocity rows: H = q(T/4))
        out, stages = self.integrator.sensitivity_stages(self.sys, q0, v0, h, self.nsteps, self.all_columns,
                                                         not self.quarter)
        q, v, Sq, Sv, sq_h, sv_h, ok = out
        if not ok:
            return bad
        self._end_state = (u.copy(), q, v)
        r = self._assemble(q, v, q0, v0)
        self._last_residual = (u.copy(), r)
        self._maps = (Sq, Sv)                           # d[q; v](end) / d[q0 (; v0)], kept as two blocks
        self._stages = stages                           # ... and the sweep's record (shooting_stability: half_block)
        dh_du = self.frac * self.T_r / self.nsteps      # dh / du_T
        sgn = 1.0 if self.symmetric else -1.0
        # J = dH/du directly in the free unknowns (reversible: [q0; T], else [q0; v0; T] plus the phase row)
        m = len(self.free)
        if self.quarter:                                # H = q(T/4): J = [dq/dq0, dq/du_T]
            J = np.empty((n, m))
            J[:, :n] = Sq[:, :n]
            J[:, n] = sq_h * dh_du
            return r, J
        J = np.zeros((self.rows, m))
        J[:n, :n] = Sq[:, :n]
        J[n:2 * n, :n] = Sv[:, :n] / w
        if not self.reversible:
            J[:n, n:2 * n] = Sq[:, n:] * w
            J[n:2 * n, n:2 * n] = Sv[:, n:]
        J[:n, m - 1] = sq_h * dh_du
        J[n:2 * n, m - 1] = sv_h * dh_du / w
        d = np.arange(n if self.reversible else 2 * n)
        J[d, d] += sgn
        if not self.reversible:
            if self.section is None:
                J[2 * n, n:2 * n] = self.q_ref
            else:
                J[2 * n, :2 * n] = self.section[1]
        return r, J

    def error(self, u, r):
        """Relative periodicity error (eq. 11) in the scaled state [q; v / w_r].

        Quarter-period shooting measures it on the half-period residual [q(T/2) + q0; v(T/2) / w_r], as the
        half-period formulation does: the integration goes on from the state at T/4 of the latest residual
        (a state sweep of N/4 more steps).  q(T/4) alone would be a weaker test (a small displacement error of
        a stiff mode at T/4 becomes a velocity error w_j / w_r times larger at T/2)."""
        q0, v0, T = self.unpack(u)
        z = np.concatenate([q0, v0 / self.w_r])
        if self.quarter:
            last = getattr(self, "_end_state", None)
            if last is None or not np.array_equal(last[0], u):
                q, v, ok = self.integrator.state(self.sys, q0, v0, self._h(T), self.nsteps)
            else:
                q, v, ok = last[1], last[2], True
            if ok:
                q, v, ok = self.integrator.state(self.sys, q, v, self._h(T), self.nsteps)
            if not ok:
                return float("inf")
            r = np.concatenate([q + q0, v / self.w_r])
        return float(np.linalg.norm(r[:2 * self.n]) / max(np.linalg.norm(z), 1e-300))

    def set_section(self, q0, v0):
        """Phase section of general orbits through the state (q0, v0): normal to the flow there."""
        s = self.sys
        z = np.concatenate([q0, v0 / self.w_r])
        g = np.concatenate([v0, (-s.omega2 * q0 - s.Bq.T @ s.force(s.Bq @ q0)) / self.w_r])
        self.section = (z, g / max(np.linalg.norm(g), 1e-300))

    def _phase(self, q0, v0):
        if self.section is None:
            return self.q_ref @ v0 / self.w_r
        z_ref, g = self.section
        return g @ (np.concatenate([q0, v0 / self.w_r]) - z_ref)

    def accept(self, u, J):
        q0, v0, _ = self.unpack(u)
        self.q_ref = q0 / np.linalg.norm(q0)
        if not self.reversible:
            self.set_section(q0, v0)
        # quarter period: the half-period map the multipliers need is swept at u when they are asked for (kept
        # while u stays the accepted point)
        if not self.quarter:
            self._accepted_maps = self._maps
        elif not np.array_equal(getattr(self, "accepted_u", None), u):
            self._accepted_maps = None
        self.accepted_u = u.copy()

    def check_step(self, u_old, u_new):
        """Refuse steps that change the period by more than max_rel_period_step (relative).

        Internal-resonance tongues branch off where the period is close to a fixed value; bounding
        the change of period per step keeps the continuation from stepping over their entrance.
        """
        T0, T1 = self.unpack(u_old)[2], self.unpack(u_new)[2]
        change = abs(T1 / T0 - 1)
        if change > self.max_rel_period_step:
            return f"the period changed by {100 * change:.2f} % in one step"
        return ""

    def scale(self, u):
        """Weights of the balanced step norm: 1 / |z| on the state z = [q0; v0 / w_r], T_r / T on the period."""
        q0, v0, T = self.unpack(u)
        w = np.full(len(u), 1.0 / max(np.linalg.norm(np.concatenate([q0, v0 / self.w_r])), 1e-300))
        w[-1] = self.T_r / T
        return w

    def max_step(self, u, p):
        """Largest step along p (scaled units): the state changes by at most max_rel_step (relative)
        and the period by at most max_rel_period_step."""
        return balanced_max_step(self.scale(u) * p, self.max_rel_step, self.max_rel_period_step)

    def energy(self, u):
        q0, v0, _ = self.unpack(u)
        return self.sys.energy(q0, v0)

    # --------------------------------------------------------------- results (driver protocol)
    def state(self, u):
        """(q0, v0, T) of the orbit u: modal initial state and period (s)."""
        return self.unpack(u)

    def coefficients(self, u):
        """No Fourier coefficients: the orbit is rebuilt by integration (ShootingSettings.orbit)."""
        return None

    def modal_orbit(self, u):
        """Modal displacements (N, n) of the orbit u at its N = steps_per_period time steps over a period."""
        q0, v0, T = self.unpack(u)
        nsteps = self.spp // 2 if self.symmetric else self.spp
        Q, _, ok = record_orbit(self.sys, q0, v0, T * nsteps / self.spp, nsteps, self.integrator.name)
        if not ok:
            return None
        Q = Q[:-1]
        return np.concatenate([Q, -Q]) if self.symmetric else Q

    def energy_gradient(self, u):
        """dE/du (J per unit of u): E = |v0|^2 / 2 + q0^T Omega^2 q0 / 2 + element potentials."""
        q0, v0, _ = self.unpack(u)
        s = self.sys
        g = np.concatenate([s.omega2 * q0 + s.Bq.T @ s.force(s.Bq @ q0), v0 * self.w_r, [0.0]])
        return g[self.free]



def shooting_orbit(system, x0, v0, period, steps_per_period, symmetric, samples, integrator="newmark"):
    """Orbit of a converged shooting point: (x, v) (samples, n) at t = k T / samples (m, m/s).

    The discrete orbit is re-integrated with the step it converged with (T / steps_per_period), over
    half a period when it was found by half-period shooting (the second half is -z(t)), then
    resampled by Fourier interpolation.  This reproduces the converged orbit even when it is strongly
    unstable.  Raises RuntimeError if the time integration fails.
    """
    spp = int(steps_per_period)
    symmetric = bool(symmetric) and spp % 2 == 0
    nsteps = spp // 2 if symmetric else spp
    Q, V, ok = record_orbit(system, system.to_modal(x0), system.to_modal(v0), period * nsteps / spp, nsteps, integrator)
    if not ok:
        raise RuntimeError("time integration of the orbit failed")
    Q, V = Q[:-1], V[:-1]
    if symmetric:
        Q, V = np.concatenate([Q, -Q]), np.concatenate([V, -V])
    return (system.to_physical(resample_periodic(Q, samples)), system.to_physical(resample_periodic(V, samples)))
