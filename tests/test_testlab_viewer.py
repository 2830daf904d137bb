"""A measured backbone on the viewer's FEP (issue 54): read with its units, placed at the selected branch's
energies (its own points land on the branch), drawn in the panel image's legend, bad files exit 2 at start-up."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_viewer import app
from nnm_viewer.demo import write_demo_file
from nnm_viewer.measured import load_measured, on_fep
from nnm_viewer.state import SharedState

viser = pytest.importorskip("viser")


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    path = tmp_path_factory.mktemp("measured") / "two.h5"
    write_demo_file(path, energy_max=10.0)
    model = nnm.load_model(path)
    return path, model, nnm.load_branches(path)


def backbone_csv(path, branch, dof, label, pick=slice(1, None, 3)):
    """The branch's own peak amplitudes at ``dof`` (|x0|: its orbits start at rest) as a measured CSV in mm."""
    amp = np.abs(branch.x0[pick, dof])
    np.savetxt(path, np.column_stack([branch.frequency_hz[pick], 1e3 * amp]), delimiter=",",
               header=f"frequency (Hz), {label} (mm)", comments="")
    return amp, branch.energy[pick]


def test_measured_points_land_on_their_branch(demo, tmp_path):
    path, model, branches = demo
    b = branches[0]
    dof = 0
    amp, energy = backbone_csv(tmp_path / "bb.csv", b, dof, "amplitude")
    m = load_measured(tmp_path / "bb.csv", model, dof=str(dof))
    np.testing.assert_allclose(m.amplitude, amp, rtol=1e-12)               # mm -> m
    assert m.dof == 0 and m.label == f"measured ({len(amp)} points)"
    e, f = on_fep(m, b, b.energy, b.energy)
    np.testing.assert_allclose(e, energy, rtol=1e-6)
    # at a k3 factor of 2 (cubic scaling law) point j of the branch has energy E_j / 2 and amplitude A_j / sqrt(2)
    from dataclasses import replace

    half = on_fep(replace(m, amplitude=m.amplitude / np.sqrt(2.0)), b, b.energy / 2.0, b.energy)[0]
    np.testing.assert_allclose(half, energy / 2.0, rtol=1e-6)


def test_the_fep_panel_draws_the_measured_points(demo, tmp_path):
    from nnm_viewer.controls import Session

    path, model, branches = demo
    backbone_csv(tmp_path / "bb.csv", branches[0], 0, "amplitude")
    shared = SharedState(model, path=path, branches=branches, measured=load_measured(tmp_path / "bb.csv", model, 0))
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        session = Session(server, shared, sync=True)
        session.drawing.fep.draw_series()
        legend = [t.get_text() for t in session.drawing.fep.renderer.legend.get_texts()]
        assert any(t.startswith("measured (") for t in legend)
        rings = [ln for ln in session.drawing.fep.renderer.ax.lines if ln.get_marker() == "o" and ln.get_mfc() == "none"]
        assert len(rings) == 1 and len(rings[0].get_xdata()) == len(branches[0].x0[1::3])
        session.close()
    finally:
        server.stop()


@pytest.mark.parametrize("text, message", [
    ("time (s), x (mm)\n0, 1\n0.1, 2\n0.2, 3\n", "a time record"),
    ("frequency (Hz), x (g)\n1, 1\n2, 2\n3, 3\n", "is a acceleration"),
    ("frequency (Hz), x (mm)\n1, 1\n2, oops\n3, 3\n", "'oops' in column 'x (mm)' is not a number"),
])
def test_a_bad_measured_file_stops_the_viewer_with_one_line(demo, tmp_path, capsys, text, message):
    path, _, _ = demo
    bad = tmp_path / "bad.csv"
    bad.write_text(text)
    assert app.main([str(path), "--measured", str(bad), "--measured-dof", "0", "--port", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("nnm-view: error:") and message in err and "\n" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]          # nothing written
