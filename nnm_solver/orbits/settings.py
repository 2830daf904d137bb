"""The orbit layer's settings: every threshold and size of orbits/, written once, with the measurement behind it.

``ORBITS`` is the instance the code reads (``ORBITS.secular_tol``); names of earlier releases that were public
(``FOLD_SLOPE``, ``EXTRA_HARMONICS``, ``DENSE_MAX_ROWS``, ``SYMMETRY_TOL``, ``CENTROID_MAX``, ``TRIVIAL_COS``,
``ARPACK_RESTARTS``) stay importable from their modules as aliases of its fields.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["OrbitSettings", "ORBITS"]


@dataclass(frozen=True)
class OrbitSettings:
    """Thresholds and sizes of the periodic-orbit layer (shooting, harmonic balance, Hill's multipliers)."""

    # ------------------------------------------------------------------ FEP slope (fep_slope.py)
    #: |d ln E / d ln f| along the branch below which the frequency at a fixed energy is not defined (an energy fold)
    fold_slope: float = 1e-3

    # ------------------------------------------------------------------ HB truncation error (hb_error.py)
    #: harmonics added for the estimate (H -> H + 2: the next odd harmonic, which odd laws excite)
    error_extra_harmonics: int = 2
    #: a first Newton step shorter than this (balanced norm, relative to the orbit) is the estimate; a longer one (a
    #: new harmonic near a mode's frequency: the larger problem is far from linear there) is followed by more steps
    #: until the frequency moves by at most error_settled of the estimate, error_max_steps in all
    error_one_step: float = 1e-3
    error_settled: float = 0.05
    error_max_steps: int = 8
    #: steps that end farther than this from the point's energy (relative), or do not settle, found no solution of
    #: the larger problem near the orbit: the estimate is then inf (not resolved)
    error_unsettled_energy: float = 1e-3

    # ------------------------------------------------------------------ Hill's multipliers: routes (hill.py)
    #: method="auto" takes the dense route up to this many rows 2 n (2H + 1) of the Hill matrix
    hill_dense_max_rows: int = 400
    #: method="auto" takes the monodromy route (hill_monodromy.py: the time-domain monodromy of the variational
    #: equation along the HB orbit, an n x n eigenproblem) from this many rows of the Hill matrix: there the other
    #: routes' fallback is an eigenproblem of that size (the aircraft's 548 modes at H = 9: 20,824 rows, minutes a
    #: point; the Ritz system of the unreduced aircraft: 25,460)
    hill_monodromy_min_rows: int = 8000
    #: (hill_monodromy.py) Gauss stages, steps per half period per harmonic of the orbit (the tangent of a cubic law
    #: holds harmonics up to 2H: 4 steps per period of its highest harmonic), and the fewest steps per half period
    monodromy_stages: int = 3
    monodromy_steps_per_harmonic: float = 8.0
    monodromy_min_steps: int = 24
    #: (hill_reversible.py) a symmetry holds when the entries of the springs' Galerkin blocks it sets to zero are
    #: below this fraction of the largest entry (the AFT round-off is ~1e-16)
    reversible_symmetry_tol: float = 1e-13
    #: (hill_shared.py) largest |mean harmonic| of a kept eigenvector (0.5 for a pair at -1: it is centred between
    #: two harmonics)
    centroid_max: float = 0.6
    #: eigenvectors of the shifted blocks within this |cos| of the orbit's velocity are the trivial pair's, not kept
    #: (the trivial block's two nearest the velocity are; the trivial pair is reported as exactly 1, 1)
    trivial_cos: float = 0.999

    # ------------------------------------------------------------------ the secular route (hill_secular.py)
    #: Newton iterations per pass, their relative step tolerance, the largest Hill residual of an accepted
    #: eigenpair, and the checks that send a point to the structured route: an exponent this close (units of
    #: omega) to a point i k, |k| <= 2H + 1, where the trivial pair's copies lie (internal resonances: a class's
    #: eigenvectors mix with those copies, the dense route may keep such a hybrid; branch points), two pairs of
    #: multipliers this close (a duplicate, or a collision)
    secular_iter: int = 30
    secular_tol: float = 1e-13
    secular_residual: float = 1e-9
    secular_lattice_gap: float = 0.05
    secular_distinct: float = 1e-6
    #: at most this many classes go to the structured route from the secular one (more: the whole structured route)
    secular_max_hard: int = 4

    # ------------------------------------------------------------------ the copies of hard classes (hill_copies.py)
    #: how far from its lattice point a copy may lie (units of omega), and how close two candidates' |mean harmonic|
    #: may be at the cut of the kept ones (closer: declined)
    copy_radius: float = 0.3
    copy_tie: float = 1e-4
    #: the radius of the ring of extra starts around 0 and the hard classes' lattice points (units of omega)
    copy_ring: float = 0.03
    #: Newton iterations for the copies (a start that has not converged by then is dropped), and their step
    #: tolerance (relative; Newton converges quadratically at a simple zero: the error after a step of 1e-10 is ~1e-20)
    copy_iter: int = 12
    copy_tol: float = 1e-10
    #: the discs around 0 whose zeros are counted (radii tried in turn until the count is an integer, units of
    #: omega), the nodes of the trapezoidal rule, and the disc where more than the trivial pair's two zeros decline
    copy_count_radii: tuple = (0.02, 0.012, 0.03)
    copy_count_nodes: int = 32
    copy_cluster: float = 0.004

    # ------------------------------------------------------------------ the structured route (hill_structured.py)
    #: vectors per exponent in the structured route (a collision of two exponents needs 2, the trivial pair beside a
    #: real pair near +1 needs 4)
    structured_block: int = 4
    #: relative residual ||L x - theta x|| / max(1, |theta|) (theta in units of omega) of an accepted eigenpair
    structured_residual_tol: float = 1e-11
    #: iterations of the structured route before it gives up (and the dense route is taken)
    structured_max_sweeps: int = 40
    #: shifts are kept this far (in units of omega) from i k omega, where the trivial pair's copies make Q singular
    structured_lattice_gap: float = 0.02
    #: largest |exponent| (units of omega) of the trivial pair as the block at 0 finds it (exactly 0 split by
    #: round-off into +-sqrt(eps)-sized values by its Jordan block; 1e-8 to 1e-5 measured)
    trivial_nu: float = 1e-4
    #: the shift of the block around the trivial pair (units of omega), and its largest number of sweeps
    zero_shift: complex = 0.03 + 0.03j
    zero_sweeps: int = 12

    # ------------------------------------------------------------------ the reference orbit (reference.py)
    #: steps of DOP853 per unit of omega_max * t (its stability limit along the imaginary axis: h omega_max ~ 3.4)
    reference_step_omega: float = 3.0

    # ------------------------------------------------------------------ shooting's multipliers (shooting_stability.py)
    #: the fewest modes for which the multipliers' eigenproblem runs in the worker threads beside the next steps.
    #: Below, the eigenproblem is too small a part of a point to pay for the hand-over and the points computed ahead
    #: in vain at the end (measured, 13-40 points, workers on / off: beam n = 70-300 0.14/0.12 .. 0.73/0.68 s, plate
    #: n = 300 0.55/0.47 s; plate n = 550 1.24/1.69 s, aircraft n = 548 4.63/7.21 s)
    background_min_n: int = 400
    #: the half-period map is kept as diagonal + low rank (lowrank.py) when its rank, n_s x the stages x the steps of half a
    #: period, is at most this share of n: the Krein follower's shifted solves then skip the n x n LU (setup
    #: O(n r^2) against O(n^3 / 3))
    low_rank_share: float = 1.0 / 3.0
    #: quarter-period shooting's half-period map dq(T/2)/dq0 for the multipliers: "reversible" from the accepted point's
    #: quarter-period sweep (integrators/gauss.py reversible_half_block: Gauss schemes; about half the cost), "sweep"
    #: by a sensitivity sweep over T/2 (the reference route; Newmark always)
    half_map: str = "reversible"
    #: ... the reversible route is taken when the quarter residual |q(T/4)| is at most this fraction of |q0| (its A11
    #: differs from the sweep's by about that, relative: tests/test_quarter_period.py)
    reversible_residual: float = 1e-7
    #: Ritz pairs of the Woodbury shift-invert Arnoldi are trusted up to this residual ||A x - c x|| / ||x||
    #: (relative to max(1, max |diag A|)); above it the call counts as failed (local_collision: the shift's real
    #: part, then the full spectrum)
    arnoldi_residual_tol: float = 1e-9
    #: restarts of the Krein follower's shift-invert Arnoldi (ARPACK's maxiter; its default, 10 n, let a complex
    #: shift far from a dense real spectrum run for hours at n = 2,200: the k nearest eigenvalues all lie at nearly
    #: the same distance).  Converged calls take a few restarts, slow ones ~20 (measured at n = 2,200)
    arpack_restarts: int = 50


#: the orbit layer's settings (the defaults above, written once)
ORBITS = OrbitSettings()
