r"""The first orbit of a branch and the problem that continues it, for each method (the driver's api.py calls these).

``start_amplitude``: the modal amplitude of the nearly linear first orbit; ``shooting_problem`` / ``hb_problem``: the periodic-orbit problem on the
modal system (orbits/shooting.py, orbits/harmonic_balance.py, orbits/condensed_hb.py), its first point u0, the
direction p0 to start along, and the branch's settings record (results/settings.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import NNMInputError
from ..integrators.registry import get_integrator
from ..orbits.condensed_hb import CondensedHBProblem
from ..orbits.harmonic_balance import HBProblem
from ..orbits.hb_basis import BASES, HBBasis
from ..orbits.hill import auto_route
from ..orbits.shooting import ShootingProblem
from ..results.settings import HarmonicBalanceSettings, ShootingSettings
from .settings import SIZES

__all__ = ["METHODS", "START_NONLINEARITY", "HILL_AUTO_SIZE", "RITZ_MIN_DOF", "MODAL_BASES", "check_positive",
           "start_amplitude", "modal_basis", "shooting_problem", "hb_problem"]


#: method names accepted by iter_nnm / continue_nnm ("harmonic_balance" is an alias of "hb")
METHODS = ("shooting", "hb")

#: the names of earlier releases for the fields of driver/settings.SIZES
START_NONLINEARITY, HILL_AUTO_SIZE, RITZ_MIN_DOF = SIZES.start_nonlinearity, SIZES.hill_auto_size, SIZES.ritz_min_dof


MODAL_BASES = ("full", "ritz")


def check_positive(name, value, integer=False):
    """NNMInputError unless ``value`` is a positive finite number (an integer if ``integer``)."""
    ok = isinstance(value, (int, np.integer)) if integer else isinstance(value, (int, float, np.number))
    if not ok or isinstance(value, bool) or not np.isfinite(value) or value <= 0:
        raise NNMInputError(f"{name} must be a positive {'integer' if integer else 'number'}, got {value!r}")


def start_amplitude(system, k, energy_max, energy_min=None):
    """Modal amplitude a (sqrt(kg) m) of the first point along linear mode k (0-based).

    With energy_min: the linear amplitude of that energy.  Otherwise nearly linear: the springs hold
    SIZES.start_nonlinearity (driver/settings.py) of the linear potential w^2 a^2 / 2, and the energy stays below 1 % of energy_max.
    """
    w2 = system.omega2[k]
    if energy_min is not None:
        return math.sqrt(2.0 * energy_min / w2)
    a_cap = math.sqrt(2.0 * energy_max * 1e-2 / w2)
    b = np.abs(system.Bq[:, k])
    C = np.abs(system.coefficients)
    touched = b > 0
    if not np.any(C * touched[:, None]) and not np.any((system.kinks[..., 0] != 0) * touched[:, None]):
        return math.sqrt(2.0 * energy_max * 1e-6 / w2)
    elements = system.elements

    def share(a):  # bound on (nonlinear potential) / (linear potential) at amplitude a; grows with a
        with np.errstate(over="ignore"):      # inf at huge energy_max amplitudes: above the threshold anyway
            return float(np.sum(elements.abs_potential(b * a))) / (0.5 * w2 * a * a)

    lo, hi = 1e-30, a_cap
    if share(hi) <= SIZES.start_nonlinearity:
        return a_cap
    for _ in range(200):  # bisection in log a
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if share(mid) < SIZES.start_nonlinearity else (lo, mid)
        if hi / lo < 1 + 1e-12:
            break
    return hi


def modal_basis(model, opts):
    """The modal basis harmonic balance works in: "full" (every mode, exact) or "ritz" (model/ritz.py)."""
    basis = opts.get("modal_basis")
    if basis is None:
        return "ritz" if model.n > SIZES.ritz_min_dof else "full"
    if basis not in MODAL_BASES:
        raise NNMInputError(f"modal_basis must be one of {MODAL_BASES} or None (automatic), got {basis!r}")
    return basis


def integrator_and_steps(integrator, steps_per_period):
    """(Integrator, time steps a period) of a shooting request: the integrator's own steps where None; one-line
    NNMInputError for an unknown integrator or fewer than 8 steps (checked before any computation)."""
    integrator = get_integrator(integrator)
    spp = integrator.steps if steps_per_period is None else steps_per_period
    check_positive("steps_per_period", spp, integer=True)
    if spp < 8:
        raise NNMInputError(f"steps_per_period={spp} is too small; use at least 8 (200 is typical)")
    return integrator, spp


def shooting_problem(system, k, a0, opts, tol, energy_max, floquet):
    integrator, spp = integrator_and_steps(opts["integrator"], opts["steps_per_period"])
    odd = system.elements.odd
    symmetric = odd if opts["symmetric"] is None else bool(opts["symmetric"])
    if symmetric and not odd:
        raise NNMInputError("symmetric=True (half-period shooting) needs odd nonlinear forces; "
                            "use symmetric=False (or leave it unset) for elements with even powers or an asymmetric "
                            "piecewise-linear law")
    reversible = opts["reversible"]
    if reversible is None and opts["symmetric"] is None and not symmetric:
        reversible = True                      # even forces: full period, orbits still start at rest
    problem = ShootingProblem(system, k, spp, symmetric=symmetric, max_rel_step=opts["max_rel_step"],
                              reversible=reversible, max_rel_period_step=opts["max_period_step"],
                              integrator=integrator)
    n = system.n
    q0 = np.zeros(n)
    q0[k] = a0
    u0 = problem.pack(q0, np.zeros(n), integrator.linear_period(math.sqrt(system.omega2[k]), problem.spp))
    p0 = problem.pack(q0 / a0, np.zeros(n), 0.0)
    settings = ShootingSettings(steps_per_period=problem.spp, tol=tol, symmetric=symmetric,
                                reversible=problem.reversible, energy_max=energy_max, integrator=integrator.name,
                                floquet=True if floquet is None else bool(floquet))
    return problem, u0, p0, settings


def hb_floquet_default(n, harmonics, ritz):
    """Does harmonic balance compute the multipliers when floquet=None: for a Hill matrix of at most
    SIZES.hill_auto_size rows, or in a Ritz basis (``ritz``: a large model) of at most SIZES.ritz_floquet_modes modes
    whose multipliers take the monodromy route (an n x n eigenproblem a point, hill_monodromy.py)."""
    if 2 * n * (2 * harmonics + 1) <= SIZES.hill_auto_size:
        return True
    return bool(ritz and n <= SIZES.ritz_floquet_modes and auto_route(n, harmonics) == "monodromy")


def hb_problem(system, k, a0, opts, tol, energy_max, floquet):
    basis, harmonics, samples = opts["basis"], opts["harmonics"], opts["samples"]
    if basis is None:
        basis = "odd" if system.elements.odd else "full"
    if basis not in BASES:
        raise NNMInputError(f"basis must be one of {BASES}, got {basis!r}")
    check_positive("harmonics", harmonics, integer=True)
    if samples is not None:
        check_positive("samples", samples, integer=True)
        if samples < 2 * harmonics + 1:
            raise NNMInputError(f"samples={samples} is too few for {harmonics} harmonics; use at least "
                                f"{2 * harmonics + 1} (more than {4 * harmonics} avoids aliasing of the cubic)")
    if basis == "odd" and not system.elements.odd:
        raise NNMInputError("basis='odd' needs odd nonlinear forces; use basis='full' for elements with even powers "
                            "or an asymmetric piecewise-linear law")
    condensed = opts["condensed"]
    if not isinstance(condensed, (bool, np.bool_)):
        raise NNMInputError(f"condensed must be True or False, got {condensed!r}")
    hb = HBBasis(harmonics, basis, samples)
    steps = dict(max_rel_step=opts["max_rel_step"], max_rel_period_step=opts["max_period_step"])
    if condensed:                              # unknowns: the elements' deformations per harmonic (condensed_hb.py)
        problem = CondensedHBProblem(system, k, hb, **steps)
        u0, p0 = problem.start(a0)
    else:
        problem = HBProblem(system, k, hb, **steps)
        A0 = np.zeros((len(hb), system.n))
        A0[int(np.flatnonzero((hb.h == 1) & ~hb.sine)[0]), k] = a0
        u0 = problem.pack(A0, problem.w_r)
        p0 = np.zeros_like(u0)
        p0[:-1] = A0.ravel() / a0
    cutoff = getattr(system, "cutoff_hz", None)
    if floquet is None:
        floquet = hb_floquet_default(system.n, hb.harmonics, cutoff is not None)
    settings = HarmonicBalanceSettings(tol=tol, harmonics=hb.harmonics, basis=hb.kind, samples=hb.samples,
                                       energy_max=energy_max, floquet=bool(floquet), condensed=bool(condensed),
                                       modal_basis="full" if cutoff is None else "ritz",
                                       cutoff_hz=0.0 if cutoff is None else float(cutoff))
    return problem, u0, p0, settings
