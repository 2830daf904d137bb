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
