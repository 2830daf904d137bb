r"""Where the frequency at a fixed energy is defined: the test both truncation-error estimates (shooting_error.py,
hb_error.py) use to choose between the step at a fixed energy and the step orthogonal to the branch.

The FEP shows the frequency at a fixed energy, so an orbit's error is estimated there: the correcting step is moved
along the branch back to the point's energy.  That move is ill-posed only at an energy fold, where the branch's
tangent in the FEP plane is vertical: d ln E = 0 while d ln f is not.  A test on the tangent in the problem's own
(balanced) norm is not that test: where the frequency changes fast with little energy (a softening family running
into a saddle, f falling 35 % over the last 1 % of the energy) the tangent is nearly all frequency and such a test
sees a fold where there is none; the orthogonal step then drops the frequency error that the fixed-energy step
measures (measured on a 2-DOF chain with a softening spring, condensed HB H = 9 against H = 31: the estimate fell
from 3.2e-5 to 8e-9 while the error grew from 4.1e-5 to 1.2e-4).

The test is therefore the slope of the branch in the FEP plane: a fold where |d ln E| < ORBITS.fold_slope |d ln f|, i.e.
|d ln E / d ln f| below ORBITS.fold_slope.  No larger threshold separates a fold from a steep branch: on that chain
|d ln E / d ln f| falls from 0.13 to 0.02 along 60 points whose fixed-energy error is real (the branch offset in
energy, magnified by the slope), and the points next to the 2-DOF benchmark's fold at 4681 J (tests/test_integrators)
see 0.12 at the nearest.  Next to a fold the fixed-energy estimate is therefore the honest, magnified one; only what
the corrector's tolerance leaves is never moved along the branch (shooting_error.py).
"""
from __future__ import annotations

from .settings import ORBITS

__all__ = ["FOLD_SLOPE", "at_energy_fold"]

#: an alias of settings.py's ORBITS.fold_slope (the code reads that)
FOLD_SLOPE = ORBITS.fold_slope


def at_energy_fold(dlnE, dlnf):
    """True where the branch tangent (d ln E, d ln f) is within ORBITS.fold_slope of vertical in the FEP plane (ln E, ln
    f): the frequency at a fixed energy is not defined there."""
    return abs(dlnE) < ORBITS.fold_slope * abs(dlnf)
