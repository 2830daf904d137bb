"""App logic in-process: a Session on a real viser server (no browser), driven by setting
handle values like a user would; background jobs streamed into the shared state."""
import queue
from pathlib import Path
import time

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_viewer.controls import Session
from nnm_viewer.demo import two_box_model, write_demo_file
from nnm_viewer.glb import read_glb_json
from nnm_viewer.state import SharedState

viser = pytest.importorskip("viser")


@pytest.fixture(scope="module")
def demo_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("viewer") / "two.h5"
    write_demo_file(path, energy_max=10.0)
    return path


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def make_session(server, path, start_job=None):
    model = nnm.load_model(path)
    shared = SharedState(model, path=path, branches=nnm.load_branches(path))
    return Session(server, shared, sync=True, start_job=start_job), shared


def wait_for(cond, timeout=10.0):
    t0 = time.time()
    while not cond():
        if time.time() - t0 > timeout:
            raise AssertionError("timed out")
        time.sleep(0.01)


class FakeJob:
    """A job with the solver's Job contract (``queue`` of Points, then None once it has ended;
    ``settings``, ``progress``, ``cancel``, ``result``) whose points are released by the test."""

    def __init__(self, branch, error=None):
        self.branch, self.n, self.error_after = branch, 0, error
        self.done, self.error, self.cancelled = False, None, False
        self.queue = queue.Queue()
        self.settings = branch.settings

    @property
    def progress(self):
        return self.n / len(self.branch)

    def release(self, k):
        new = min(self.n + k, len(self.branch))
        for i in range(self.n, new):
            self.queue.put(self.branch.point(i))
        self.n = new

    def points(self):
        return self.branch.subset(slice(0, self.n))

    def _end(self):
        if not self.done:
            self.done = True
            self.queue.put(None)

    def cancel(self):
        self.cancelled = True
        self._end()

    def fail(self):
        self.error = self.error_after
        self._end()

    def result(self, timeout=None):
        if self.error is not None:
            raise self.error
        return self.points()


def test_initial_state_selection_and_animation(server, demo_file):
    s, shared = make_session(server, demo_file)
    assert len(shared.entries) == 2
    assert s.sel_uid == shared.entries[0].uid and s.s == 0.0
    assert s.h_branch.value.startswith("1: NNM 1")
    assert "branch 1, point 1 of 57" in s.h_sel.content
    js = read_glb_json(s.last_glb)
    assert "animations" in js and js["meshes"][0]["primitives"][0]["targets"]
    assert "peak displacement" in s.h_peak.content
    assert "Hz" in s.h_info.content and "MAC" in s.h_info.content
    assert len(s._board_handles) == 2                     # one clickable batch per branch
    s.close()


def test_one_energy_for_the_point_shown_in_every_place(server, demo_file):
    """Issue 32, finding (a): between two computed points the readout under the panel FEP, the selection
    text, the FEP marker and the Point tab all give the energy of the orbit shown, Branch.interpolate's
    (linear in energy between the neighbours); the readout used to interpolate in log energy (0.912 J
    there against 0.9573 J in the Point tab).  The energy slider picks the orbit of the energy it shows,
    also at a scaled k3 (energies / factor)."""
    s, shared = make_session(server, demo_file)
    e = shared.entries[1]
    E = e.branch.energy
    j = int(np.argmax(E[1:] / E[:-1]))               # the widest energy step: log and linear differ most
    along = j + 0.5
    s.pick(e.uid, j)
    s.h_along.value = along + 1                       # the slider gives the point's number, 1-based
    orbit = e.branch.interpolate(along).energy[0]
    assert abs(orbit / np.sqrt(E[j] * E[j + 1]) - 1) > 0.01   # the old readout's value is another number
    shown = f"{orbit:.4g} J"
    assert s.current_point.energy == pytest.approx(orbit, rel=1e-12)
    assert f"E = {shown}" in s.h_readout.content and f"E = {shown}" in s.h_sel.content
    assert f"energy **{shown}**" in s.h_info.content
    assert s.drawing.fep.selected_point()[0] == pytest.approx(orbit, rel=1e-12)
    for k3 in (0.0, 1.0):                             # k3 x 1, then x 10 (scaling law: energies / 10)
        s.h_k3.value = k3
        target = round(float(np.log10(E[j] * E[j + 1])) / 2 - k3, 2)
        s.h_energy.value = target
        assert j <= s.s <= j + 1
        assert s.current_point.energy == pytest.approx(10 ** target, rel=1e-6)
        shown = f"{s.current_point.energy:.4g} J"
        assert f"E = {shown}" in s.h_readout.content and f"E = {shown}" in s.h_sel.content
        assert f"energy **{shown}**" in s.h_info.content
    s.close()


def test_panel_fep_says_it_is_not_clickable(server, demo_file):
    """Issue 32, finding (i): clicks on the panel FEP image never reach the server (viser 1.1); the caption
    right under it says so and where to pick points instead."""
    s, _ = make_session(server, demo_file)
    text = s.h_fep_caption.content
    assert "not clickable" in text and "board" in text and "Energy" in text and "Along branch" in text
    assert s.h_energy.label.startswith("Energy") and s.h_along.label.startswith("Along branch")
    assert s.h_fep.order < s.h_fep_caption.order < s.h_readout.order
    s.close()


def test_pick_energy_and_along_sliders(server, demo_file):
    s, shared = make_session(server, demo_file)
    b2 = shared.entries[1]
    s.pick(b2.uid, 5)                                      # click on point 5 of branch 2 in the scene
    assert s.sel_uid == b2.uid and s.s == 5.0
    assert s.h_branch.value.startswith("2: NNM 2") and "branch 2, point 6 of 48" in s.h_sel.content
    assert s.h_along.value == 6.0 and s.h_along.min == 1.0 and s.h_along.max == 48.0   # one numbering
    assert "point 6 of 48" in s.h_readout.content and "point 6 of 48" in s.h_info.content
    E = b2.branch.energy
    assert s.h_energy.value == pytest.approx(np.log10(E[5]), abs=0.006)
    # energy slider: selection moves along the branch, the along slider follows
    target = 0.5 * (np.log10(E[7]) + np.log10(E[8]))
    s.h_energy.value = round(target, 2)
    assert 7.0 <= s.s <= 8.0
    assert s.h_along.value == pytest.approx(round(s.s + 1, 2))
    assert f"point {s.s + 1:.2f} of 48" in s.h_sel.content            # between two computed points
    assert s.current_point.energy == pytest.approx(10 ** target, rel=0.1)
    # along slider: the energy slider follows
    s.h_along.value = 3.0                                  # point 3: row 2
    assert s.s == 2.0 and s.h_energy.value == pytest.approx(np.log10(E[2]), abs=0.006)
    # branch dropdown
    s.h_branch.value = s.h_branch.options[0]
    assert s.sel_uid == shared.entries[0].uid and s.s == 0.0
    s.close()


def test_animation_controls(server, demo_file):
    s, _ = make_session(server, demo_file)
    s.pick(s.sel_uid, 10)
    amp_auto, peak = s.amplification()
    assert peak > 0 and amp_auto * peak == pytest.approx(0.12 * s.geom.size)
    s.h_auto.value = False
    s.h_amp.value = 1.0
    assert s.amplification()[0] == pytest.approx(10.0)
    assert "x10" in s.h_peak.content
    s.h_speed.value = 2.0
    js = read_glb_json(s.last_glb)
    t_acc = js["accessors"][js["animations"][0]["samplers"][0]["input"]]
    assert t_acc["max"][0] == pytest.approx(0.5)           # one cycle in 1/speed s
    s.h_play.value = False
    assert s.h_phase.visible and "animations" not in read_glb_json(s.last_glb)
    s.close()


def test_stiffness_slider_uses_exact_scaling_law(server, demo_file):
    s, shared = make_session(server, demo_file)
    s.pick(s.sel_uid, 12)
    pd1 = s.current_point
    peak1 = s.amplification()[1]
    s.h_k3.value = 1.0                                     # every k3 x 10
    pd10 = s.current_point
    assert pd10.frequency == pytest.approx(pd1.frequency)
    assert pd10.energy == pytest.approx(pd1.energy / 10)
    assert np.max(np.abs(pd10.x)) == pytest.approx(np.max(np.abs(pd1.x)) / np.sqrt(10))
    assert s.amplification()[1] == pytest.approx(peak1 / np.sqrt(10))
    assert "E = " in s.h_sel.content and not s.h_recompute.disabled
    assert s.scaling_law and s.last_runner is None and shared.job is None     # no job: Recompute confirms
    assert s.h_k3.label == "k3 factor log10" and "cubic springs only" not in s.h_k3_text.content
    # the scaled branch agrees with Branch.scaled of the solver
    ref = shared.entries[0].branch.scaled(10.0)
    assert shared.entries[0].series(10.0).energy == pytest.approx(ref.energy)
    s.close()


def test_recompute_confirms_scaling_and_save_keeps_file(server, demo_file, tmp_path):
    path = tmp_path / "copy.h5"
    path.write_bytes(demo_file.read_bytes())
    s, shared = make_session(server, path)
    s.h_k3.value = 1.0
    s._cb(s._on_recompute)(None)
    job = s.last_runner
    assert job is not None and not s.h_error.visible
    job.finished.wait(60)
    new = shared.entries[-1]
    assert new.k3_factor == pytest.approx(10.0) and new.source == "computed" and not new.saved
    assert s.sel_uid == new.uid
    # recomputed frequencies vs the scaled file branch, at the same energies
    old = shared.entries[0].series(10.0)
    le_new = np.log10(new.branch.energy)
    inside = (np.log10(old.energy) > le_new.min()) & (np.log10(old.energy) < le_new.max())
    f_interp = np.interp(np.log10(old.energy[inside]), le_new, new.branch.frequency_hz)
    assert inside.sum() >= 3
    assert f_interp == pytest.approx(old.frequency[inside], rel=2e-3)
    # save: the branch is mapped back to the file's k3 and appended; the file keeps the rest
    s._cb(s._on_save)(None)
    assert new.saved and "saved" in s.h_status.content and new.label.endswith("[saved]")
    branches = nnm.load_branches(path)
    assert len(branches) == 3
    np.testing.assert_allclose(branches[2].model.k3, nnm.load_model(path).k3)
    np.testing.assert_allclose(branches[2].energy, new.branch.energy * 10.0)
    s.close()


def test_job_streams_points_stop_keeps_them(server, demo_file):
    model = nnm.load_model(demo_file)
    full = nnm.load_branches(demo_file)[0]
    fake = FakeJob(full)
    s, shared = make_session(server, demo_file, start_job=lambda m, mode, energy_max, **kw: fake)
    s.h_mode.value = s.h_mode.options[0]
    s._cb(s._on_start)(None)
    runner = shared.job
    runner.poll = 0.01
    entry = runner.entry
    assert entry.source == "running" and len(entry) == 0
    assert not s.h_stop.disabled and s.h_start.disabled
    fake.release(4)
    wait_for(lambda: len(entry) == 4)
    wait_for(lambda: s.h_branch.value.endswith("(4 pts)"))
    assert s.sel_uid == entry.uid and s.current_point is not None   # first points shown at once
    wait_for(lambda: abs(s.h_progress.value - 100 * 4 / len(full)) < 1)
    fake.release(3)
    wait_for(lambda: len(entry) == 7)
    s._cb(s._on_stop)(None)
    runner.finished.wait(5)
    assert fake.cancelled and entry.source == "stopped" and len(entry) == 7
    assert s.h_stop.disabled and not s.h_start.disabled and not s.h_save.disabled
    assert model.n == 2
    s.close()


def test_solver_error_is_shown_in_page_and_server_keeps_running(server, demo_file):
    full = nnm.load_branches(demo_file)[0]
    fake = FakeJob(full, error=RuntimeError("Newton diverged at point 3"))
    s, shared = make_session(server, demo_file, start_job=lambda m, mode, energy_max, **kw: fake)
    s._cb(s._on_start)(None)
    shared.job.poll = 0.01
    fake.release(3)
    runner = shared.job
    wait_for(lambda: len(runner.entry) == 3)
    fake.fail()
    runner.finished.wait(5)
    assert "Newton diverged" in shared.error and "3 points kept" in shared.error
    assert s.h_error.visible and "Newton diverged" in s.h_error.content
    assert len(runner.entry) == 3 and runner.entry.source == "failed"
    s._cb(s._dismiss_error)(None)
    assert not s.h_error.visible
    # bad input from the solver (mode out of range): one line in the page, nothing crashes
    s2, _ = make_session(server, demo_file)
    s2._cb(lambda _: s2._start(5, 10.0, 1.0))(None)
    assert s2.h_error.visible and "mode 5" in s2.h_error.content
    s.h_along.value = 2.0                                 # the session still works
    assert s.s == 1.0
    s.close()
    s2.close()


def test_two_tabs_are_independent_but_share_branches(server, demo_file):
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file))
    a = Session(server, shared, sync=True)
    b = Session(server, shared, sync=True)
    a.pick(shared.entries[1].uid, 3)
    assert b.sel_uid == shared.entries[0].uid and b.s == 0.0
    shared.add(shared.entries[0].branch.subset(slice(0, 5)), source="computed", saved=False)
    assert a.h_branch.options == b.h_branch.options and len(a.h_branch.options) == 3
    assert a.sel_uid == shared.entries[1].uid               # a new branch does not steal the selection
    a.close()
    b.close()


def test_model_without_mesh_gets_fallback_boxes(server, tmp_path):
    m = two_box_model()
    bare = nnm.Model(m.M, m.K, m.springs, name="bare")
    path = tmp_path / "bare.h5"
    nnm.save_model(path, bare)
    nnm.save_branch(path, nnm.continue_nnm(bare, mode=1, energy_max=1.0, max_points=8))
    s, _ = make_session(server, path)
    js = read_glb_json(s.last_glb)
    assert js["accessors"][0]["count"] == 16                # two boxes of 8 vertices
    s.close()


def test_point_tab_charts_and_dof_choice(server, demo_file):
    s, _ = make_session(server, demo_file)
    s.pick(s.sel_uid, 15)
    h_time, n = s._charts["time"]
    assert n == 1 + 1                                     # t/T + the spring DOF ('auto')
    assert len(h_time.data[0]) == len(h_time.data[1]) and h_time.data[0][-1] == 1.0
    assert 1.0 <= np.max(np.abs(h_time.data[1])) < 1000.0        # shown in m, mm, µm or nm
    s.h_dofs.value = "0, 1"
    h_time, n = s._charts["time"]
    h_harm, _ = s._charts["harm"]
    assert n == 3 and len(h_harm.data) == 3
    a1 = h_harm.data[1]                                   # log10 amplitudes of DOF 0
    assert a1[1] == a1.max() and a1[3] > a1[2]              # odd harmonics of the cubic spring
    s.h_dofs.value = "9"
    assert s.h_error.visible and "DOF 9 does not exist" in s.h_error.content
    s.close()


def test_zoom_fits_the_selected_branch(server, demo_file):
    s, shared = make_session(server, demo_file)
    full = s._view_ranges(*s._series())
    s.pick(shared.entries[1].uid, 2)
    s.h_zoom.value = True
    zoomed = s._view_ranges(*s._series())
    f2 = shared.entries[1].branch.frequency_hz
    assert zoomed[1][0] > full[1][0] and zoomed[1][0] < f2.min()  # frequency axis fitted to NNM 2
    assert s._board_handles[shared.entries[0].uid] is None          # other branches hidden on the board
    s.close()


def test_start_animates_the_new_branch_not_the_old_pick(server, demo_file, tmp_path):
    """Issue 14a: after Start the scene shows the new branch (at rest until its first point, then
    point 0, then the picked point), while points stream in, after Stop and after Save."""
    path = tmp_path / "copy.h5"
    path.write_bytes(demo_file.read_bytes())
    full = nnm.load_branches(path)[0]
    fake = FakeJob(full)
    s, shared = make_session(server, path, start_job=lambda m, mode, energy_max, **kw: fake)
    s.pick(shared.entries[1].uid, 5)                        # an orbit of NNM 2 is animated
    assert s.current_point.energy == pytest.approx(shared.entries[1].branch.energy[5])
    s._cb(s._on_start)(None)
    runner = shared.job
    runner.poll = 0.01
    entry = runner.entry
    assert s.sel_uid == entry.uid
    assert s.current_point is None and "animations" not in read_glb_json(s.last_glb)   # model at rest
    fake.release(4)
    wait_for(lambda: len(entry) == 4)
    wait_for(lambda: s.h_branch.value.endswith("(4 pts)"))
    assert s.current_point.energy == pytest.approx(full.energy[0])        # the new branch's point 0
    assert "animations" in read_glb_json(s.last_glb)
    s.pick(entry.uid, 2)
    fake.release(3)
    wait_for(lambda: len(entry) == 7)
    wait_for(lambda: s.h_branch.value.endswith("(7 pts)"))
    assert s.current_point.energy == pytest.approx(full.energy[2])        # the picked point stays
    s._cb(s._on_stop)(None)
    runner.finished.wait(5)
    wait_for(lambda: entry.source == "stopped")
    assert s.sel_uid == entry.uid and s.current_point.energy == pytest.approx(full.energy[2])
    s._cb(s._on_save)(None)
    assert entry.saved and s.sel_uid == entry.uid
    assert s.current_point.energy == pytest.approx(full.energy[2])
    s.close()


def test_k3_label_follows_the_slider(server, demo_file):
    """Issue 14b: the label under the k3 slider gives the factor in use."""
    s, _ = make_session(server, demo_file)
    assert s.h_k3_text.content == "k3 x 1 (as in the file)"
    s.h_k3.value = 1.0
    assert "k3 x 10 " in s.h_k3_text.content and "as in the file" not in s.h_k3_text.content
    s.h_k3.value = -0.5
    assert "k3 x 0.316 " in s.h_k3_text.content
    s.h_k3.value = 0.0
    assert s.h_k3_text.content == "k3 x 1 (as in the file)"
    s.close()


def test_point_tab_mac_is_mass_weighted(server, tmp_path):
    """Issue 14c: MAC(x0, phi_k) = (phi_k^T M x0)^2 / ((phi_k^T M phi_k)(x0^T M x0)) with the
    model's mass matrix (here sparse, with unequal masses)."""
    import scipy.sparse as sparse

    M = sparse.diags([1.0, 4.0]).tocsr()
    model = nnm.Model(M, np.array([[3.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)], name="masses")
    path = tmp_path / "masses.h5"
    nnm.save_model(path, model)
    branch = nnm.continue_nnm(model, mode=1, energy_max=1.0, max_points=8)
    nnm.save_branch(path, branch)
    s, _ = make_session(server, path)
    s.pick(s.sel_uid, 6)
    x0 = nnm.load_branches(path)[0].x0[6]
    _, phi = model.linear_modes()
    Md = M.toarray()
    want = (phi.T @ Md @ x0) ** 2 / (np.einsum("ik,ij,jk->k", phi, Md, phi) * (x0 @ Md @ x0))
    unweighted = (phi.T @ x0) ** 2 / ((phi ** 2).sum(axis=0) * (x0 @ x0))
    assert not np.allclose(want, unweighted, atol=1e-3)                 # the weighting matters here
    np.testing.assert_allclose(s.current_point.mac, want, atol=1e-9)
    assert f"| {want[0]:.3f} |" in s.h_info.content
    s.close()


def test_page_is_drawn_while_the_solver_is_prepared(server, demo_file, monkeypatch):
    """Issue 14, item 3 and issue 32, item 4: until the solver's kernels are compiled (warmup.py) a new tab
    draws the branch list, the FEP and the sliders, says "preparing the solver", and animates the selected
    orbit integrated by scipy (Branch.reference_motion: no compiled kernel, no wait for the compiler), which
    the Point tab says; once the kernels are ready, the solver's own orbit replaces it."""
    import nnm_viewer.point_view as pv
    from nnm_solver.results.branch import Branch

    calls, exact = [], []
    real = pv.point_data
    monkeypatch.setattr(pv, "point_data", lambda *a, **k: calls.append(k.get("reference")) or real(*a, **k))
    real_motion = Branch.motion
    monkeypatch.setattr(Branch, "motion", lambda self, *a, **k: exact.append(1) or real_motion(self, *a, **k))
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file), solver_ready=False)
    s = Session(server, shared, sync=True)
    assert s.h_solver.visible and "Preparing the solver" in s.h_solver.content
    assert "Selected:" in s.h_sel.content and len(s.h_branch.options) == 2 and len(s._board_handles) == 2
    assert calls == [True] and not exact                   # the reference orbit, not the integrator's
    assert "animations" in read_glb_json(s.last_glb) and "DOP853" in s.h_info.content
    assert "preparing the solver" in s.h_job.content
    b1 = shared.entries[0].branch
    np.testing.assert_allclose(s.current_point.x, b1.reference_motion(0, samples=len(s.current_point.t))[1])
    b2 = shared.entries[1]
    s.pick(b2.uid, 5)                                     # picking works meanwhile
    assert s.sel_uid == b2.uid and "branch 2, point 6 of 48" in s.h_sel.content and calls == [True, True]
    ref = s.current_point
    shared.set_solver_ready()
    assert not s.h_solver.visible and calls == [True, True, False] and exact
    assert s.current_point.energy == pytest.approx(b2.branch.energy[5]) and "DOP853" not in s.h_info.content
    t, x = real_motion(b2.branch, 5, samples=len(ref.t))
    np.testing.assert_allclose(s.current_point.x, x)
    # the reference orbit was that orbit, to the integrator's discretisation error (Newmark, 2nd order here)
    assert np.abs(ref.x - x).max() < 1e-2 * np.abs(x).max()
    assert "animations" in read_glb_json(s.last_glb) and "preparing" not in s.h_job.content
    s.close()


def test_no_reference_orbit_when_it_would_be_too_slow(server, demo_file, monkeypatch):
    """Issue 32, item 4: when scipy's orbit would take more than info.REFERENCE_MAX_STEPS steps (very high modal
    frequencies) the model stays at rest until the solver's orbit is ready, with no error in the page."""
    import nnm_viewer.info as info

    monkeypatch.setattr(info, "REFERENCE_MAX_STEPS", 1)
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file), solver_ready=False)
    s = Session(server, shared, sync=True)
    assert s.current_point is None and "animations" not in read_glb_json(s.last_glb)
    assert not s.h_error.visible and "preparing the solver" in s.h_info.content
    shared.set_solver_ready()
    assert s.current_point is not None and "animations" in read_glb_json(s.last_glb)
    s.close()


def test_server_warms_the_solver_in_the_background(demo_file):
    """Issue 14, item 3: ViewerApp serves at once and marks the solver ready when the warm-up ends."""
    import threading

    from nnm_viewer.app import ViewerApp
    from nnm_viewer.browser import free_port
    from nnm_viewer.warmup import warm_kernels

    release = threading.Event()
    app = ViewerApp(nnm.load_model(demo_file), nnm.load_branches(demo_file), port=free_port(),
                    warm=lambda: release.wait(10))
    try:
        assert not app.shared.solver_ready.is_set()
        release.set()
        assert app.shared.solver_ready.wait(10) and app.warm_up.error is None
    finally:
        app.stop()
    t0 = time.perf_counter()
    warm_kernels()                                        # the real warm-up runs (kernels cached here)
    assert time.perf_counter() - t0 < 60


def test_orbit_description_names_its_measure_and_single_dofs(server):
    """Issue 14, item 7: inside the 3:1 tongue of the 2-DOF model (shipped two_dof.h5, NNM 1 index 116, on the
    way in at 3.8 kJ) the mass-weighted content is still 'fundamental' (harmonic 1: 89 %) while x1 moves mostly
    at 3 times the frequency: the Point tab says which measure it uses and names x1."""
    from nnm_viewer.examples import example_path

    s, shared = make_session(server, example_path("two_dof.h5"))
    s.pick(shared.entries[0].uid, 116)
    h = s.current_point.harmonics
    assert h[3, 0] > 2 * h[1, 0]                                   # x1: 3rd harmonic > 1st
    text = s.h_info.content
    assert "mass-weighted over all 2 DOFs" in text and "fundamental NNM motion" in text
    line = next(l for l in text.splitlines() if "higher harmonic exceeds the 1st" in l)
    assert "x1" in line and "3rd harmonic is 4." in line and "x2" not in line
    s.pick(shared.entries[0].uid, 40)                              # below the tongue: no such note
    assert "higher harmonic exceeds" not in s.h_info.content
    s.close()


def test_branch_status_and_events_are_shown(server, demo_file, monkeypatch):
    """Issue 14, item 8: how a branch ended (status and the solver's message) and its events (folds,
    bifurcations) are shown in the branch list and under the selection, and marked by kind on the
    panel FEP and on the 3D board."""
    import nnm_viewer.scene as scene

    boards = []
    real = scene.render_board
    monkeypatch.setattr(scene, "render_board", lambda board, ranges, series=(), **k:
                        boards.append(list(series)) or real(board, ranges, series, **k))
    scene._BOARD_CACHE.clear()
    model = nnm.load_model(demo_file)
    b = nnm.load_branches(demo_file)[0].subset(slice(0, 12))
    b.status, b.message = "failed", "no convergence after point 12 (E = 1 J): try a larger steps_per_period"
    b.events = [dict(kind="fold", index=4, energy=float(b.energy[4]), frequency_hz=float(b.frequency_hz[4]),
                     detail="energy maximum"),
                dict(kind="bifurcation", index=7, energy=float(b.energy[7]), frequency_hz=float(b.frequency_hz[7]),
                     detail="loss of stability, multiplier through -1"),
                dict(kind="branch_point", index=9, energy=float(b.energy[9]), frequency_hz=float(b.frequency_hz[9]),
                     detail="loss of stability, multiplier through +1")]
    shared = SharedState(model, path=demo_file, branches=[nnm.load_branches(demo_file)[1], b])
    s = Session(server, shared, sync=True)
    assert s.h_branch.options[1] == "2: NNM 1 (in phase) (12 pts, failed)" and s.h_branch.options[0].endswith("pts)")
    s.pick(shared.entries[1].uid, 3)
    info = s.h_branch_info.content
    assert "failed" in info and "try a larger steps_per_period" in info
    # numbered from 1 as everywhere (issue 53, finding 3): rows 4, 7, 9 are points 5, 8, 10
    assert "1 fold (near point 5)" in info and "1 period doubling (near point 8)" in info
    assert "1 branch point (near point 10)" in info
    # the panel: a marker per event, by kind, and the failed end, with legend entries
    ax = s.drawing.fep.renderer.ax
    legend = [t.get_text() for t in s.drawing.fep.renderer.legend.get_texts()]
    for text in ("fold (energy turns back)", "period doubling (multiplier -1)", "branch point (multiplier +1)",
                 "end: solver failed"):
        assert text in legend
    marks = {(ln.get_marker(), round(float(ln.get_xdata()[0]), 9)) for ln in ax.lines if len(ln.get_xdata()) == 1}
    for i, marker in ((4, "x"), (7, "D"), (9, "s"), (11, "X")):
        assert (marker, round(float(np.log10(b.energy[i])), 9)) in marks
    # the board picture gets the same events and the status
    ser = boards[-1][1]
    assert ser.status == "failed" and [k for k, _, _ in ser.events] == ["fold", "period_doubling", "branch_point"]
    s.close()


def test_branch_colours_are_distinct_with_legends(server, demo_file):
    """Issue 14, item 9: every branch has its own colour (no repeat after 8 branches) on the board and
    in the panel, whose legend names them."""
    from nnm_viewer.fep import BRANCH_COLORS, branch_color
    from nnm_viewer.state import legend_label

    colours = [branch_color(k) for k in range(40)]
    assert colours[:8] == BRANCH_COLORS and len(set(colours)) == 40
    s, shared = make_session(server, demo_file)
    base = shared.entries[0].branch
    for k in range(9):                                      # 11 branches in all
        shared.add(base.subset(slice(k, k + 6)), source="computed", saved=False, notify=False)
    shared.notify("branches")
    firsts = [tuple(s._board_handles[e.uid].batched_colors[0]) for e in shared.entries]
    assert len(set(firsts)) == 11
    assert firsts[9] == tuple(int(branch_color(9)[i:i + 2], 16) for i in (1, 3, 5))
    leg = s.drawing.fep.renderer.legend
    names = [t.get_text() for t in leg.get_texts()]
    assert names[:11] == [legend_label(e.label) for e in shared.entries]
    assert names[0] == "NNM 1" and shared.entries[0].label == "NNM 1 (in phase)"   # the mode label: in the lists
    short = legend_label("NNM 14 (fin bending 1 (anti-symmetric)) \u00b7 paper mode 13: tongue 1 (5:1) [new]")
    assert short.startswith("NNM 14 \u00b7 paper mode 13: tongue 1") and len(short) <= 42
    assert len({h.get_color() for h in leg.legend_handles[:11]}) == 11
    s.close()


def test_click_picks_the_point_nearest_on_the_screen(server, demo_file):
    """Issue 14, item 9: a click on overlapping spheres picks the point whose centre is nearest to the
    click on the screen (from the click's ray), not the sphere the ray met first."""
    from types import SimpleNamespace

    s, shared = make_session(server, demo_file)
    fv = s.drawing.fep
    a, b = shared.entries
    cam = np.asarray(s.geom.camera_position, dtype=float)
    target = fv.board_points[b.uid][4]
    on_a = fv._click_handler(a.uid)                         # the ray met a sphere of branch 1 first ...
    on_a(SimpleNamespace(ray_origin=tuple(cam), ray_direction=tuple(target - cam), instance_index=0))
    assert s.sel_uid == b.uid and s.s == 4.0                # ... but it points at point 4 of branch 2
    near = fv.board_points[a.uid][7] + 0.2 * (fv.board_points[a.uid][8] - fv.board_points[a.uid][7])
    fv._click_handler(b.uid)(SimpleNamespace(ray_origin=tuple(cam), ray_direction=tuple(near - cam),
                                             instance_index=4))
    assert s.sel_uid == a.uid and s.s == 7.0
    s.close()


def test_sweep_branches_are_listed_by_variant(server, demo_file):
    """Issue 16: branches named <variant>:mode<N> (a sweep's) are listed under their variant, ordered by
    variant then mode, after the other branches; numbers and colours stay per branch."""
    from nnm_viewer.fep import branch_color

    model = nnm.load_model(demo_file)
    b1, b2 = nnm.load_branches(demo_file)

    def named(b, name):
        c = b.subset(slice(0, 8))
        c.name = name
        return c

    branches = [b1, named(b2, "stiff:mode2"), named(b2, "base:mode2"), named(b1, "base:mode1"),
                named(b1, "stiff:mode1")]
    shared = SharedState(model, path=demo_file, branches=branches)
    s = Session(server, shared, sync=True)
    opts = s.h_branch.options
    assert opts[0].startswith("1: NNM 1 (")
    assert [o.split(" (")[0] for o in opts[1:]] == ["base \u203a 4: NNM 1", "base \u203a 3: NNM 2",
                                                     "stiff \u203a 5: NNM 1", "stiff \u203a 2: NNM 2"]
    assert "variant" not in " ".join(opts)                # the variant leads the option, once
    # the dropdown selects the branch of the option; a pick shows the branch's grouped option
    s.h_branch.value = opts[3]
    assert s.sel_uid == shared.entries[4].uid
    assert "**Sweep:** variant stiff, mode 1" in s.h_branch_info.content and "branch 5" in s.h_sel.content
    s.pick(shared.entries[2].uid, 3)
    assert s.h_branch.value == opts[2] and "variant base, mode 2" in s.h_branch_info.content
    s.pick(shared.entries[0].uid, 1)
    assert s.h_branch.value == opts[0] and "Sweep" not in s.h_branch_info.content
    # colours stay per branch (position in the file), legend names the branches
    for k, e in enumerate(shared.entries):
        assert tuple(s._board_handles[e.uid].batched_colors[0]) == tuple(
            int(branch_color(k)[i:i + 2], 16) for i in (1, 3, 5))
    s.close()


def test_fep_and_orbit_csv_downloads(server, demo_file):
    """Issue 14, item 11: the Point tab offers the selected branch's FEP (nnm_solver.export_csv) and
    the picked orbit over one period as CSV downloads, both at the k3 factor shown."""
    import csv
    import io

    from nnm_solver.files.exports import CSV_COLUMNS
    from nnm_viewer.downloads import orbit_csv

    s, shared = make_session(server, demo_file)
    e = shared.entries[1]
    s.pick(e.uid, 3)
    name, data = s.fep_csv()
    rows = list(csv.reader(io.StringIO(data.decode())))
    assert name.endswith("_fep.csv") and "branch2" in name and " " not in name
    assert tuple(rows[0]) == CSV_COLUMNS and len(rows) == len(e) + 1
    np.testing.assert_array_equal([float(r[0]) for r in rows[1:]], e.branch.energy)
    np.testing.assert_array_equal([float(r[1]) for r in rows[1:]], e.branch.frequency_hz)
    # the orbit: t_s and the DOF labels, one row per sample over one period
    s._on_csv_orbit(None)                                  # the button's callback
    name, data = s.last_download
    rows = list(csv.reader(io.StringIO(data.decode())))
    pd = s.current_point
    assert name.endswith("_point4_orbit.csv")
    assert rows[0] == ["t_s", "x1", "x2"] and len(rows) == len(pd.t) + 1
    table = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(table[:, 0], pd.t)
    np.testing.assert_array_equal(table[:, 1:], pd.x)
    assert table[0, 0] == 0.0 and table[-1, 0] == pytest.approx(pd.period, rel=0.05)
    # at k3 x 10: energies / 10, displacements / sqrt(10) (exact scaling law), as shown
    s.h_k3.value = 1.0
    name, data = s.fep_csv()
    energies = [float(r[0]) for r in list(csv.reader(io.StringIO(data.decode())))[1:]]
    assert "k3x10" in name and np.allclose(energies, e.branch.energy / 10, rtol=1e-12)
    _, data = s.orbit_csv()
    scaled = np.array(list(csv.reader(io.StringIO(data.decode())))[1:], dtype=float)
    np.testing.assert_allclose(scaled[:, 1:], table[:, 1:] / np.sqrt(10), rtol=1e-12)
    # a model without DOF labels: x0..x{n-1}
    unlabelled = nnm.Model(s.model.M, s.model.K)
    assert orbit_csv(pd, unlabelled).decode().splitlines()[0] == "t_s,x0,x1"
    s.close()


def test_job_progress_is_the_further_of_points_and_energy():
    """Issue 14, item 10: progress by points (of max_points) or by energy, whichever is further; the rate
    so far and the time left (issue 53: at the recent pace, tests/test_viewer_eta.py)."""
    from nnm_viewer.eta import TimeLeft
    from nnm_viewer.worker import JobProgress, duration_text

    p = JobProgress(points=60, max_points=80, energy_fraction=0.957, elapsed=120.0)
    assert p.fraction == pytest.approx(0.957) and p.by == "energy"
    assert p.rate_per_min == pytest.approx(30.0)
    assert p.eta is None and "left" not in p.text()          # no estimate given: none said
    q = JobProgress(points=60, max_points=80, energy_fraction=0.3, elapsed=120.0, left=TimeLeft(40.0, "points"))
    assert q.fraction == pytest.approx(0.75) and q.by == "points" and q.eta == pytest.approx(40.0)
    assert JobProgress(points=60, max_points=80, energy_fraction=0.957, elapsed=1.0, done=True).fraction == 1.0
    text = q.text()
    assert "60 of at most 80 points" in text and "75 % (by points" in text and "30 points/min" in text
    assert "at most 20 more points, about 40 s at the recent pace" in text
    # by energy: said once (it read "17 % (by energy; by energy 17 %)")
    assert "96 % (by energy)" in p.text() and p.text().count("by energy") == 1
    assert [duration_text(x) for x in (42, 185, 3720)] == ["42 s", "3 min 05 s", "1 h 02 min"]


def test_compute_tab_shows_elapsed_rate_eta_and_points_progress(server, demo_file):
    """Issue 14, item 10: the Compute tab's progress follows the points when they are further than the
    energy (not stuck), with elapsed time, rate and time left; the end says how long it took."""
    full = nnm.load_branches(demo_file)[0]
    fake = FakeJob(full)                                  # its energy progress: n / 277, far behind
    s, shared = make_session(server, demo_file, start_job=lambda m, mode, energy_max, **kw: fake)
    s.h_maxpts.value = 10
    s._cb(s._on_start)(None)
    runner = shared.job
    runner.poll = 0.01
    fake.release(4)
    wait_for(lambda: len(runner.entry) == 4)
    wait_for(lambda: abs(s.h_progress.value - 40.0) < 0.5)
    text = s.h_job.content
    assert "NNM 1 (in phase)" in text and "4 of at most 10 points" in text and "(by points" in text
    assert "elapsed" in text and "points/min" in text
    # four points read in one poll, then none: no pace to go by, so no number, and the wait is said
    wait_for(lambda: "no new point for" in s.h_job.content)
    assert "time left unknown" in s.h_job.content and " left at" not in s.h_job.content
    fake.release(2)
    wait_for(lambda: abs(s.h_progress.value - 60.0) < 0.5)
    s._cb(s._on_stop)(None)
    runner.finished.wait(5)
    wait_for(lambda: "stopped" in s.h_job.content)
    assert "6 points in" in s.h_job.content and "points/min" in s.h_job.content
    assert s.h_progress.value == pytest.approx(60.0, abs=0.5)   # a cancelled job keeps its progress
    s.close()


def test_every_mode_is_offered_and_branch_names_are_consistent(server, tmp_path):
    """Issue 14, item 10: the Compute tab lists every mode (not 60); branches are named
    'NNM <k> (<mode label>)' whatever name they were stored with; the save message names it once."""
    from nnm_viewer.state import branch_label

    n = 75
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    chain = nnm.Model(np.eye(n), K, [nnm.CubicSpring(dof=0, k3=1.0)],
                      mode_labels=[f"chain mode {k + 1}" for k in range(n)])
    shared = SharedState(chain)
    s = Session(server, shared, sync=True)
    assert len(s.h_mode.options) == n and s.h_mode.options[-1].startswith(f"{n}: ")
    assert s.h_mode.options[-1].endswith(f"chain mode {n}")
    s.close()
    path = tmp_path / "two.h5"
    write_demo_file(path, energy_max=1.0, max_points=8)
    b1 = nnm.load_branches(path)[0]
    cases = {"NNM1": "NNM 1 (in phase)", "mode1": "NNM 1 (in phase)", "NNM 1": "NNM 1 (in phase)",
             "mode1 (paper mode 13)": "NNM 1 (in phase) \u00b7 paper mode 13",
             "NNM1 harmonic balance H15": "NNM 1 (in phase) \u00b7 harmonic balance H15",
             "mode1: tongue 1 (3:1)": "NNM 1 (in phase) \u00b7 tongue 1 (3:1)",
             "mode1 (paper mode 13): tongue 1 (5:1)": "NNM 1 (in phase) \u00b7 paper mode 13: tongue 1 (5:1)",
             "stiff:mode1": "NNM 1 (in phase) \u00b7 variant stiff",
             # a second branch of mode 1 saved to the same file (e.g. by nnm-solve from a .mat run)
             "mode1_2": "NNM 1 (in phase) \u00b7 run 2", "NNM1_3": "NNM 1 (in phase) \u00b7 run 3",
             "mode1_2 (paper mode 13)": "NNM 1 (in phase) \u00b7 run 2 (paper mode 13)",
             "mode12": "NNM 1 (in phase) \u00b7 mode12", "": "NNM 1 (in phase)"}
    for name, want in cases.items():
        b1.name = name
        assert branch_label(b1) == want, name
    assert branch_label(b1, 10.0, "saved") == "NNM 1 (in phase) (k3 x 10) [saved]"
    bare = nnm.Model(np.eye(2), np.eye(2))                 # no mode labels: 'NNM k' alone
    b1.name = "mode1"
    assert branch_label(nnm.Branch.from_points(bare, 1, [])) == "NNM 1"
    # the save message names the branch once, without the list's state tag
    s, shared = make_session(server, path)
    shared.add(shared.entries[0].branch.subset(slice(0, 5)), source="computed", saved=False)
    s.select(len(shared.entries) - 1, 0)
    s._cb(s._on_save)(None)
    msg = s.h_status.content
    assert msg.startswith("saved NNM 1 (in phase), 5 points, to ") and "[" not in msg and msg.count("NNM") == 1
    s.close()


class TabWithCamera:
    """The server's gui and scene with a camera, as a tab (ClientHandle) has."""

    def __init__(self, server):
        from types import SimpleNamespace

        self.gui, self.scene = server.gui, server.scene
        self.camera_callbacks = []          # the session's camera-message callback (its canvas size)
        self.camera = SimpleNamespace(position=(1.0, -1.0, 1.0), look_at=(0.0, 0.0, 0.0),
                                      on_update=self.camera_callbacks.append)


def test_animation_gif_download(server, demo_file):
    """Issue 14, item 11: the picked orbit as an animated GIF (matplotlib's Pillow writer): one period,
    the structure moving, seen along the tab's camera."""
    import io

    from PIL import Image

    from nnm_viewer.gif import GIF_FRAMES

    s, shared = make_session(server, demo_file)
    with s.lock:
        s.current_point = s.current_anim = None               # no orbit shown (e.g. solver not ready)
    with pytest.raises(ValueError, match="pick a point"):
        s.animation_gif()
    s.pick(shared.entries[0].uid, 20)
    s._on_gif(None)                                          # the button's callback
    name, data = s.last_download
    assert name.endswith("_point21.gif") and data[:6] == b"GIF89a"
    im = Image.open(io.BytesIO(data))
    assert im.n_frames == GIF_FRAMES
    frames = []
    for k in (0, GIF_FRAMES // 4):
        im.seek(k)
        frames.append(np.asarray(im.convert("RGB"), dtype=float))
    assert np.mean(np.abs(frames[0] - frames[1]).sum(axis=2) > 30) > 0.002    # the structure moves
    colourful = frames[0][..., 0] - frames[0][..., 2]
    assert (colourful > 80).any() and (colourful < -80).any()             # red and blue: colour map and bar
    s.close()


def test_view_presets_ghost_colour_bar_and_help(server, demo_file):
    """Issue 14, item 11: view presets frame the model from above, the side, the front; the undeformed
    shape as a ghost; a colour bar of the displacement colours in physical units; the Help tab."""
    from types import SimpleNamespace

    from nnm_viewer.scene import preset_camera

    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file))
    tab = TabWithCamera(server)
    s = Session(tab, shared, sync=True)
    assert tab.camera_callbacks == [s._on_camera]       # a tab's canvas size is followed (the board's spheres)
    v = s.mesh.vertices
    centre = 0.5 * (v.min(axis=0) + v.max(axis=0))
    for name, axis, sign in (("Top", 2, 1), ("Side", 1, -1), ("Front", 0, -1)):
        s.h_view.value = name
        s._cb(s._on_view)(SimpleNamespace(target=s.h_view))
        d = np.asarray(tab.camera.position) - np.asarray(tab.camera.look_at)
        np.testing.assert_allclose(tab.camera.look_at, centre)
        assert sign * d[axis] > 0.99 * np.linalg.norm(d), name
        pos, _ = preset_camera(v, name)
        rel = v - pos                                        # every vertex inside the field of view
        angle = np.degrees(np.arccos(np.clip(rel @ -d / np.linalg.norm(rel, axis=1) / np.linalg.norm(d), -1, 1)))
        assert angle.max() < s.geom.fov_deg / 2, name
        assert np.allclose(-s.view_direction() / np.linalg.norm(d), d / np.linalg.norm(d))
    with pytest.raises(ValueError, match="unknown view"):
        preset_camera(v, "Below")
    # ghost
    assert s.drawing.ghost_handle is None
    s.h_ghost.value = True
    g = s.drawing.ghost_handle
    assert g is not None and g.opacity == pytest.approx(0.3) and len(g.vertices) == len(v)
    s.h_ghost.value = False
    assert s.drawing.ghost_handle is None
    # colour bar: shown with the orbit, from 0 to the true peak (follows the k3 scaling law)
    s.pick(shared.entries[0].uid, 20)
    peak = s.amplification()[1]
    assert s.h_colorbar.visible and s.drawing.point.colorbar_peak == pytest.approx(peak)
    img = np.asarray(s.h_colorbar.image)
    assert img.shape[1] > 200 and (img[..., 0].astype(int) - img[..., 2] > 100).any()   # red end of the map
    s.h_k3.value = 1.0
    assert s.drawing.point.colorbar_peak == pytest.approx(peak / np.sqrt(10))
    # help
    text = s.h_help.content
    for words in ("Frequency-energy plot", "Floquet multipliers", "unstable", "period doubling", "torus",
                  "tongue k:1", "backbone"):
        assert words in text, words
    s.close()


ASSETS = Path(__file__).resolve().parents[1] / "assets"


def test_fep_zooms_on_a_narrow_branch_by_default_and_relative_axis(server):
    """Issue 14, item 9: on two_dof.h5 NNM 1 spans 2 % of the frequency range (NNM 2 climbs to 3.8 Hz):
    the FEP zooms on it by default (its tongues are visible), not on the wide NNM 2; the user's choice
    then wins.  The relative axis shows f/f_linear - 1 in % on both FEPs.  The picked point's readout
    is under the panel FEP (no hover events reach Python in viser 1.1)."""
    from nnm_viewer.fep import FepSeries, should_zoom

    z = np.zeros(3, bool)
    narrow = FepSeries(np.array([1.0, 2, 3]), np.array([1.0, 1.01, 1.02]), z, "a")
    wide = FepSeries(np.array([1.0, 2, 3]), np.array([2.0, 3.0, 4.0]), z, "b")
    assert should_zoom([narrow, wide], 0) and not should_zoom([narrow, wide], 1)
    assert not should_zoom([narrow], 0) and not should_zoom([narrow, wide], None)

    path = ASSETS / "two_dof.h5"
    if not path.exists():
        pytest.skip("assets/two_dof.h5 is missing")
    s, shared = make_session(server, path)
    nnm1, nnm2 = shared.entries[0], shared.entries[1]
    assert s.sel_uid == nnm1.uid and s.h_zoom.value
    (_, _), (flo, fhi) = s._view_ranges(*s._series())
    f1 = nnm1.branch.frequency_hz
    assert flo < f1.min() and fhi < f1.max() + 0.1 * np.ptp(f1)           # fitted to NNM 1
    assert s._board_handles[nnm2.uid] is None and "zoomed" in s.drawing.fep.renderer.ax.get_title()
    s.pick(nnm2.uid, 3)                                                   # a wide branch: no zoom
    assert not s.h_zoom.value and s._view_ranges(*s._series())[1][1] > nnm2.branch.frequency_hz.max()
    s.h_branch.value = s.h_branch.options[0]
    assert s.h_zoom.value
    s.h_zoom.value = False                                                # the user's choice is kept
    s.pick(nnm2.uid, 3)
    s.pick(nnm1.uid, 3)
    assert not s.h_zoom.value and s._board_handles[nnm2.uid] is not None
    # relative axis: 100 (f / f_linear - 1) per branch, on both FEPs
    s.h_relative.value = True
    f_lin = shared.linear_freqs
    _, series = s._series()
    np.testing.assert_allclose(series[1].frequency, 100 * (nnm2.branch.frequency_hz / f_lin[1] - 1))
    assert abs(series[0].frequency[0]) < 0.1                              # starts at the linear frequency
    ax = s.drawing.fep.renderer.ax
    assert ax.get_ylabel() == "f / f_linear \u2212 1 (%)"
    assert ax.get_ylim()[1] > 100 * (nnm2.branch.frequency_hz.max() / f_lin[1] - 1)
    star = s.drawing.fep.renderer._star.get_ydata()[0]
    assert star == pytest.approx(100 * (f1[3] / f_lin[0] - 1))
    pos = s.drawing.fep.board_points[nnm1.uid][3]                         # the board in % too
    ranges = s.drawing.fep.ranges
    assert pos == pytest.approx(s.geom.board.to_world([nnm1.branch.energy[3]], [series[0].frequency[3]],
                                                      ranges)[0])
    # the readout of the picked point
    text = s.h_readout.content
    assert text.startswith("**Picked:** branch 1, NNM 1 (") and "point 4 of" in text
    assert f"f = {f1[3]:.6g} Hz" in text and "% from its linear" in text and "stable" in text and "backbone" in text
    s.close()


def test_point_label_and_accuracy_estimate_are_shown(server, demo_file):
    """Issue 14: each point's label (backbone / tongue k:1) and, when the branch has one, its estimated
    relative frequency error (``Branch.freq_error``; None or absent in older files) in the Point tab,
    the readout and the selection text."""
    s, shared = make_session(server, demo_file)
    e = shared.entries[0]
    b = e.branch
    b.freq_error = None                                                 # as a branch of an older file
    s.pick(e.uid, 6)
    assert "label: **backbone** (the fundamental NNM family)" in s.h_info.content
    assert "estimated" not in s.h_info.content and "estimated" not in s.h_readout.content
    labels = np.array(b.labels, dtype=object)
    labels[7] = "tongue 3:1"
    b.labels = labels
    b.freq_error = np.full(len(b), 3e-7)
    b.freq_error[7] = 2.0e-6
    s.pick(e.uid, 7)
    assert "label: **tongue 3:1** (inside an internal-resonance tongue)" in s.h_info.content
    f7 = b.frequency_hz[7]
    assert f"estimated relative error 2.0e-06 (± {2e-6 * f7:.2g} Hz)" in s.h_info.content
    assert "tongue 3:1 · estimated frequency error 2.0e-06 (relative)" in s.h_readout.content
    assert "tongue 3:1" in s.h_sel.content
    b.freq_error = np.full(len(b) - 1, 1e-6)                            # wrong length: not shown
    s.pick(e.uid, 6)
    assert "estimated" not in s.h_info.content
    b.freq_error = np.full(len(b), np.nan)                              # not estimated: not shown
    s.pick(e.uid, 5)
    assert "estimated" not in s.h_readout.content
    s.close()


def test_model_panel_lists_the_nonlinear_elements(server, tmp_path):
    """Issue 14: the model's nonlinear elements (cubic, polynomial, piecewise-linear springs) with their
    DOFs (and labels) and parameters, in the Modes tab; the title counts them by kind."""
    from nnm_viewer.model_info import elements_markdown, elements_summary

    n = 4
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    els = [nnm.CubicSpring(dof=0, k3=2.5e4), nnm.PolynomialSpring(dof=1, other=2, coefficients={2: 3.0, 3: 1e5}),
           nnm.PiecewiseLinearSpring(dof=3, stiffnesses=[1e3, 5e3], breakpoints=[1e-3])]
    model = nnm.Model(np.eye(n), K, els, dof_labels=["a", "b", "c", "d"], name="chain")
    assert elements_summary(model) == "1 cubic spring, 1 polynomial spring, 1 piecewise-linear spring"
    rows = elements_markdown(model).splitlines()[4:]
    assert rows[0] == "| 1 | cubic spring | x[0 (a)] | k3 = 2.5e+04 N/m³ |"
    assert rows[1] == "| 2 | polynomial spring | x[1 (b)] − x[2 (c)] | k2 = 3 N/m^2, k3 = 1e+05 N/m^3 |"
    assert rows[2].startswith("| 3 | piecewise-linear spring | x[3 (d)] | slopes [1000, 5000] N/m at "
                              "breakpoints [0.001] m")
    assert elements_summary(nnm.Model(np.eye(n), K)) == "no nonlinear element"
    s = Session(server, SharedState(model), sync=True)
    assert "1 cubic spring, 1 polynomial spring, 1 piecewise-linear spring" in s.h_title.content
    assert "**Model:** chain, 4 DOFs" in s.h_model.content and "piecewise-linear spring" in s.h_model.content
    s.close()


# ---------------------------------------------------------------- issue 18: stiffness slider, non-cubic models
def polynomial_two_box(k3=0.5, k5=0.5):
    """The 2-DOF demo with a cubic + quintic spring: no exact scaling law."""
    from nnm_viewer.demo import two_box_model

    m = two_box_model(k3)
    return m.with_springs([nnm.PolynomialSpring(dof=0, coefficients={3: k3, 5: k5})])


@pytest.fixture(scope="module")
def poly_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("viewer_poly") / "poly.h5"
    model = polynomial_two_box()
    nnm.save_model(path, model)
    for mode in (1, 2):
        nnm.save_branch(path, nnm.continue_nnm(model, mode=mode, energy_max=1.0, max_points=12))
    return path


class JobRecorder:
    """A ``start_job`` that records each call (the model's force factor, mode, energy_max) and returns
    a FakeJob streaming ``branch``; the jobs end when the test says (release, cancel)."""

    def __init__(self, branch, k5=0.5):
        self.branch, self.k5, self.calls, self.jobs = branch, k5, [], []

    def __call__(self, model, mode, energy_max, **kw):
        factor = model.springs[0].law()[5] / self.k5
        self.calls.append((factor, mode, energy_max))
        job = FakeJob(self.branch)
        self.jobs.append(job)
        return job


def _watch_ghosts(s):
    """Record the ghosts (scaled-law grey curves) drawn in the panel FEP of session ``s``."""
    seen = []
    real = s.drawing.fep.renderer.set_series

    def set_series(*a, **kw):
        seen.append(list(kw.get("ghosts", ())))
        return real(*a, **kw)
    s.drawing.fep.renderer.set_series = set_series
    return seen


def test_scaling_law_is_only_for_pure_cubic_models():
    from nnm_viewer.demo import two_box_model
    from nnm_viewer.state import scaling_law_holds

    assert scaling_law_holds(two_box_model())
    assert not scaling_law_holds(polynomial_two_box())
    pw = two_box_model().with_springs([nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.2, 1.0], breakpoints=[0.5])])
    assert not scaling_law_holds(pw)
    assert scaling_law_holds(two_box_model().with_springs([nnm.PolynomialSpring(dof=0, coefficients={3: 2.0})]))


def test_stiffness_slider_recomputes_a_non_cubic_model(server, poly_file, tmp_path, monkeypatch):
    """Issue 18: elements not all cubic: moving the stiffness slider scales nothing (no Branch.scaled,
    no scaled point or FEP, no grey ghost); its label says why; a job computes the branch of the
    model with every spring force x the chosen factor, named with its factor; it cannot be saved into
    the file (no law maps it back)."""
    path = tmp_path / "poly.h5"
    path.write_bytes(poly_file.read_bytes())
    file_b1 = nnm.load_branches(path)[0]
    rec = JobRecorder(file_b1)
    s, shared = make_session(server, path, start_job=rec)
    assert not s.scaling_law and "cubic springs only" in s.h_k3_text.content
    assert s.h_k3.label == "Spring force factor log10"
    ghosts = _watch_ghosts(s)
    scaled_calls = []
    monkeypatch.setattr(nnm.Branch, "scaled", lambda self, f: scaled_calls.append(f) or 1 / 0)
    b1 = shared.entries[0]
    s.pick(b1.uid, 6)
    s.h_k3.value = 1.0                                     # every spring force x 10
    assert not s.h_error.visible, s.h_error.content
    assert scaled_calls == []
    assert [c[:2] for c in rec.calls] == [(pytest.approx(10.0), 1)]
    assert rec.calls[0][2] == pytest.approx(np.max(b1.branch.energy))
    runner = s.last_runner
    assert runner is s.slider_runner and runner.k3_factor == pytest.approx(10.0) and shared.job is runner
    new = runner.entry
    assert s.sel_uid == new.uid and "(k3 x 10)" in new.label and "(k3 x 10)" in s.h_branch.value
    assert "forces x 10 (recomputed)" in s.h_k3_text.content and "cubic springs only" in s.h_k3_text.content
    # the file's branches are shown as computed: same energies, no ghost
    np.testing.assert_array_equal(s.fep_series(b1).energy, b1.branch.energy)
    assert all(g == [] for g in ghosts) and "k3 x" not in s.drawing.fep.renderer.ax.get_title()
    runner.poll = 0.01
    rec.jobs[0].release(len(file_b1))
    rec.jobs[0]._end()
    runner.finished.wait(5)
    wait_for(lambda: new.source == "computed")
    wait_for(lambda: f"({len(file_b1)} pts" in s.h_branch.value)
    s.pick(new.uid, 4)                                     # its points are shown as computed
    assert s.current_point.energy == pytest.approx(file_b1.energy[4]) and s.ratio == 1.0
    assert not s.h_error.visible and scaled_calls == []
    # the FEP CSV of a file branch at this slider position: as computed, no k3 in the name
    s.pick(b1.uid, 2)
    name, data = s.fep_csv()
    assert "k3x" not in name and scaled_calls == []
    # no scaling law maps the branch back to the file's springs: not saved, one line, file unchanged
    s.pick(new.uid, 0)
    s._cb(s._on_save)(None)
    assert s.h_error.visible and "cubic springs only" in s.h_error.content and not new.saved
    assert len(nnm.load_branches(path)) == 2
    s.close()


def test_stiffness_slider_recompute_is_debounced(server, poly_file):
    """Issue 18: one job runs, for the slider's final value: a slider job for a factor no longer wanted
    is stopped and its branch dropped; the next starts when it has ended; a factor already computed
    (back to x 1: the file's branch) is selected, not recomputed; a job started by Start is not
    stopped: the slider's recompute waits for it."""
    file_b1 = nnm.load_branches(poly_file)[0]
    rec = JobRecorder(file_b1)
    s, shared = make_session(server, poly_file, start_job=rec)
    b1 = shared.entries[0]
    s.h_k3.value = 1.0
    first = s.slider_runner
    first.poll = 0.01
    rec.jobs[0].release(3)
    wait_for(lambda: len(first.entry) == 3)
    s.h_k3.value = 1.5                                     # first job superseded
    assert rec.jobs[0].cancelled and all(e is not first.entry for e in shared.entries)
    wait_for(lambda: s.slider_runner is not first)
    second = s.slider_runner
    assert len(rec.calls) == 2 and rec.calls[1][0] == pytest.approx(10 ** 1.5) and rec.calls[1][1] == 1
    assert rec.calls[1][2] == pytest.approx(rec.calls[0][2])        # the same energy range as the first
    assert s.sel_uid == second.entry.uid and len(shared.entries) == 3
    s.h_k3.value = 0.0                                     # back to the file's springs
    assert rec.jobs[1].cancelled and s.sel_uid == b1.uid and len(rec.calls) == 2
    second.finished.wait(5)
    wait_for(lambda: shared.job is None)
    assert len(rec.calls) == 2 and len(shared.entries) == 2 and not s.h_error.visible
    # a Start job is not stopped by the slider: the recompute is queued until it ends
    s._cb(s._on_start)(None)
    user = shared.job
    user.poll = 0.01
    s.h_k3.value = 1.0
    assert len(rec.calls) == 3 and not rec.jobs[2].cancelled and "queued" in s.h_status.content
    rec.jobs[2].release(2)
    rec.jobs[2]._end()
    wait_for(lambda: s.slider_runner is not None and s.slider_runner.job is rec.jobs[-1] and len(rec.calls) == 4)
    assert rec.calls[3][0] == pytest.approx(10.0) and s.slider_runner.k3_factor == pytest.approx(10.0)
    rec.jobs[3].cancel()
    s.slider_runner.finished.wait(5)
    assert not s.h_error.visible
    s.close()


def test_stiffness_slider_drag_starts_one_job(server, poly_file, monkeypatch):
    """Issue 18, a tab drawn in its own thread (as in the browser): values sent while the slider is
    dragged start no job; one job starts once it has rested, for the final value."""
    import nnm_viewer.compute_actions as compute_actions

    # (the drag's five values 0.05 s apart must all arrive within the delay: 0.3 s was passed on a loaded machine,
    # a job starting mid-drag; 1.5 s keeps the test about the debounce, not the machine's speed)
    monkeypatch.setattr(compute_actions, "RECOMPUTE_DELAY", 1.5)
    rec = JobRecorder(nnm.load_branches(poly_file)[1])
    model = nnm.load_model(poly_file)
    shared = SharedState(model, path=poly_file, branches=nnm.load_branches(poly_file))
    s = Session(server, shared, start_job=rec)
    s.pick(shared.entries[1].uid, 3)
    for v in (0.1, 0.2, 0.3, 0.4, 0.5):
        s.h_k3.value = v
        time.sleep(0.05)
    assert rec.calls == []
    wait_for(lambda: s.slider_runner is not None)
    time.sleep(0.5)
    assert [c[:2] for c in rec.calls] == [(pytest.approx(10 ** 0.5), 2)]
    wait_for(lambda: s.sel_uid == s.slider_runner.entry.uid and "(k3 x 3.16)" in s.h_branch.value)
    rec.jobs[0].cancel()
    s.slider_runner.finished.wait(5)
    assert not s.h_error.visible
    s.close()
    with s.drawing._draw_lock:                            # a drawing under way ends before the server stops
        pass


# ---------------------------------------------------------------- issue 14 item 11: the Modes tab's linear modes
def test_modes_tab_shows_a_linear_mode_and_a_later_pick_shows_the_point(server, demo_file):
    """'Show this linear mode' animates x(t) = a phi_k cos(2 pi f_k t) (frequency f_k, MAC 1 with mode k,
    stable, no Floquet multipliers) and the Point tab names it; the selection is kept, and a pick (even of
    the point still selected), the along slider or the energy slider show a branch point again."""
    s, shared = make_session(server, demo_file)
    model = shared.model
    freqs, shapes = model.linear_modes()
    M = np.asarray(model.M)
    assert s.h_lin_mode.options == s.h_mode.options                      # same labels as the Compute tab
    e2 = shared.entries[1]
    # the Modes tab opens on the selected branch's mode, and follows the selection to another branch
    assert s.h_lin_mode.value == s.h_lin_mode.options[shared.entries[0].branch.mode - 1]
    s.pick(e2.uid, 5)
    assert e2.branch.mode == 2 and s.h_lin_mode.value == s.h_lin_mode.options[1]
    glb_point = s.last_glb
    s.h_lin_mode.value = s.h_lin_mode.options[1]
    s._cb(s._on_show_linear)(None)
    assert not s.h_error.visible
    pd = s.current_point
    f2, phi = freqs[1], shapes[:, 1]
    assert pd.frequency == pytest.approx(f2, rel=1e-12) and pd.period == pytest.approx(1 / f2, rel=1e-12)
    assert pd.stable and pd.floquet.size == 0
    assert pd.mac[1] == pytest.approx(1.0, abs=1e-12) and pd.mac[0] == pytest.approx(0.0, abs=1e-12)
    a = float(pd.x[0] @ M @ phi)                                         # x(0) = a phi (phi^T M phi = 1)
    assert a > 0
    np.testing.assert_allclose(pd.x, a * np.cos(2 * np.pi * f2 * pd.t)[:, None] * phi[None, :], atol=1e-12 * a)
    assert nnm.mac(pd.x[0], phi, M) == pytest.approx(1.0, abs=1e-12)
    assert pd.energy == pytest.approx(0.5 * (2 * np.pi * f2 * a) ** 2, rel=1e-12)
    # the amplitude is the auto amplification's: a manual factor of 1 shows it the same
    amp, peak = s.amplification()
    assert amp == pytest.approx(1.0, rel=1e-6) and peak == pytest.approx(0.12 * s.geom.size, rel=1e-6)
    label = model.mode_labels[1]
    assert f"**linear mode 2 ({label}), f = {f2:.6g} Hz**" in s.h_info.content
    assert "Branch 2" not in s.h_info.content and "linear mode 2" in s.h_peak.content
    assert "animations" in read_glb_json(s.last_glb) and s.last_glb != glb_point
    assert s.sel_uid == e2.uid and s.s == 5.0 and "branch 2, point 6 of 48" in s.h_sel.content
    s.request("branches")                                  # e.g. a job's points arriving: the mode stays
    assert s.current_point.frequency == pytest.approx(f2, rel=1e-12)
    name, data = s.orbit_csv()
    assert "linear_mode2" in name and data.count(b"\n") >= len(pd.t)
    # a pick of the point still selected shows that point again, as before
    s.pick(e2.uid, 5)
    assert s.linear_mode is None and s.current_uid == e2.uid
    assert s.current_point.energy == pytest.approx(e2.branch.energy[5])
    assert s.current_point.frequency == pytest.approx(e2.branch.frequency_hz[5])
    assert s.h_info.content.startswith("**Branch 2") and "linear mode" not in s.h_peak.content
    # the sliders too
    s._cb(s._on_show_linear)(None)
    s.h_along.value = 4.0                                  # point 4: row 3
    assert s.current_point.energy == pytest.approx(e2.branch.energy[3])
    s.h_lin_mode.value = s.h_lin_mode.options[0]
    s._cb(s._on_show_linear)(None)
    assert s.current_point.frequency == pytest.approx(freqs[0], rel=1e-12)
    s.h_energy.value = round(float(np.log10(e2.branch.energy[7])), 2)
    assert s.linear_mode is None and s.current_point.frequency == pytest.approx(e2.branch.frequency_hz[7], rel=1e-3)
    s.close()


def test_stiffness_slider_after_a_linear_mode_animates_the_picked_point(server, demo_file):
    """Issue 32, finding (c): while a linear mode is shown the readout says so (it used to name only the
    picked point); the stiffness slider, which changes that point and not the linear mode, animates the
    picked point again at the new factor (scaling law: same frequency, energy / 10), and every text agrees."""
    s, shared = make_session(server, demo_file)
    e2 = shared.entries[1]
    s.pick(e2.uid, 5)
    assert "Shown:" not in s.h_readout.content
    s.h_lin_mode.value = s.h_lin_mode.options[0]
    s._cb(s._on_show_linear)(None)
    f1 = shared.model.linear_modes()[0][0]
    assert s.current_point.frequency == pytest.approx(f1, rel=1e-12)
    assert s.h_readout.content.startswith("**Shown:** linear mode 1") and "point 6 of 48" in s.h_readout.content
    s.h_k3.value = 1.0                                     # every k3 x 10
    assert s.linear_mode is None and s.current_uid == e2.uid
    assert s.current_point.frequency == pytest.approx(e2.branch.frequency_hz[5], rel=1e-12)
    assert s.current_point.energy == pytest.approx(e2.branch.energy[5] / 10, rel=1e-12)
    shown = f"E = {e2.branch.energy[5] / 10:.4g} J"
    assert "Shown:" not in s.h_readout.content and shown in s.h_readout.content and shown in s.h_sel.content
    assert s.h_info.content.startswith("**Branch 2") and "linear mode" not in s.h_peak.content
    s.close()


def test_modes_tab_compute_its_branch_starts_the_job_as_start_does(server, demo_file):
    """'Compute its branch' selects the mode in the Compute tab and starts the job with the same
    arguments as Start; the new branch is selected (the linear mode shown is replaced)."""
    full = nnm.load_branches(demo_file)[1]
    calls = []

    def start_job(model, mode, energy_max, **kw):
        calls.append((mode, energy_max, kw))
        return FakeJob(full)

    s, shared = make_session(server, demo_file, start_job=start_job)
    s.h_emax.value = 5.0
    s.h_maxpts.value = 30
    s.h_lin_mode.value = s.h_lin_mode.options[1]
    s._cb(s._on_show_linear)(None)
    s._cb(s._on_compute_linear)(None)
    assert not s.h_error.visible
    runner = shared.job
    runner.poll = 0.01
    assert s.h_mode.value == s.h_mode.options[1] and runner.mode == 2
    assert calls == [(2, 5.0, {"max_points": 30, "integrator": "gauss6", "steps_per_period": 100, "tongues": "follow"})]
    assert s.sel_uid == runner.entry.uid and s.linear_mode is None and s.current_point is None
    assert "Compute" in s.h_status.content and "NNM 2" in s.h_modes_job.content
    assert s.h_compute_linear.disabled and s.h_start.disabled
    s._cb(s._on_compute_linear)(None)                                   # one job at a time
    assert s.h_error.visible and "already running" in s.h_error.content and len(calls) == 1
    s._cb(s._on_stop)(None)
    assert runner.finished.wait(5)
    wait_for(lambda: not s.h_compute_linear.disabled)
    s._cb(s._on_start)(None)                                            # Start with that mode: the same job
    assert calls[1] == calls[0]
    s._cb(s._on_stop)(None)
    assert shared.job is None or shared.job.finished.wait(5)
    s.close()


def test_compute_tab_integrator_reaches_the_job(server, demo_file, tmp_path):
    """The Compute tab's integrator and steps per period are passed to the job (start_branch); the
    computed branch has them in its settings and the Point tab says so next to the frequency."""
    calls = []
    full = nnm.load_branches(demo_file)[0]

    def start_job(model, mode, energy_max, **kw):
        calls.append(kw)
        return FakeJob(full)

    s, shared = make_session(server, demo_file, start_job=start_job)
    # the solver's defaults (gauss6, 100 steps: nnm_solver/driver/settings.py), then the seed paper's scheme chosen
    assert tuple(s.h_integrator.options) == tuple(nnm.INTEGRATORS) and s.h_integrator.value == "gauss6"
    assert s.h_spp.value == 100 and "gauss6 100" in s.h_spp.hint and "newmark 200" in s.h_spp.hint
    s.h_integrator.value = "newmark"
    assert s.h_spp.value == 200                               # the solver's default for newmark
    s._cb(s._on_start)(None)
    assert calls[-1]["integrator"] == "newmark" and calls[-1]["steps_per_period"] == 200
    s._cb(s._on_stop)(None)
    shared.job is None or shared.job.finished.wait(5)
    s.close()
    # the real solver: the branch's settings, and the Point tab
    path = tmp_path / "copy.h5"
    path.write_bytes(demo_file.read_bytes())
    s, shared = make_session(server, path)
    s.h_integrator.value = "gauss4"
    s.h_spp.value = 120
    s.h_maxpts.value = 3
    s.h_emax.value = 1.0
    s._cb(s._on_start)(None)
    runner = s.last_runner
    assert runner.finished.wait(120) and runner.entry.source == "computed", runner.entry.source
    b = runner.entry.branch
    assert b.settings.integrator == "gauss4" and b.settings.steps_per_period == 120 and len(b) == 3
    s.pick(runner.entry.uid, 1)
    freq_line = next(l for l in s.h_info.content.splitlines() if l.startswith("- frequency"))
    assert freq_line.endswith("· shooting, gauss4, 120 steps per period")
    s.pick(shared.entries[0].uid, 1)                                    # the file's branch: its own settings
    st = shared.entries[0].branch.settings
    assert f"· shooting, {st.integrator}, {st.steps_per_period} steps per period" in s.h_info.content
    s.close()


def test_unticking_auto_amplification_keeps_the_factor_the_slider_shows(server, demo_file):
    """With Auto on the drawing shows the auto factor on the Amplification slider and stores it (amp_log);
    unticked, the factor used is the one the slider shows (docs/viewer.md), not a stale amp_log of 0 (x1)."""
    s, _ = make_session(server, demo_file)
    s.pick(s.sel_uid, 1)                                   # a small orbit: the auto factor is far from x1
    amp_auto, _ = s.amplification()
    shown = s.h_amp.value
    assert abs(np.log10(amp_auto)) > 0.1 and shown == pytest.approx(np.log10(amp_auto), abs=0.006)
    assert s.amp_log == shown
    s.h_auto.value = False
    assert s.h_amp.value == shown
    assert s.amplification()[0] == pytest.approx(10.0 ** shown, rel=1e-12)
    assert f"shown x{10.0 ** shown:.3g}" in s.h_peak.content and "(auto)" not in s.h_peak.content
    s.h_amp.value = 1.0                                    # the manual slider still sets it
    assert s.amplification()[0] == pytest.approx(10.0)
    s.close()


def test_selection_text_and_point_tab_agree_halfway_between_stable_and_unstable(server):
    """assets/two_dof.h5 rows 70/71 are stable/unstable: at point 71.5 (s = 70.5) the selection text, the
    readout and the Point tab all name the upper neighbour's stability, as Branch.interpolate."""
    path = Path(__file__).resolve().parents[1] / "assets" / "two_dof.h5"
    s, shared = make_session(server, path)
    e = shared.entries[0]
    assert bool(e.branch.stable[70]) and not bool(e.branch.stable[71])
    s.pick(e.uid, 70)
    assert "stable" in s.h_sel.content and "stability: **stable**" in s.h_info.content
    s.h_along.value = 71.5
    assert s.s == 70.5
    assert "unstable" in s.h_sel.content and "stability: **UNSTABLE**" in s.h_info.content
    s.close()


def test_a_branch_without_multipliers_is_not_said_stable_in_the_session(server):
    """floquet=False: the legend, the selection text and the Point tab all say the stability was not computed."""
    m = nnm.Model(np.eye(2), np.array([[2., -1], [-1, 2]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    b = nnm.continue_nnm(m, mode=1, energy_max=1.0, max_points=10, floquet=False)
    s = Session(server, SharedState(m, branches=[b]), sync=True)
    s.pick(s.sel_uid, 3)
    assert "stability not computed" in s.h_sel.content and ", stable" not in s.h_sel.content
    assert "stability: **not computed**" in s.h_info.content
    assert "Floquet multipliers:" not in s.h_info.content and "nan" not in s.h_info.content
    s.close()
