"""The driver's public iterator API (iter_nnm), the background job and the element module."""
import threading

import numpy as np
import pytest

import nnm_solver as nnm
from conftest import duffing_model, two_dof_model


@pytest.mark.parametrize("method", ["shooting", "hb"])
def test_iter_nnm_equals_continue_nnm(method):
    m = two_dof_model()
    opts = dict(harmonics=9) if method == "hb" else {}
    ref = nnm.continue_nnm(m, 1, 10.0, method=method, max_points=200, **opts)
    it = nnm.iter_nnm(m, 1, 10.0, method, max_points=200, **opts)
    pts = list(it)
    assert len(pts) == len(ref) and it.status == ref.status == "done"
    np.testing.assert_allclose([p.energy for p in pts], ref.energy, rtol=1e-12)
    np.testing.assert_allclose([p["frequency_hz"] for p in pts], ref.frequency_hz, rtol=1e-12)
    b = it.branch()
    assert b.settings.method == ref.settings.method and b.status == "done"
    assert (b.coefficients is not None) == (method == "hb")


def test_own_stopping_rule_is_a_break():
    m = duffing_model(1.0)
    it = nnm.iter_nnm(m, 1, 1e3)
    f0 = None
    for p in it:
        f0 = f0 or p.frequency_hz
        if p.frequency_hz > 1.1 * f0:
            break
    b = it.branch()
    assert b.status == "stopped" and "caller" in b.message
    assert b.frequency_hz[-1] > 1.1 * f0 >= b.frequency_hz[-2]
    with pytest.raises(StopIteration):
        next(it)


def test_method_options_are_checked():
    m = two_dof_model()
    with pytest.raises(nnm.NNMInputError, match="belongs to method='hb'"):
        nnm.iter_nnm(m, 1, 1.0, harmonics=5)
    with pytest.raises(nnm.NNMInputError, match="method must be one of"):
        nnm.iter_nnm(m, 1, 1.0, method="collocation")
    with pytest.raises(nnm.NNMInputError, match="steps_per_period"):
        nnm.iter_nnm(m, 1, 1.0, steps_per_period=4)


def test_start_branch_on_point_and_queue():
    m = two_dof_model()
    seen = []
    job = nnm.start_branch(m, 1, 5.0, on_point=seen.append, max_points=30)
    b = job.result(timeout=120)
    streamed = []
    while True:
        p = job.queue.get(timeout=5)
        if p is None:
            break
        streamed.append(p)
    assert len(seen) == len(streamed) == len(b) > 3
    np.testing.assert_array_equal([p.energy for p in streamed], b.energy)
    assert isinstance(seen[0], nnm.Point)


def test_running_snapshot_orbit_equals_final_orbit():
    """A snapshot of a running job rebuilds orbits with the branch's own settings (half period)."""
    m = two_dof_model()
    gate = threading.Event()
    got = threading.Event()
    count = [0]

    def slow(point):
        count[0] += 1
        if count[0] == 6:
            got.set()
            gate.wait(60)       # hold the job while the snapshot is taken

    job = nnm.start_branch(m, 1, 1e3, on_point=slow, max_points=40)
    assert got.wait(120)
    snap = job.points()
    assert snap.status == "running" and len(snap) >= 6
    assert snap.settings.symmetric and snap.settings.steps_per_period == 100     # gauss6 default (integrators/registry.py)
    t_s, x_s = snap.motion(5, 64)
    gate.set()
    final = job.result(timeout=120)
    t_f, x_f = final.motion(5, 64)
    np.testing.assert_array_equal(x_s, x_f)
    np.testing.assert_array_equal(t_s, t_f)


def test_branch_extend_matches_from_points():
    b = nnm.continue_nnm(two_dof_model(), 1, 5.0, max_points=20)
    pts = [b.point(i) for i in range(len(b))]
    grown = nnm.Branch.from_points(b.model, b.mode, pts[:7], settings=b.settings, status="running")
    grown.extend(pts[7:])
    np.testing.assert_array_equal(grown.energy, b.energy)
    np.testing.assert_array_equal(grown.floquet, b.floquet)
    assert grown.events == b.events


def test_settings_read_like_the_first_release_dicts():
    s = nnm.ShootingSettings(steps_per_period=100)
    assert s["steps_per_period"] == 100 and s["method"] == "shooting" and s.get("harmonics") is None
    old = nnm.Branch(two_dof_model(), 1, [1.0], [0.2], [5.0], np.zeros((1, 2)), np.zeros((1, 2)),
                     settings={"method": "shooting", "steps_per_period": 100, "tol": 1e-6})
    assert isinstance(old.settings, nnm.ShootingSettings) and old.settings.symmetric is False
    with pytest.raises(nnm.NNMInputError, match="unknown branch method"):
        nnm.Branch(two_dof_model(), 1, [], [], [], [], [], settings={"method": "magic"})


def test_element_force_tangent_potential_are_consistent():
    m = nnm.Model(np.eye(3), np.diag([1.0, 2.0, 3.0]),
                  [nnm.CubicSpring(dof=0, k3=2.0), nnm.CubicSpring(dof=1, other=2, k3=-0.5)])
    el = m.elements
    rng = np.random.default_rng(1)
    d = rng.normal(size=(5, 2))
    h = 1e-6
    np.testing.assert_allclose(el.tangent(d), (el.force(d + h) - el.force(d - h)) / (2 * h), rtol=1e-7)
    np.testing.assert_allclose(el.force(d), (el.potential(d + h) - el.potential(d - h)) / (2 * h), rtol=1e-7)
    x = rng.normal(size=3)
    # f_nl is the gradient of the model's potential energy
    grad = np.array([(m.energy(x + h * e, np.zeros(3)) - m.energy(x - h * e, np.zeros(3))) / (2 * h)
                     for e in np.eye(3)])
    np.testing.assert_allclose(grad, m.K @ x + m.nonlinear_force(x), rtol=1e-7)
    assert el.odd


def test_hb_coefficients_recomputed_for_first_release_branches():
    m = two_dof_model()
    b = nnm.hb.continue_nnm_hb(m, 1, 5.0, harmonics=9, max_points=15)
    old = nnm.Branch(m, 1, b.energy, b.frequency_hz, b.period, b.x0, b.v0, b.floquet, b.stable,
                     settings=b.settings.as_dict())          # no coefficients, as in first-release files
    _, _, X = nnm.hb.hb_coefficients(old, 10)
    np.testing.assert_allclose(X, b.coefficients[10], atol=1e-8 * np.abs(X).max())
