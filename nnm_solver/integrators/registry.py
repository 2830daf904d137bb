"""The time integrators of the shooting method, by name: one object per scheme with the same four calls.

``INTEGRATORS`` lists the names; "newmark" (average acceleration, order 2, the seed paper's scheme) is
first and the default.  "gauss4" and "gauss6" are the 2- and 3-stage Gauss-Legendre collocation methods
(orders 4 and 6, symplectic and symmetric; gauss.py).  Each integrator gives, for a ModalSystem:

    state(system, q0, v0, h, nsteps)              -> (q, v, ok)
    record(system, q0, v0, h, nsteps)             -> (Q, V, ok)     every state
    sensitivity(system, q0, v0, h, nsteps, all, velocities)
                                                  -> (q, v, Sq, Sv, sq_h, sv_h, ok)   exact derivatives
                                                     (velocities=False: Sv is None, not assembled)
    sensitivity_factors(system, q0, v0, h, nsteps) -> (q, v, dq_N/dq0 as diagonal + low rank, ok) or None
    directional(system, q0, v0, h, nsteps, X)     -> (dq_N/dq0 @ X, dv_N/dq0 @ X, ok) for a few directions X
    sensitivity_stages(...), reversible_half_block(system, stages, Gqq)
                                                  -> a sweep with its record; the half-period dq/dq0 of a
                                                     reversible orbit from its quarter map (Gauss: symplectic)
    linear_period(omega, steps_per_period)        -> T (s) whose discrete orbit closes for frequency omega
    relative_error(y)                             -> relative frequency error of a harmonic with h w = y

All share the low-rank treatment of the localised nonlinearity (the implicit solve is on the element
deformations only), so a step costs O(n n_s) for every scheme.  Models with coupled elements (PolynomialStiffness,
several deformations in one force) take the same schemes in the full modal space (general.py).
"""
from __future__ import annotations

import math

import numpy as np

from . import gauss, general, newmark
from ..errors import NNMInputError

__all__ = ["INTEGRATORS", "Integrator", "get_integrator", "record_orbit"]


class Integrator:
    """A one-step scheme for q'' = -Omega^2 q - Bq^T g(Bq q) with s implicit stages (Newmark: s = 1).

    name : the name users pass (``continue_nnm(..., integrator=name)``); order : the convergence order
    of the frequency error (2 for Newmark, 2s for Gauss); stages : implicit stages per step (the cost
    of one step relative to Newmark, roughly).
    """

    def __init__(self, name, order, stages, description, steps):
        self.name, self.order, self.stages, self.description = name, order, stages, description
        self.steps = int(steps)     # the default steps per period with this scheme (the registry says why)

    def __repr__(self):
        return f"Integrator({self.name!r}, order {self.order})"

    # -- the angle of one step of the linear discrete map: 2 arg P(i h w) (gauss.rotation)
    def rotation(self, y):
        return gauss.rotation(y, self.stages)

    def relative_error(self, y):
        """Relative frequency error of a harmonic resolved with h w = y per step (y < pi): a linear mode of
        frequency w is integrated at the frequency rotation(y) / h, so the error is rotation(y) / y - 1
        (negative: the discrete motion is slower; e.g. Newmark -y^2 / 12)."""
        y = np.asarray(y, dtype=float)
        safe = np.where(y > 0, y, 1.0)
        return np.where(y > 0, self.rotation(safe) / safe - 1.0, 0.0)

    def linear_period(self, omega, steps_per_period):
        """Period T (s) for which the discrete map of a linear mode of frequency omega (rad/s) closes
        after exactly steps_per_period steps: N rotation(omega T / N) = 2 pi."""
        N = int(steps_per_period)
        if self.stages == 1:                     # 2 atan(w h / 2) = 2 pi / N
            return 2.0 * N / omega * math.tan(math.pi / N)
        T = 2 * math.pi / omega
        for _ in range(20):                      # Newton on N rotation(w T / N) - 2 pi (rotation' ~ 1)
            y = omega * T / N
            r = float(self.rotation(y)) - 2 * math.pi / N
            dy = 1e-7 * y
            dr = (float(self.rotation(y + dy)) - float(self.rotation(y - dy))) / (2 * dy)
            T -= r / dr * N / omega
            if abs(r) < 1e-16:
                break
        return T

    # -- sweeps
    def state(self, system, q0, v0, h, nsteps):
        raise NotImplementedError  # pragma: no cover

    def record(self, system, q0, v0, h, nsteps):
        raise NotImplementedError  # pragma: no cover

    def sensitivity(self, system, q0, v0, h, nsteps, all_columns=True, velocities=True):
        raise NotImplementedError  # pragma: no cover

    def sensitivity_factors(self, system, q0, v0, h, nsteps):
        """(q, v, dq_N/dq0 as a lowrank.DiagonalPlusLowRank, ok), or None where the scheme does not keep that
        form (then use sensitivity)."""
        return None

    def directional(self, system, q0, v0, h, nsteps, X):
        """(dq_N/dq0 @ X, dv_N/dq0 @ X, ok) for a few initial displacements X (n, p); here from the full
        sensitivity (Gauss: a Volterra solve of p columns, gauss.sweep_directional)."""
        _, _, Sq, Sv, _, _, ok = self.sensitivity(system, q0, v0, h, nsteps, False, True)
        return Sq[:, :len(q0)] @ X, Sv[:, :len(q0)] @ X, ok

    def sensitivity_stages(self, system, q0, v0, h, nsteps, all_columns=True, velocities=True):
        """(sensitivity's outputs, a record of the sweep for reversible_half_block; None where the scheme has
        none)."""
        return self.sensitivity(system, q0, v0, h, nsteps, all_columns, velocities), None

    def reversible_half_block(self, system, stages, Gqq):
        """dq(2 t)/dq0 of a symmetric reversible orbit from its quarter-period sweep (sensitivity_stages' record, Gqq
        = dq(t)/dq0; gauss.reversible_half_block), or None where the scheme is not symplectic or kept no record."""
        return None


def _general(system):
    """True when the model has coupled elements (PolynomialStiffness): the general kernels (general.py)."""
    return system.elements.coupled


class _Newmark(Integrator):
    def state(self, system, q0, v0, h, nsteps):
        if _general(system):
            return general.state(system, 1, q0, v0, h, nsteps)
        return newmark.sweep_state(q0, v0, h, nsteps, *system.kernel)

    def record(self, system, q0, v0, h, nsteps):
        if _general(system):
            return general.record(system, 1, q0, v0, h, nsteps)
        return newmark.sweep_record(q0, v0, h, nsteps, *system.kernel)

    def sensitivity(self, system, q0, v0, h, nsteps, all_columns=True, velocities=True):
        if _general(system):
            return general.sensitivity(system, 1, q0, v0, h, nsteps, all_columns, velocities)
        return newmark.sweep_sensitivity(q0, v0, h, nsteps, *system.kernel, all_columns, velocities)

    def sensitivity_factors(self, system, q0, v0, h, nsteps):
        if _general(system):
            return None
        return newmark.sweep_factors(q0, v0, h, nsteps, *system.kernel)


class _Gauss(Integrator):
    def _args(self, system, h):
        k = gauss.constants(system, h, self.stages)
        return (*system.kernel, k.C1, k.Cc, k.F, k.G, k.b, k.bbar, k.c)

    def state(self, system, q0, v0, h, nsteps):
        if _general(system):
            return general.state(system, self.stages, q0, v0, h, nsteps)
        return gauss.sweep_state(q0, v0, h, nsteps, *self._args(system, h))

    def record(self, system, q0, v0, h, nsteps):
        if _general(system):
            return general.record(system, self.stages, q0, v0, h, nsteps)
        return gauss.sweep_record(q0, v0, h, nsteps, *self._args(system, h))

    def sensitivity(self, system, q0, v0, h, nsteps, all_columns=True, velocities=True):
        if _general(system):
            return general.sensitivity(system, self.stages, q0, v0, h, nsteps, all_columns, velocities)
        return gauss.sweep_sensitivity(q0, v0, h, nsteps, system.kernel, self.stages, all_columns, velocities)

    def sensitivity_factors(self, system, q0, v0, h, nsteps):
        if _general(system):
            return None
        return gauss.sweep_factors(q0, v0, h, nsteps, system.kernel, self.stages)

    def sensitivity_stages(self, system, q0, v0, h, nsteps, all_columns=True, velocities=True):
        if _general(system):
            return super().sensitivity_stages(system, q0, v0, h, nsteps, all_columns, velocities)
        return gauss.sweep_sensitivity_stages(q0, v0, h, nsteps, system.kernel, self.stages, all_columns, velocities)

    def directional(self, system, q0, v0, h, nsteps, X):
        if _general(system):
            return super().directional(system, q0, v0, h, nsteps, X)
        return gauss.sweep_directional(q0, v0, h, nsteps, system.kernel, self.stages, X)[2:]

    def reversible_half_block(self, system, stages, Gqq):
        if stages is None or _general(system):
            return None
        return gauss.reversible_half_block(Gqq, stages, system.kernel, self.stages)


#: Default steps per period: Newmark 200 (a fundamental-dominated orbit's frequency to 8e-5, the seed paper's
#: choice; the aircraft's mode 20 near its 3:1 tongue only to 1e-2, issue 51), gauss4 and gauss6 100 (gauss6:
#: 1e-11 on the Duffing backbone, docs/integrators.md; the aircraft's mode 20 to 7e-4 at worst, 1e-7 typically)
_REGISTRY = {
    "newmark": _Newmark("newmark", 2, 1, "Newmark average acceleration (trapezoidal rule), order 2: the seed paper's "
                        "scheme", steps=200),
    "gauss4": _Gauss("gauss4", 4, 2, "2-stage Gauss-Legendre collocation, order 4, symplectic", steps=100),
    "gauss6": _Gauss("gauss6", 6, 3, "3-stage Gauss-Legendre collocation, order 6, symplectic", steps=100),
}

#: the available integrator names (a contract): "newmark" first (the default is Shooting's, driver/settings.py)
INTEGRATORS = tuple(_REGISTRY)


def get_integrator(name):
    """The Integrator called ``name`` (one of INTEGRATORS); NNMInputError otherwise."""
    if isinstance(name, Integrator):
        return name
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise NNMInputError(f"integrator must be one of {', '.join(INTEGRATORS)}; got {name!r}") from None


def record_orbit(system, q0, v0, duration, nsteps, integrator="newmark"):
    """States of ``system`` (a ``ModalSystem``) from the modal state (q0, v0) at nsteps + 1 equally spaced
    times over ``duration`` (s), integrated with ``integrator`` (a name of INTEGRATORS; default Newmark):
    (Q, V, ok), Q and V (nsteps + 1, n)."""
    return get_integrator(integrator).record(system, np.ascontiguousarray(q0, dtype=float),
                                             np.ascontiguousarray(v0, dtype=float), duration / nsteps, int(nsteps))
