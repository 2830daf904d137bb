"""Issue 53, finding 5: the Compute tab's time left is an estimate from the recent pace, checked on
canned progress sequences against the time the sequence actually took; no number during a stall."""
import numpy as np
import pytest

from nnm_viewer.eta import time_left
from nnm_viewer.worker import JobProgress


def geometric_run(n_total, dt, e0=1e-3, e_end=10.0):
    """A run whose points arrive every dt s with even steps in log E, reaching e_end at its last point."""
    times = dt * np.arange(1, n_total + 1)
    energies = e0 * (e_end / e0) ** (np.arange(n_total) / (n_total - 1))
    return times, energies


def test_steady_pace_predicts_the_remaining_time():
    """Even steps in log E, one point per 2 s: after 10 of 30 points the energy end is 20 points
    (40 s) away, which the run then takes; the points end (100) is further."""
    times, energies = geometric_run(30, 2.0)
    for k in (5, 10, 20, 29):
        est = time_left(times[:k], energies[:k], times[k - 1], 10.0, 100)
        assert est.by == "energy"
        assert est.seconds == pytest.approx(times[-1] - times[k - 1], rel=1e-9)
    # the points end when it comes first: 40 points at most -> 30 left at 2 s each
    est = time_left(times[:10], energies[:10], times[9], 1e6, 40)
    assert est.by == "points" and est.seconds == pytest.approx(60.0)


def test_slowdown_is_seen_from_the_recent_points_not_the_average():
    """Issue 53's case: 90 % of the way in log E in 10 quick points, then each point takes 10 s.
    The average pace said 'about 2 s left' for a minute; the recent pace says what is left."""
    quick = np.arange(1, 11) * 1.0
    slow = quick[-1] + 10.0 * np.arange(1, 8)
    times = np.concatenate([quick, slow])
    e_end = 10.0
    logs = np.concatenate([np.linspace(np.log(1e-3), np.log(e_end) - 0.1 * np.log(1e4), 10),
                           np.log(e_end) - 0.1 * np.log(1e4) + 0.01 * np.log(1e4) * np.arange(1, 8)])
    energies = np.exp(logs)
    k = len(times)
    est = time_left(times, energies, times[-1], e_end, 200)
    # 3 % of the log-E way left at 1 % per 10 s: 30 s
    assert est.by == "energy" and est.seconds == pytest.approx(30.0, rel=1e-6)
    overall = times[-1] * (1 - (logs[-1] - logs[0]) / (np.log(e_end) - logs[0])) / \
        ((logs[-1] - logs[0]) / (np.log(e_end) - logs[0]))
    assert overall < 3.0 and est.seconds > 9 * overall       # what the old estimate said
    assert k == 17


def test_a_stall_gives_no_number_and_says_how_long_it_has_waited():
    times, energies = geometric_run(30, 2.0)
    t_last = times[9]
    # a wait within the recent pace: the open interval already lengthens the estimate
    est = time_left(times[:10], energies[:10], t_last + 4.0, 10.0, 100)
    assert est.seconds == pytest.approx(20 * 2.0 * (12 + 4) / 12)
    # three recent intervals without a point: the pace is refuted
    est = time_left(times[:10], energies[:10], t_last + 6.5, 10.0, 100)
    assert est.seconds is None and est.by == "stalled" and est.wait == pytest.approx(6.5)
    p = JobProgress(points=10, max_points=100, energy_fraction=0.3, elapsed=t_last + 6.5, left=est)
    assert p.eta is None and "no new point for 6 s: time left unknown" in p.text() and " left at" not in p.text()


def test_points_arriving_together_are_not_a_stall_within_the_poll():
    """Points read in one poll share a time stamp: no stall before the poll interval has passed."""
    times = np.array([0.5, 0.5, 0.5, 0.5, 0.75, 0.75])
    energies = np.geomspace(1e-3, 1e-2, 6)
    assert time_left(times, energies, 0.8, 1.0, 50, resolution=0.25).seconds is not None
    assert time_left(times, energies, 1.6, 1.0, 50, resolution=0.25).by == "stalled"


def test_energy_not_growing_leaves_the_points_end():
    """In a tongue or past a fold the energy does not grow over the recent points: the energy end is
    unknown and the estimate is to max_points (an upper bound the job cannot exceed)."""
    times = np.arange(1, 13) * 1.5
    energies = np.concatenate([np.geomspace(1e-3, 1.0, 6), [1.0, 0.9, 0.95, 0.8, 0.85, 0.99]])
    est = time_left(times, energies, times[-1], 10.0, 20)
    assert est.by == "points" and est.seconds == pytest.approx(8 * 1.5) and est.bound
    text = JobProgress(points=12, max_points=20, energy_fraction=0.75, elapsed=18.0, left=est).text()
    assert "at most 8 more points, about 12 s at the recent pace (the energy is not growing)" in text
    # the points end reached first while the energy grows: an estimate, not a bound
    times, energies = geometric_run(30, 2.0)
    est = time_left(times[:10], energies[:10], times[9], 1e6, 40)
    assert est.by == "points" and not est.bound
    assert time_left(times[:2], energies[:2], times[1], 10.0, 20).seconds is None
    assert time_left([], [], 3.0, 10.0, 20).by == "too few points"


def test_done_job_says_no_time_left():
    times, energies = geometric_run(30, 2.0)
    est = time_left(times[:10], energies[:10], times[9], 10.0, 100)
    assert JobProgress(points=10, max_points=100, energy_fraction=0.3, elapsed=20.0, left=est).eta == \
        pytest.approx(40.0)
    assert JobProgress(points=10, max_points=100, energy_fraction=0.3, elapsed=20.0, left=est, done=True).eta is None


#: a real run (issue 53, finding 5): the shipped aircraft's mode 11 to 100 J with the Compute tab's defaults, 39 points
#: in 88.2 s (load 7-8 on 2 cores): when each point arrived (s after Start) and its energy (J).  Points 9 and 10 took
#: 15 and 31 s; from point 12 on the branch is in a 5:1 tongue, its energy flat, until it climbs to 100 J at the end.
MODE11_TIMES = [7.07, 7.61, 8.04, 8.49, 8.91, 9.57, 11.09, 12.45, 27.81, 58.68, 64.49, 65.41, 66.21, 66.76, 67.39,
                67.93, 68.38, 68.82, 69.73, 70.29, 71.08, 71.54, 72.11, 72.77, 73.26, 73.98, 74.53, 75.01, 77.95, 79.3,
                80.06, 81.69, 82.35, 83.07, 83.7, 84.29, 85.01, 85.93, 88.24]
MODE11_ENERGIES = [0.2631, 0.5921, 1.16, 2.274, 4.457, 8.735, 17.11, 33.53, 37.67, 38.47, 38.88, 39.08, 39.18, 39.23,
                   39.27, 39.3, 39.31, 39.32, 39.32, 39.28, 39.16, 39.02, 38.94, 38.86, 38.7, 38.46, 38.12, 37.66, 37.24,
                   37.02, 36.86, 36.87, 36.94, 37.09, 37.64, 39.46, 45.76, 68.8, 100.0]


def old_estimate(times, energies, now, energy_max, max_points):
    """The estimate issue 53 found wanting: the average pace since Start, to the nearer end."""
    n, e = len(times), np.maximum.accumulate(energies)
    f = np.log(e[-1] / e[0]) / np.log(energy_max / e[0])
    etas = [(max_points - n) * now / n] + ([now * (1 - f) / f] if 0 < f < 1 else [])
    return min(etas)


def test_a_real_run_never_shows_a_time_left_that_the_wait_has_already_refuted():
    """Replayed second by second: a number shown is never shorter than the time the current point has already taken
    (the old estimate was, through both long waits: '2 s left' 10 s into a 15-s point); during the waits the text says
    how long the job has waited."""
    t, E = np.array(MODE11_TIMES), np.array(MODE11_ENERGIES)
    refuted_old, unknown = 0, []
    for now in np.arange(9.0, t[-1], 0.5):
        k = int(np.sum(t <= now))
        wait = now - t[k - 1]
        est = time_left(t[:k], E[:k], now, 100.0, 500, resolution=0.25)
        assert est.seconds is None or est.seconds >= wait, (now, est)
        refuted_old += old_estimate(t[:k], E[:k], now, 100.0, 500) < wait
        if est.seconds is None:
            unknown.append(now)
            text = JobProgress(points=k, max_points=500, energy_fraction=0.5, elapsed=now, left=est).text()
            assert f"no new point for {int(round(wait))} s" in text or wait < 1
    assert refuted_old > 40                                  # the old estimate, on the same run
    assert any(20 <= u <= 27 for u in unknown) and any(40 <= u <= 58 for u in unknown)   # both long waits
    # inside the tongue (energy flat, points every ~0.6 s) the number is the points end, said as such
    k = int(np.sum(t <= 75.0))
    est = time_left(t[:k], E[:k], 75.0, 100.0, 500, resolution=0.25)
    assert est.by == "points" and est.bound
