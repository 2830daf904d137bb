"""Natural-parameter continuation in ln p (continuation/natural.py): the skeleton's, its guide's and its sheets'
stepping."""
import math

import numpy as np

from nnm_solver.continuation.natural import LogStepper, LogSteps


def _solve_cubic_root(p, guess):
    """u with u^3 + u = p (Newton from the guess, as the callers' fixed-parameter corrector), None if far."""
    u = np.array(guess, dtype=float)
    for _ in range(30):
        du = -(u ** 3 + u - p) / (3 * u ** 2 + 1)
        u = u + du
        if abs(du[0]) < 1e-14:
            return u
    return None


def test_secant_predictor_in_ln_p_and_the_exact_solution():
    st = LogStepper(_solve_cubic_root, LogSteps(1.1, 1.001, 1.5))
    pts = [(1.0, _solve_cubic_root(1.0, [0.5]))]
    for _ in range(20):
        p, u = st.trial(pts)
        assert u is not None and abs(u[0] ** 3 + u[0] - p) < 1e-12
        st.accept(2.0)
        pts.append((p, u))
    assert math.isclose(pts[-1][0] / pts[-2][0], 1.5)             # grew to ratio_max and stayed
    # the secant through the last two points in ln p is exact for a line in ln p, closer than the last point
    p = pts[-1][0] * 1.2
    guess = st.predict(pts, p)
    exact = _solve_cubic_root(p, pts[-1][1])
    assert abs(guess[0] - exact[0]) < 0.5 * abs(pts[-1][1][0] - exact[0])


def test_refusals_halve_the_step_down_to_its_smallest_and_growth_is_bounded():
    st = LogStepper(_solve_cubic_root, LogSteps(1.5, 1.01, 2.0, grow_max=1.5))
    halvings = 0
    while st.shorter():
        halvings += 1
    assert st.ratio == 1.01 and halvings == 6                    # 0.5, 0.25, ..., 0.015625 -> 0.01
    st.accept(100.0)
    assert math.isclose(st.ratio, 1.015)                         # ratio - 1 grown by grow_max at most
    st.accept(1e-9)
    assert st.ratio == 1.01                                      # never below ratio_min
    st.accept(10.0, cap=1.012)
    assert st.ratio == 1.012


def test_a_restart_steps_from_the_last_point_alone_and_steps_go_down_too():
    st = LogStepper(_solve_cubic_root, LogSteps(1 / 1.01, 1 / 1.01, 1 / 1.01), scaled_first=slice(0, 1))
    pts = [(2.0, np.array([1.0])), (1.0, np.array([0.5]))]
    st.restart()
    assert np.allclose(st.predict(pts, 0.5), [0.25])              # the last point scaled with p (scaled_first)
    st.accept(1.0)
    p, u = st.trial(pts)
    assert math.isclose(p, 1.0 / 1.01) and abs(u[0] ** 3 + u[0] - p) < 1e-12

