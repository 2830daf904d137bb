"""The viewer after issue 53 (the second day with nnm): the points off the backbone marked on both FEPs, the
Compute tab's method, tongues and mode, the solver's defaults, the Save message where the user looks, the
panel FEP's clipping and legend, the mode names."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_viewer.controls import Session
from nnm_viewer.state import SharedState

viser = pytest.importorskip("viser")


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def session_on(server, path, start_job=None):
    model = nnm.load_model(path)
    return Session(server, SharedState(model, path=path, branches=nnm.load_branches(path)), sync=True,
                   start_job=start_job)


def test_points_off_the_backbone_are_marked_on_both_feps(server, tmp_path, two_dof_nnm1):
    """NNM 1 of the 2-DOF model through its 3:1 tongue: the panel FEP names the tongue's points in its legend and
    draws them in the solver's colour for them; the board's spheres of those points take that colour."""
    from matplotlib.colors import to_hex
    from nnm_solver.results.plotting import OFF_BACKBONE_COLOR
    from nnm_viewer.fep import rgb

    path = tmp_path / "t.h5"
    nnm.save_model(path, two_dof_nnm1.model)
    nnm.save_branch(path, two_dof_nnm1)
    s = session_on(server, path)
    off = np.asarray(two_dof_nnm1.labels) != "backbone"
    assert 0 < off.sum() < len(off)
    legend = [t.get_text() for t in s.drawing.fep.renderer.legend.get_texts()]
    assert "tongue 3:1 (off the backbone)" in legend
    ax = s.drawing.fep.renderer.ax
    orange = to_hex(OFF_BACKBONE_COLOR)
    marked = [ln for ln in ax.get_lines() if to_hex(ln.get_color()) == orange]
    assert sum(len(ln.get_xdata()) for ln in marked) == off.sum()
    uid = s.shared.entries[0].uid
    colors = np.asarray(s._board_handles[uid].batched_colors)
    stable = np.asarray(two_dof_nnm1.stable)
    assert (colors[off & stable] == rgb(orange)).all() and not (colors[~off] == rgb(orange)).all(axis=1).any()
    s.close()


class Recorder:
    """A ``start_job`` recording its calls; the job streams the given branch (test_viewer_session.FakeJob)."""

    def __init__(self, branch):
        self.branch, self.calls = branch, []

    def __call__(self, model, mode, energy_max, **kw):
        from test_viewer_session import FakeJob
        self.calls.append(dict(mode=mode, energy_max=energy_max, **kw))
        return FakeJob(self.branch)


@pytest.fixture(scope="module")
def demo_file(tmp_path_factory):
    from nnm_viewer.demo import write_demo_file
    path = tmp_path_factory.mktemp("second_day") / "two.h5"
    write_demo_file(path, energy_max=10.0)
    return path


def test_compute_tab_has_the_apis_defaults_and_starts_on_the_selected_nnm(server, demo_file):
    """Finding 5: the Compute tab's defaults are continue_nnm's (read from the solver), and its mode is the
    selected NNM's, not mode 1."""
    from nnm_solver.cli.defaults import solver_defaults
    from nnm_viewer.layout import method_choice

    D = solver_defaults()
    rec = Recorder(nnm.load_branches(demo_file)[1])
    s = session_on(server, demo_file, start_job=rec)
    assert s.h_maxpts.value == D["max_points"] and s.h_spp.value == D["steps_per_period"]
    assert s.h_integrator.value == D["integrator"] and s.h_tongues.value == D["tongues"]
    assert s.h_harmonics.value == D["harmonics"] and s.h_method.value == method_choice(D["method"], D["condensed"])
    assert s.h_mode.value.startswith("1:")                   # branch 1 (NNM 1) selected
    e2 = s.shared.entries[1]
    s.pick(e2.uid, 4)                                          # NNM 2 selected: the Compute tab follows
    assert s.h_mode.value.startswith("2:") and s.h_lin_mode.value.startswith("2:")
    s._cb(s._on_start)(None)
    assert rec.calls[-1]["mode"] == 2 and rec.calls[-1]["tongues"] == D["tongues"]
    assert rec.calls[-1]["integrator"] == D["integrator"] and "method" not in rec.calls[-1]
    s._cb(s._on_stop)(None)
    s.last_runner.finished.wait(5)
    s.close()


def test_steps_per_period_follow_the_chosen_integrator(server, demo_file):
    """Issue 53: the steps field stayed at 100 when newmark was chosen; it takes each integrator's own default,
    read from the solver's registry (never re-typed), and a value typed after choosing is what the job gets."""
    from nnm_solver.integrators.registry import get_integrator

    rec = Recorder(nnm.load_branches(demo_file)[0])
    s = session_on(server, demo_file, start_job=rec)
    assert s.h_spp.value == get_integrator(s.h_integrator.value).steps
    seen = {}
    for name in ("newmark", "gauss4", "gauss6", "newmark"):
        s.h_integrator.value = name
        seen[name] = s.h_spp.value
        assert s.h_spp.value == get_integrator(name).steps
    assert seen["newmark"] != seen["gauss6"]          # the two defaults differ, so the test can see a stale field
    s.h_spp.value = 300
    s._cb(s._on_start)(None)
    assert (rec.calls[-1]["integrator"], rec.calls[-1]["steps_per_period"]) == ("newmark", 300)
    s._cb(s._on_stop)(None)
    s.last_runner.finished.wait(5)
    s.close()


def test_compute_tab_method_and_tongues_reach_the_job(server, demo_file, tmp_path):
    rec = Recorder(nnm.load_branches(demo_file)[0])
    s = session_on(server, demo_file, start_job=rec)
    assert s.h_integrator.visible and not s.h_harmonics.visible
    s.h_method.value = "condensed harmonic balance"
    assert not s.h_integrator.visible and not s.h_spp.visible and s.h_harmonics.visible
    s.h_harmonics.value = 5
    s.h_tongues.value = "skip"
    s._cb(s._on_start)(None)
    call = rec.calls[-1]
    assert (call["method"], call["condensed"], call["harmonics"], call["tongues"]) == ("hb", True, 5, "skip")
    assert "integrator" not in call and "steps_per_period" not in call
    s._cb(s._on_stop)(None)
    s.last_runner.finished.wait(5)
    s.close()
    # the real solver: a harmonic-balance branch, its settings say so
    path = tmp_path / "copy.h5"
    path.write_bytes(demo_file.read_bytes())
    s = session_on(server, path)
    s.h_method.value = "harmonic balance"
    s.h_harmonics.value = 5
    s.h_maxpts.value = 3
    s.h_emax.value = 1.0
    s._cb(s._on_start)(None)
    runner = s.last_runner
    assert runner.finished.wait(120) and runner.entry.source == "computed", runner.entry.status
    b = runner.entry.branch
    assert b.settings.method == "harmonic_balance" and b.settings.harmonics == 5 and len(b) == 3
    s.close()


def test_save_says_what_it_did_under_the_save_button(server, demo_file, tmp_path, monkeypatch):
    """Finding 4: after Compute -> Stop -> Save the message, with the file written, is right under the Save button
    of the Compute tab (it was only below the fold of the left panel); a refused save says why there too."""
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "copy.h5"
    path.write_bytes(demo_file.read_bytes())
    rec = Recorder(nnm.load_branches(path)[0])
    s = session_on(server, path, start_job=rec)
    assert s.h_save.order < s.h_save_msg.order < s.h_progress.order and s.h_save_msg.content == ""
    s._cb(s._on_start)(None)
    runner = s.last_runner
    runner.poll = 0.01
    from test_viewer_session import wait_for
    runner.job.release(5)
    wait_for(lambda: len(runner.entry) == 5)
    s._cb(s._on_stop)(None)
    assert runner.finished.wait(60)            # a generous bound: the machine may be loaded
    s._cb(s._on_save)(None)
    msg = s.h_save_msg.content
    assert msg.startswith("**Saved:**") and str(path) in msg and "5 points" in msg
    assert len(nnm.load_branches(path)) == 3
    s._cb(s._on_save)(None)                                   # again: refused, and said there
    assert s.h_save_msg.content.startswith("**Not saved:**") and "already in the file" in s.h_save_msg.content
    s._cb(s._on_start)(None)                                  # a new job: the message is cleared
    assert s.h_save_msg.content == ""
    s._cb(s._on_stop)(None)
    s.last_runner.finished.wait(5)
    s.close()


def _series(energy, freq, label, events=(), status="", stable=None):
    from nnm_viewer.fep import FepSeries
    energy, freq = np.asarray(energy, float), np.asarray(freq, float)
    return FepSeries(energy, freq, np.ones(len(energy), bool) if stable is None else stable, label,
                     events=list(events), status=status)


def test_panel_fep_keeps_every_marker_inside_and_lists_what_it_shows():
    """Finding 7: the panel FEP zoomed on a branch kept its lowest markers and a fold marker half outside the
    axes (5 % padding, a 10.5-pt end marker); its legend listed every branch while one was drawn, and the
    board's legend dropped the torus markers it drew (the legend was full of branches)."""
    from nnm_viewer.fep import FepRenderer, axis_ranges

    a = _series(np.logspace(-2, 1, 12), np.linspace(8.294, 8.2348, 12), "NNM 10",
                events=[("fold", 11.27, 8.2348), ("torus", 10.9, 8.2433)], status="escape")
    far = [_series(np.logspace(-1, 2, 5), 30 + np.arange(5.0), f"NNM {k}") for k in range(11, 19)]
    r = FepRenderer(size=(480, 470))
    zoom = axis_ranges([a])
    r.set_series([a] + far, 0, ranges=zoom)
    ax = r.ax
    box = ax.get_window_extent()
    xy = ax.transData.transform(np.c_[np.log10(np.r_[a.energy, 11.27, 10.9]), np.r_[a.frequency, 8.2348, 8.2433]])
    radius = 10.5 / 2 * r.fig.dpi / 72                           # the end marker, the largest
    margin = np.min(np.c_[xy[:, 0] - box.x0, box.x1 - xy[:, 0], xy[:, 1] - box.y0, box.y1 - xy[:, 1]])
    assert margin >= radius, (margin, radius)
    legend = [t.get_text() for t in r.legend.get_texts()]
    assert "NNM 10" in legend and not any(t.startswith("NNM 1") and t != "NNM 10" for t in legend), legend
    assert "torus (complex multipliers)" in legend and "end: escape" in legend and "fold (energy turns back)" in legend


def test_board_legend_keeps_the_event_markers_and_its_labels_fit():
    """The board's legend (14 entries at most) names the torus markers drawn even with many branches, and 6-digit
    tick labels leave the y axis label inside the picture."""
    from nnm_viewer.board import board_layout
    from nnm_viewer.scene import board_figure

    board = board_layout(np.zeros(3), np.ones(3), np.array([1.0, 1.0, -0.5]))
    many = [_series(np.logspace(-1, 2, 6), 123.4561 + 1e-4 * np.arange(6) + 1e-5 * k, f"NNM {k}",
                    events=[("torus", 10.0, 123.4563 + 1e-5 * k)]) for k in range(14)]
    fig = board_figure(board, axis_ranges_of(many), many)
    ax = fig.axes[0]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "torus (complex multipliers)" in legend
    renderer = fig.canvas.get_renderer()
    ticks = [t for t in ax.get_yticklabels() if t.get_text()]
    assert max(len(t.get_text()) for t in ticks) >= 7, [t.get_text() for t in ticks]
    assert min(t.get_window_extent(renderer).x0 for t in ticks) >= 0
    assert ax.yaxis.label.get_window_extent(renderer).x0 >= 0


def axis_ranges_of(series):
    from nnm_viewer.fep import axis_ranges
    return axis_ranges(series)


def test_mode_names_say_the_models_label_and_the_papers(server, tmp_path):
    """Finding 8: model mode 19 'wing torsion 2 (symmetric)' is the paper's first symmetric wing torsion, mode 20
    'wing torsion 1 (anti-symmetric)' its second wing torsion: the shipped file carries the paper's names
    (/extra/reference/mode_names) and the viewer's lists, branch names and Modes tab, and nnm-solve --list-modes,
    say both."""
    from pathlib import Path
    from nnm_solver.cli.modes import list_modes

    paris = Path(__file__).resolve().parents[1] / "assets" / "paris.h5"
    model = nnm.load_model(paris)
    shared = SharedState(model, path=paris, branches=nnm.load_branches(paris))
    s = Session(server, shared, sync=True)
    both19 = "wing torsion 2 (symmetric); paper: first (symmetric) wing torsion"
    both20 = "wing torsion 1 (anti-symmetric); paper: second (anti-symmetric) wing torsion"
    assert s.h_mode.options[18].endswith(both19) and s.h_lin_mode.options[19].endswith(both20)
    labels = [e.label for e in shared.entries]
    assert any(lab.startswith(f"NNM 19 ({both19})") for lab in labels), labels
    assert any(lab.startswith(f"NNM 20 ({both20})") for lab in labels), labels
    assert s.h_mode.options[10].endswith("wing bending 1 (anti-symmetric)")       # the paper names no other
    s.close()
    import io
    buf = io.StringIO()
    list_modes(model, nnm.load_extra(paris, "reference"), count=21, out=buf)
    out = buf.getvalue()
    assert both19 in out and both20 in out and "paper: first wing bending" in out
    # a file without the names: the model's labels alone
    plain = tmp_path / "plain.h5"
    nnm.save_model(plain, nnm.Model(np.eye(2), np.array([[2.0, -1], [-1, 2]]), mode_labels=["in", "out"]))
    assert SharedState(nnm.load_model(plain), path=plain).reference_names == {}


def test_a_resized_canvas_adds_the_board_spheres_anew(server, demo_file):
    """Issue 53, finding 7: viser sizes a clickable sphere's hover outline with the canvas size read when the
    spheres were added under their name; a camera message with a new canvas size adds them under a new name
    (the old group removed), the same size does nothing (tests/test_browser_board.py measures the halo)."""
    from types import SimpleNamespace

    from nnm_viewer.scene import sphere_group

    s = session_on(server, demo_file)
    fep = s.drawing.fep
    assert fep.board_group == sphere_group(None) and fep.board_handles
    before = dict(fep.board_handles)
    s._on_camera(SimpleNamespace(image_width=800, image_height=600))
    assert fep.board_group == "/fep/spheres_800x600" and s.view.canvas == (800, 600)
    assert set(fep.board_handles) == set(before)
    assert all(fep.board_handles[u] is not before[u] for u in before)     # new handles, under the new name
    assert all(h.name.startswith("/fep/spheres_800x600/") for h in fep.board_handles.values())
    again = dict(fep.board_handles)
    s._on_camera(SimpleNamespace(image_width=800, image_height=600))      # the camera turned: same canvas
    assert all(fep.board_handles[u] is again[u] for u in again)
    s._on_camera(SimpleNamespace(image_width=0, image_height=0))          # no canvas yet: ignored
    assert s.view.canvas == (800, 600)
    s.close()


def test_no_branch_is_drawn_in_the_colour_of_the_points_off_the_backbone():
    """Found in the fresh-clone trial of issue 53: the 4th branch (a Compute tab's second new branch) was drawn in
    tab:orange, the colour that says 'off the backbone (in a tongue)', and the 9th in a red-orange; the end marker
    of an escape was that orange too.  Every branch colour now keeps a hue away from orange (and from the red of
    failures and the yellow of the picked orbit), and stays distinct."""
    import colorsys

    from nnm_viewer.fep import END_MARKERS, branch_color, off_backbone_style, rgb

    _, off = off_backbone_style()

    def hue(c):
        r, g, b = (x / 255 for x in rgb(c))
        h, _, s = colorsys.rgb_to_hls(r, g, b)
        return h, s

    h_off, _ = hue(off)
    colours = [branch_color(k) for k in range(60)]
    assert len(set(colours)) == 60 and off not in colours
    for c in colours:
        h, _ = hue(c)
        far = np.linalg.norm(np.subtract(rgb(c), rgb(off)))          # a dark brown is not an orange
        assert min(abs(h - h_off), 1 - abs(h - h_off)) > 0.06 or far > 100, (c, h, far)
    assert all(colour != off for _, colour, _ in END_MARKERS.values())


def test_saves_at_once_write_one_after_the_other_and_say_so_at_once(server, demo_file, tmp_path, monkeypatch):
    """Found in the fresh-clone trial of issue 53: saving a branch of the aircraft (a 16 MB file) took seconds under
    load with nothing said meanwhile, and Save pressed again (or in another tab) while the file was written passed
    the 'already in the file' check: the branch was written twice, and two branches saved at once (each file write
    is atomic: a copy with the branch appended, then renamed) could keep only the last one.  Now the message says
    'Saving ... to FILE' at once, the writes take turns, a second save of the same branch is refused and the
    other branch is appended after the first."""
    import threading
    import time

    monkeypatch.chdir(tmp_path)
    path = tmp_path / "copy.h5"
    path.write_bytes(demo_file.read_bytes())
    before = len(nnm.load_branches(path))
    s = session_on(server, path)
    shared = s.shared
    base = shared.entries[0].branch
    a = shared.add(base.subset(slice(0, 6)), source="computed", saved=False)
    b = shared.add(base.subset(slice(2, 9)), source="computed", saved=False)
    real_save, active, most, seen = nnm.save_branch, [0], [0], []

    def slow_save(target, branch):
        active[0] += 1
        most[0] = max(most[0], active[0])
        seen.append(s.h_save_msg.content)        # what the tab says while the file is written
        time.sleep(0.3)
        try:
            return real_save(target, branch)
        finally:
            active[0] -= 1

    monkeypatch.setattr(nnm, "save_branch", slow_save)
    results = []

    def save(entry):
        try:
            results.append(shared.save(entry))
        except nnm.NNMInputError as exc:
            results.append(str(exc))

    threads = [threading.Thread(target=save, args=(e,)) for e in (a, a, b)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert most[0] == 1                                             # one write at a time
    assert sorted(map(str, results)).count("this branch is already in the file") == 1
    assert len(nnm.load_branches(path)) == before + 2              # a once, b once: nothing lost, nothing doubled
    # the tab's Save: the message is there while the file is written
    shared.update(a, source="computed")
    s.set_view(sel_uid=b.uid)
    with shared.lock:
        b.saved = False
    seen.clear()
    s._cb(s._on_save)(None)
    assert seen and seen[0].startswith("**Saving**") and str(path) in seen[0]
    assert s.h_save_msg.content.startswith("**Saved:**")
    s.close()


def test_a_harmonic_balance_job_that_raises_its_harmonics_streams_to_its_end(tmp_path):
    """Found in the fresh-clone trial of issue 53: the Compute tab's condensed harmonic balance with tongues 'skip'
    on the 2-DOF model to 1e4 J failed after 92 points ('solver job failed: all the input array dimensions ...
    must match exactly ... size 4 ... size 5'): the accuracy target raised the harmonics 7 -> 9 mid-branch and
    the next point's coefficients no longer fit the rows received.  Now the job runs to its end, and every row
    streamed is the solver's own (the same as continue_nnm's branch, row for row)."""
    from nnm_viewer.worker import JobRunner

    from pathlib import Path

    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "two_dof.h5")
    opts = dict(max_points=500, tongues="skip", method="hb", harmonics=7, condensed=True)
    direct = nnm.continue_nnm(model, 1, 1e4, **opts)
    assert direct.settings.harmonics > 7                      # the target raised them: the case of the finding
    shared = SharedState(model)
    runner = JobRunner(shared, 1, 1e4, poll=0.02, **opts)
    runner.start()
    assert runner.finished.wait(600)
    e = runner.entry
    assert e.source == "computed" and not shared.error, (e.source, shared.error)
    assert len(e.branch) == len(direct) and e.branch.coefficients.shape == direct.coefficients.shape
    np.testing.assert_allclose(e.branch.energy, direct.energy, rtol=1e-9)
