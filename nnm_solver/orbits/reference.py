r"""A periodic orbit integrated by a general-purpose ODE solver, independent of the solver's own integrators.

The stored initial state (x0, v0) of a converged point is integrated over the stored period T with
scipy's explicit Runge-Kutta method of order 8 (``solve_ivp(method="DOP853")``) on the equations of
motion in mass-normalised modal coordinates (model/modal.py),

    q'' = -Omega^2 q - Bq^T g(Bq q),       x = Phi q,

whose right-hand side costs O(n n_s) in numpy: no compiled kernel is needed, so it can run before
numba has compiled the integrators (a fresh install, the viewer's first seconds).  The result is the
exact flow of the ODE from that state, to the tolerance ``rtol``; the solver's own orbit
(``Branch.motion``) is the discrete orbit of its integrator, which it reproduces to that integrator's
discretisation error (the frequency error ``Branch.freq_error`` estimates) and to the growth of that
error over one period on an unstable orbit.

An orbit found by half-period shooting (``symmetric``, odd force laws: x(t + T/2) = -x(t)) is
integrated over T/2 and continued by that symmetry, as the solver's own orbit is, which halves the
growth of the errors on unstable orbits.

An explicit method needs steps shorter than about 3 / omega_max (omega_max, rad/s: the highest modal
frequency): for the 548-DOF aircraft (11.4 kHz) and NNM 10 (T = 0.122 s, half of it integrated) about
1,300 steps (15,000 right-hand sides), 0.2 s on one core.
"""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError
from .settings import ORBITS

__all__ = ["reference_orbit", "reference_steps"]


def reference_steps(system, duration):
    """Estimated DOP853 steps to integrate ``system`` over ``duration`` (s): duration * omega_max / 3, the
    stability limit of an explicit method (accuracy may ask for more on orbits with strong high harmonics)."""
    omega_max = float(np.sqrt(max(float(np.max(system.omega2, initial=0.0)), 0.0)))
    return int(np.ceil(float(duration) * omega_max / ORBITS.reference_step_omega)) + 1


def reference_orbit(system, x0, v0, period, samples=256, symmetric=False, rtol=1e-9, max_steps=None):
    """(x, v) (samples, n): the orbit of ``system`` (a ModalSystem) from the physical state x0 (m), v0 (m/s)
    at t = k T / samples, k = 0 .. samples - 1, T = ``period`` (s), integrated by scipy's DOP853 to the
    relative tolerance ``rtol`` (absolute tolerance rtol * 1e-3 of the state's size, in each of q and
    v).  ``symmetric``: integrate over T/2 and use x(t + T/2) = -x(t) (needs an even ``samples``; with an
    odd one the whole period is integrated).  ``max_steps``: RuntimeError before integrating if
    ``reference_steps`` estimates more steps (a model with very high modal frequencies makes an explicit
    method slow).  RuntimeError if the integration fails."""
    from scipy.integrate import solve_ivp

    samples = int(samples)
    period = float(period)
    if samples < 2:
        raise NNMInputError("samples must be at least 2")
    if not (np.isfinite(period) and period > 0):
        raise NNMInputError(f"the period must be positive and finite, not {period!r}")
    q0 = np.asarray(system.to_modal(np.asarray(x0, dtype=float)), dtype=float)
    p0 = np.asarray(system.to_modal(np.asarray(v0, dtype=float)), dtype=float)
    n = system.n
    omega2, Bq, elements = system.omega2, system.Bq, system.elements
    w = 2.0 * np.pi / period
    size = max(float(np.max(np.abs(q0), initial=0.0)), float(np.max(np.abs(p0), initial=0.0)) / w, 1e-300)
    atol = np.concatenate([np.full(n, 1e-3 * rtol * size), np.full(n, 1e-3 * rtol * size * w)])

    def rhs(_t, y):
        q = y[:n]
        return np.concatenate([y[n:], -omega2 * q - Bq.T @ elements.force(Bq @ q)])

    half = bool(symmetric) and samples % 2 == 0
    count = samples // 2 if half else samples
    t_eval = np.arange(count) * period / samples
    if max_steps is not None and reference_steps(system, t_eval[-1]) > max_steps:
        raise RuntimeError(f"the reference integration would take about {reference_steps(system, t_eval[-1])} "
                           f"steps (highest modal frequency {np.sqrt(np.max(omega2)) / (2 * np.pi):.4g} Hz over "
                           f"{t_eval[-1]:.4g} s), more than max_steps = {max_steps}")
    sol = solve_ivp(rhs, (0.0, t_eval[-1]), np.concatenate([q0, p0]), method="DOP853", t_eval=t_eval,
                    rtol=rtol, atol=atol)
    if sol.status != 0 or sol.y.shape[1] != count or not np.all(np.isfinite(sol.y)):
        raise RuntimeError(f"the reference integration of the orbit failed: {sol.message}")
    Q, V = sol.y[:n].T, sol.y[n:].T
    if half:
        Q, V = np.concatenate([Q, -Q]), np.concatenate([V, -V])
    return system.to_physical(Q), system.to_physical(V)
