r"""NNM branches by harmonic balance (HB): a second method, independent of shooting/Newmark.

Model (SI units): M x'' + K x + B^T [k3 * (B x)^3] = 0, x (m), k3 (N/m^3), d = B x the spring
deformations (m).  A periodic orbit of angular frequency omega (rad/s, period T = 2 pi / omega s)
is written as a truncated Fourier series in mass-normalised modal coordinates (x = Phi q):

    x(t) = Phi sum_j A[j] c_j(omega t),   c_j = cos(h_j theta) [or sin(h_j theta)],

and the equations of motion are balanced harmonic by harmonic (Galerkin):

    (Omega^2 - h_j^2 omega^2) A[j] + F[j](A) = 0,   F = P [k3 (E A Bq^T)^3] Bq   (AFT)

E / P: sampling of the basis at N equispaced instants / its projector, Bq = B Phi.  The
nonlinear forces are evaluated in the time domain on the n_s spring deformations only; the
Jacobian is analytic (chain rule through E and P).  Details and the Jacobian: ``hb_aft.py``.

Basis (``basis=``):
  * ``"odd"`` (default): cosines of the odd harmonics h = 1, 3, ..., <= ``harmonics``.  The
    NNMs that continue a linear mode of a model with odd (cubic) springs are symmetric,
    x(-t) = x(t) and x(t + T/2) = -x(t), so this basis is exact for them; t = 0 is an instant of
    zero velocity (v0 = 0) and no phase condition is needed.
  * ``"full"``: mean + cosines and sines of h = 1..``harmonics`` for general periodic orbits, with
    the phase condition <q_ref, q'(0)> = 0 (q_ref: shape of the previous point), as in shooting.

Unknowns u = [A (sqrt(kg) m) ; omega / w_r]; no amplitude normalisation: the pseudo-arclength
engine (continuation.py) adds the arclength row.  Convergence: ||R|| / (w_r^2 ||A||) < tol.
HB converges exponentially in the number of harmonics for these analytic orbits.

Each point's energy (J) is ``model.energy(x(0), v(0))``.  Floquet multipliers come from Hill's
method (``hb_hill.py``: the quadratic eigenproblem of the perturbations in the full basis of the
same highest harmonic), stability flags and events as for shooting (``floquet.py``).
"""
from __future__ import annotations

import numpy as np

from .continuation import ContinuationSettings, pseudo_arclength
from .errors import NNMInputError
from .floquet import STABILITY_TOL, is_stable
from .hb_aft import BASES, HBBasis, HBProblem
from .hb_hill import hill_multipliers
from .nnm_continuation import _check_positive, check_branch_arguments, collect_branch, start_amplitude
from .shooting import modal_system

__all__ = ["continue_nnm_hb", "hb_coefficients", "hb_motion"]

#: largest Hill matrix (rows) for which floquet=None computes the multipliers
HILL_AUTO_SIZE = 1000


def _basis(harmonics, samples, basis):
    if basis not in BASES:
        raise NNMInputError(f"basis must be one of {BASES}, got {basis!r}")
    _check_positive("harmonics", harmonics, integer=True)
    if samples is not None:
        _check_positive("samples", samples, integer=True)
        if samples < 2 * harmonics + 1:
            raise NNMInputError(f"samples={samples} is too few for {harmonics} harmonics; use at least "
                                f"{2 * harmonics + 1} (more than {4 * harmonics} avoids aliasing of the cubic)")
    return HBBasis(harmonics, basis, samples)


def continue_nnm_hb(model, mode, energy_max, harmonics=7, samples=None, tol=1e-8, max_points=500, on_point=None,
                    stop=None, energy_min=None, basis="odd", step=None, max_angle=0.35, max_correction=0.5,
                    max_rel_step=0.4, floquet=None):
    """NNM branch of linear mode ``mode`` (1-based) by harmonic balance, from low energy to ``energy_max`` (J).

    Parameters
    ----------
    harmonics : highest harmonic order kept (``basis="odd"``: orders 1, 3, ..., <= harmonics).
    samples : time samples per period for AFT (default 4*harmonics + 4: exact for cubic springs).
    tol : relative residual tolerance of the harmonic-balance equations.
    basis : ``"odd"`` (cosines of odd harmonics, symmetric NNMs) or ``"full"`` (see module doc).
    max_points, on_point, stop, energy_min, step, max_angle, max_correction : as ``continue_nnm``.
    floquet : Floquet multipliers by Hill's method (True), not (False: NaN, all stable), or when the
        Hill matrix 2 n (2 harmonics + 1) has at most HILL_AUTO_SIZE rows (None); cost O(size^3) a point.

    Returns a Branch (settings["method"] = "harmonic_balance"); the Fourier coefficients of each
    point are available from ``hb_coefficients(branch, i)``.
    """
    k = check_branch_arguments(model, mode, energy_max, tol, max_points, energy_min)
    hb = _basis(harmonics, samples, basis)
    system = modal_system(model)
    problem = HBProblem(system, k, hb, max_rel_step=max_rel_step)
    a0 = start_amplitude(system, k, energy_max, energy_min)
    A0 = np.zeros((len(hb), model.n))
    A0[int(np.flatnonzero((hb.h == 1) & ~hb.sine)[0]), k] = a0
    u0 = problem.pack(A0, problem.w_r)
    p0 = np.zeros_like(u0)
    p0[:-1] = A0.ravel() / a0
    s0 = 0.5 * a0 if step is None else float(step)
    settings = ContinuationSettings(step=s0, step_min=1e-8 * a0, step_max=np.inf, max_angle=max_angle,
                                    max_correction=max_correction)

    if floquet is None:
        floquet = 2 * model.n * (2 * hb.harmonics + 1) <= HILL_AUTO_SIZE
    def record(pt):
        A, w = problem.unpack(pt.u)
        q0, v0 = problem.initial_state(pt.u)
        x0, v0 = system.to_physical(q0), system.to_physical(v0)
        if floquet:
            mu = hill_multipliers(problem, pt.u)
            stable = is_stable(mu, STABILITY_TOL)
        else:
            mu, stable = np.full(2 * model.n, np.nan, dtype=complex), True
        return dict(energy=float(model.energy(x0, v0)), frequency_hz=w / (2 * np.pi), period=2 * np.pi / w,
                    x0=x0, v0=v0, floquet=mu, stable=stable, coefficients=system.to_physical(A))

    branch, rows = collect_branch(
        model, mode, pseudo_arclength(problem, u0, p0, settings, tol), record, energy_max, max_points, on_point,
        stop, dict(method="harmonic_balance", harmonics=hb.harmonics, basis=hb.kind, samples=hb.samples,
                   tol=tol, energy_max=energy_max, k3_factor=1.0, floquet=bool(floquet)))
    branch.hb_coefficients = np.array(rows.get("coefficients", []), dtype=float).reshape(len(branch), len(hb), model.n)
    return branch


def _hb_branch_basis(branch):
    s = branch.settings
    if s.get("method") != "harmonic_balance":
        raise NNMInputError(f"the branch was computed by {s.get('method', 'an unknown method')!r}, "
                            f"not by harmonic balance (nnm_solver.hb.continue_nnm_hb)")
    return HBBasis(int(s["harmonics"]), s.get("basis", "odd"), s.get("samples"))


def hb_coefficients(branch, i):
    """Fourier coefficients of point i of an HB branch: (orders (N_b,), sine (N_b,) bool, X (N_b, n) m).

    x(t) = sum_j X[j] * (sin if sine[j] else cos)(orders[j] * 2 pi t / period).  For a branch
    loaded from a file (the coefficients are not stored) they are recomputed: projection of the
    time-integrated orbit, then Gauss-Newton on the HB equations and the point's initial state.
    """
    basis = _hb_branch_basis(branch)
    i = branch._check_index(i)
    X = getattr(branch, "hb_coefficients", None)
    if X is not None and len(X) == len(branch):
        return basis.h.copy(), basis.sine.copy(), X[i].copy()
    system = modal_system(branch.model)
    problem = HBProblem(system, branch.mode - 1, basis)
    q0, v0 = system.to_modal(branch.x0[i]), system.to_modal(branch.v0[i])
    problem.q_ref = q0 / max(np.linalg.norm(q0), 1e-300)
    sub = 16  # Newmark at 16 steps per sample: a close first guess, refined below
    Q, _, _ = system.orbit(q0, v0, branch.period[i], basis.samples * sub)
    u = problem.pack(basis.P @ Q[:-1:sub], 2 * np.pi / branch.period[i])
    c0, s0 = basis.functions([0.0])[0], basis.derivatives([0.0])[0]
    tol = float(branch.settings.get("tol", 1e-8))
    for _ in range(30):  # Gauss-Newton on the HB equations + the initial state (x0, v0) of the point
        r, J = problem.jacobian(u)
        A, w = problem.unpack(u)
        r0 = np.concatenate([c0 @ A - q0, (w * (s0 @ A) - v0) / problem.w_r])
        J0 = np.vstack([np.hstack([np.kron(c0, np.eye(problem.n)), np.zeros((problem.n, 1))]),
                        np.hstack([np.kron(s0, np.eye(problem.n)) * w / problem.w_r, (s0 @ A)[:, None]])])
        du = np.linalg.lstsq(np.vstack([J, J0]), -np.concatenate([r, r0]), rcond=None)[0]
        u += du
        if np.linalg.norm(du) <= 1e-13 * np.linalg.norm(u):
            break
    if not problem.error(u, problem.residual(u)) < 10 * tol:
        raise RuntimeError(f"the harmonic-balance coefficients of point {i} could not be recomputed")
    return basis.h.copy(), basis.sine.copy(), system.to_physical(problem.unpack(u)[0])


def hb_motion(branch, i, samples=256):
    """Orbit of point i of an HB branch from its Fourier series: (t (samples,) s, x, v (samples, n) m, m/s)."""
    h, sine, X = hb_coefficients(branch, i)
    samples = int(samples)
    if samples < 2:
        raise NNMInputError("samples must be at least 2")
    basis = _hb_branch_basis(branch)
    T = branch.period[i]
    t = np.arange(samples) * T / samples
    theta = 2 * np.pi * t / T
    return t, basis.functions(theta) @ X, (2 * np.pi / T) * (basis.derivatives(theta) @ X)
