"""switch_branch shoots the family born at a branch point with its parent's integrator and steps; from a
harmonic-balance parent (no integrator of its own) with the defaults, Shooting() (gauss6 at 100 steps), not the first
release's Newmark at 200 (found by the second-day trial of issue 53)."""
import numpy as np

import nnm_solver as nnm


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


def test_family_switched_from_a_harmonic_balance_parent_is_shot_with_the_defaults():
    hb = nnm.continue_nnm(two_dof(), 1, 50.0, nnm.HarmonicBalance(harmonics=9, freq_tol=None))
    event = next(e for e in hb.events if e["kind"] == "branch_point")
    assert abs(event["energy"] / 40.9748 - 1) < 1e-3                  # the benchmark's pitchfork
    born = nnm.switch_branch(hb, event, 80.0, max_points=4)
    assert (born.settings.integrator, born.settings.steps_per_period) == (nnm.Shooting().integrator, 100)
    assert len(born) >= 2
    # the new family leaves the symmetric one: the two masses no longer move as the parent's orbit
    assert not np.allclose(born.x0[-1] / np.linalg.norm(born.x0[-1]), event["x0"] / np.linalg.norm(event["x0"]),
                           atol=1e-3)


def test_no_branch_of_a_fep_plot_is_drawn_in_a_colour_that_means_something_else():
    """plot_fep's branch colours leave out the off-backbone orange and the event markers' colours (the second
    branch of tutorial section 2's fep.png was orange, the colour of the points inside a tongue)."""
    from matplotlib.colors import to_rgb

    from nnm_solver.results.plotting import BRANCH_COLORS, EVENT_MARKERS, OFF_BACKBONE_COLOR
    meaning = {to_rgb(OFF_BACKBONE_COLOR)} | {to_rgb(c) for _, c in EVENT_MARKERS.values()}
    assert len(set(map(to_rgb, BRANCH_COLORS))) == len(BRANCH_COLORS)
    assert not meaning & set(map(to_rgb, BRANCH_COLORS))
