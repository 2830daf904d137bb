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
    assert runner.finished.wait(5)
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
