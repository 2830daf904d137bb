r"""What a user asks for, as typed frozen objects: the method and the continuation.

    continue_nnm(model, mode, energy_max, method=Shooting(integrator="gauss6") | HarmonicBalance(harmonics=9),
                 continuation=Continuation(max_points=200), tongues=Follow() | Skip())

Every default is written once: the methods' in results/settings.py (``Shooting``, ``HarmonicBalance``: the same
objects are the branch's record, ``branch.settings``, with every None resolved), the continuation's here, the
tongues' in backbone/settings.py.  The keywords of earlier releases
(``integrator=``, ``steps_per_period=``, ``harmonics=``, ``max_points=``, ...) are mapped onto these objects by
``from_keywords`` (api.py), so old calls give the same objects.

The default method is shooting with the 6th-order Gauss-Legendre integrator at 100 steps a period, chosen by
measurement (docs/integrators.md): on the 2-DOF benchmark its backbone is within 1e-8 of the exact one (Newmark at
200 steps: 1.3e-4), and on the aircraft's mode 20 its points lie within 3e-5 of the harmonic-balance skeleton up to
the family's end, where Newmark's estimated errors reach 1e-2 near the 3:1 tongue and its backbone ended 35 % lower
in energy.  It costs about 3x Newmark's time a step at half the steps.  Its accuracy target, freq_tol = 1e-4 by
default (the steps raised where a point's estimated error exceeds it; harmonic balance: two more harmonics), makes the
1e-4 a guarantee where the estimate holds: on mode 20 at 100 steps the backbone's points next to the 3:1 and 9:1
resonances (4.1-4.4 J) had estimated errors up to 7.8e-4 (their higher harmonics of modes 42 and 260 resolved by 33
and 11 steps); with the target 16 of its 92 points ran at 180 steps, the largest estimate fell to 6.6e-6, the
backbone ended where it did (5.194 J, -4.72 %), and condensed harmonic balance (9 harmonics, raised to 11) ended at
5.196 J, -4.72 % (load 6-8: 482 s and 8 s).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import NNMInputError
from ..results.settings import HarmonicBalance, Shooting

__all__ = ["Shooting", "HarmonicBalance", "Continuation", "Sizes", "SIZES", "method_of"]


@dataclass(frozen=True)
class Continuation:
    """Pseudo-arclength step control (continuation/engine.py).

    step : first step, relative to the orbit (0.5: half the starting amplitude); step_min : smallest step;
    max_angle : largest turn (rad) of the tangent between two points; max_correction : largest corrector
    displacement, relative to the step; max_rel_step : largest relative change of the orbit's state in one step;
    max_period_step : largest relative change of the period between two points: 0.005 for every method.  Shooting's
    orbits meet tongues of every order, whose entrances are narrow in period.  For harmonic balance a 2 % cap takes
    about NLvib's points (issue 30: 23 instead of 70 on its example 04, 87 instead of 190 on 09, the same folds) but
    straight lines between its points then miss the curve by up to 2.4e-3 across a piecewise-linear kink and the
    energy-balance peak prediction by 1.3e-3, and at 5 % a step of the 3-DOF combination-resonance branch stepped
    over its whole unstable interval between two Krein collisions; max_points : largest number of points kept;
    max_refusals : steps refused in a row when an event inside them cannot be located (the step is halved each time).
    """

    step: float = 0.5
    step_min: float = 1e-8
    max_angle: float = 0.35
    max_correction: float = 0.5
    max_rel_step: float = 0.4
    max_period_step: float = 0.005
    max_points: int = 500
    max_refusals: int = 3


@dataclass(frozen=True)
class Sizes:
    """Where the driver changes its route with the model's size, and how small the first orbit is.

    start_nonlinearity : fraction of the linear potential energy carried by the nonlinear elements at a branch's
        first point (1e-5: the first point is linear to that order, far below any frequency accuracy asked);
    hill_auto_size : largest Hill matrix (rows) for which harmonic balance computes the multipliers when
        floquet=None (a dense eigenproblem of that size costs about 0.1 s here);
    ritz_floquet_modes : harmonic balance in a Ritz basis (a large model) computes them too when floquet=None if its
        multipliers take the monodromy route (orbits/hill.auto_route) and the basis has at most this many modes (an
        n x n eigenproblem a point: ~0.3 s for the unreduced aircraft's 670, a small share of its basis's cost);
    ritz_min_dof : harmonic balance works in a Ritz basis (model/ritz.py) by default above this many DOFs;
    condense_ratio : a forced response with condensed=None is condensed when n_s * condense_ratio < n (few elements
        in a large model); max_uncondensed : the largest uncondensed forced HB system (basis functions x n).
    """

    start_nonlinearity: float = 1e-5
    hill_auto_size: int = 1000
    ritz_floquet_modes: int = 1500
    ritz_min_dof: int = 2000
    condense_ratio: int = 4
    max_uncondensed: int = 20000


#: the driver's sizes (the defaults above, written once)
SIZES = Sizes()


def method_of(method):
    """The method settings object of ``method`` (a Shooting / HarmonicBalance, or a name: "shooting", "hb",
    "harmonic_balance"); NNMInputError otherwise."""
    if isinstance(method, (Shooting, HarmonicBalance)):
        return method
    if method in ("shooting", None):
        return Shooting()
    if method in ("hb", "harmonic_balance"):
        return HarmonicBalance()
    raise NNMInputError(f"method must be one of Shooting(), HarmonicBalance(), 'shooting' or 'hb', got {method!r}")
