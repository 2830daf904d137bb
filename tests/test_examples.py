"""The examples' fast modes run end to end and show what they demonstrate."""
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver import analysis

ROOT = Path(__file__).resolve().parents[1]
PARIS = ROOT / "assets" / "paris.h5"


def load_example(name):
    spec = importlib.util.spec_from_file_location(f"example_{name}", ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_two_dof_tongues_fast(tmp_path):
    ex = load_example("two_dof_tongues")
    h5 = tmp_path / "two_dof.h5"
    summary = tmp_path / "summary.json"
    assert ex.main(["--fast", "--out-dir", str(tmp_path), "--assets", str(h5), "--summary", str(summary)]) == 0
    s = json.loads(summary.read_text())
    t31 = [t for t in s["tongues"]["nnm1"] if t["label"] == "3:1"]
    assert len(t31) == 1 and t31[0]["complete"]            # traversed: in, down to the tip, and out again
    assert t31[0]["tip_energy"] == pytest.approx(286, rel=0.05)
    assert t31[0]["entry_energy"] > 10 * t31[0]["tip_energy"]
    assert s["picks"]["a"]["fraction3"] < 0.15 < 0.5 < s["picks"]["c"]["fraction3"]
    assert s["picks"]["c"]["description"].startswith("3:1 internal resonance")
    # ... and on to the 5:1 tongue
    assert "5:1" in [t["label"] for t in s["tongues"]["nnm1"]]
    # the file opens with its mesh and three branches; the tongue's far end is dominated by harmonic 3
    model = nnm.load_model(h5)
    assert model.mesh is not None and model.mesh.displacement_map.shape[1] == 2
    branches = nnm.load_branches(h5, model)
    assert [b.name for b in branches] == ["NNM1", "NNM2"]
    b1 = branches[0]
    k, frac, *_ = analysis.dominant_harmonic(b1, t31[0]["tip"])
    assert k == 3 and frac > 0.5
    assert analysis.dominant_harmonic(b1, t31[0]["start"])[0] == 1
    # the mesh moves each mass with its DOF along x, and the walls stay
    u = model.mesh.displacements(np.array([1.0, 0.0]))
    assert np.allclose(u[:, 1:], 0) and u[:, 0].max() == pytest.approx(1.0) and u[:, 0].min() == 0.0
    for png in tmp_path.glob("*.png"):
        assert png.stat().st_size < 150_000, png
    assert h5.stat().st_size < 2_000_000


@pytest.mark.slow
def test_paris_fast(tmp_path):
    if not PARIS.exists():
        pytest.skip("assets/paris.h5 is not there (built by examples/build_paris.py)")
    summary = tmp_path / "summary.json"
    out = tmp_path / "paris_branches.h5"
    # a separate process, so that the script's one-thread BLAS setting applies (see examples/paris_fep.py)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "paris_fep.py"), "--fast", "--out-dir",
                          str(tmp_path), "--save-to", str(out), "--summary", str(summary)],
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    s = json.loads(summary.read_text())["modes"]
    m13, m20 = s["13"], s["20"]
    # tail bending: frequency unchanged (< 0.5 %) over the energy range where wing torsion softens
    assert abs(m13["drop_pct"]) < 0.5 and abs(m13["backbone_min_f_pct"]) < 0.5
    assert m13["energy_max"] >= 0.5 * m20["energy_max"]
    assert m20["drop_pct"] > 0.5 and m20["backbone_min_f_pct"] > 0.5       # anti-symmetric wing torsion softens
    # builder 1.1: the tail bending (model mode 13, 3.4 % of its strain energy in the attachments) softens
    # 0.47 % at these coarse settings, mode 20 (25 %) 2.1 %
    assert m20["drop_pct"] > 4 * abs(m13["drop_pct"])
    assert len(nnm.load_branches(out)) == 2
    for png in tmp_path.glob("*.png"):
        assert png.stat().st_size < 150_000, png


def test_bilinear_attachment_two_dof(tmp_path):
    """examples/bilinear_attachment.py, 2-DOF part: the bilinear law has the cubic's force and energy at the
    representative deformation, is linear below d1 (backbone at the linear frequency), and softens past
    it to within a few tenths of a percent of the cubic backbone at the top energy."""
    ex = load_example("bilinear_attachment")
    summary = tmp_path / "summary.json"
    assert ex.main(["--two-dof-only", "--out-dir", str(tmp_path), "--summary", str(summary)]) == 0
    r = json.loads(summary.read_text())["two_dof"]
    d_r, d1, k1, k3 = r["d_r"], r["d1"], r["k1"], r["k3"]
    assert d1 == pytest.approx(d_r / 2) and k1 == pytest.approx(2 * k3 * d_r ** 2) and k1 < 0
    pw = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.0, k1], breakpoints=[d1])
    assert float(pw.exact_force(d_r)) == pytest.approx(k3 * d_r ** 3, rel=1e-12)
    m = nnm.Model(np.eye(1), np.eye(1), [pw])
    assert m.energy(np.array([d_r]), np.zeros(1)) - 0.5 * d_r ** 2 == pytest.approx(k3 * d_r ** 4 / 4, rel=1e-4)
    c, b = r["cubic"], r["bilinear"]
    assert c["status"] == b["status"] == "done" and c["stable"] and b["stable"]
    assert c["energy"][1] == pytest.approx(2.0, rel=1e-5) and b["energy"][1] == pytest.approx(2.0, rel=1e-5)
    assert c["peak_d"] == pytest.approx(d_r) and b["peak_d"] == pytest.approx(d_r, rel=0.02)
    assert b["linear_below_d1"] < 1e-7                       # nothing happens below the breakpoint
    assert -2.5 < c["drop_percent"] < -1.5 and -2.5 < b["drop_percent"] < -1.5
    assert abs(b["drop_percent"] - c["drop_percent"]) < 0.3
    low = r["table"][0]
    assert low["bilinear_percent"] == pytest.approx(0.0, abs=1e-5) and low["cubic_percent"] < -0.01
    assert (tmp_path / "bilinear_two_dof.png").stat().st_size < 150_000
