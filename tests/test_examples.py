"""The examples' fast modes run end to end and show what they demonstrate."""
from types import SimpleNamespace
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver import analysis

ROOT = Path(__file__).resolve().parents[1]
PARIS = ROOT / "assets" / "paris.h5"


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def paris_copy(tmp_path):
    """A copy of the repository's layout for examples/paris_fep.py (the script and assets/paris.h5): the
    script's ROOT is then the copy, so that whatever it writes cannot touch the real assets/ or docs/."""
    repo = tmp_path / "repo"
    (repo / "examples").mkdir(parents=True)
    (repo / "assets").mkdir()
    shutil.copy(ROOT / "examples" / "paris_fep.py", repo / "examples" / "paris_fep.py")
    shutil.copy(PARIS, repo / "assets" / "paris.h5")
    return repo


def run_paris(repo, *args, timeout=300):
    # a separate process, so that the script's one-thread BLAS setting applies (see examples/paris_fep.py)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    return subprocess.run([sys.executable, "examples/paris_fep.py", *map(str, args)], cwd=repo, env=env,
                          capture_output=True, text=True, timeout=timeout)


def load_example(name):
    spec = importlib.util.spec_from_file_location(f"example_{name}", ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_two_dof_tongues_writes_the_shipped_files_only_when_asked(tmp_path, monkeypatch):
    """Issue 32: by default the example writes ./two_dof.h5 and ./two_dof_figures/, never the shipped
    assets/two_dof.h5 and docs/img (those with --update-shipped)."""
    ex = load_example("two_dof_tongues")
    monkeypatch.chdir(tmp_path)
    ns = lambda **kw: SimpleNamespace(**{"out_dir": None, "assets": None, "update_shipped": False, **kw})  # noqa: E731
    assert ex.default_outputs(ns()) == ("two_dof_figures", "two_dof.h5")
    assert ex.default_outputs(ns(update_shipped=True)) == (str(ex.SHIPPED_FIGURES), str(ex.SHIPPED))
    assert ex.default_outputs(ns(assets="x.h5", out_dir="f")) == ("f", "x.h5")
    assert ex.SHIPPED == ROOT / "assets" / "two_dof.h5"
    # issue 53, finding 9: a --fast run never replaces the full run's file and figures
    assert ex.default_outputs(ns(fast=True)) == ("two_dof_figures_fast", "two_dof_fast.h5")
    assert ex.default_outputs(ns(fast=True, update_shipped=True)) == (str(ex.SHIPPED_FIGURES), str(ex.SHIPPED))


def test_example_outputs_are_ignored_by_git(tmp_path):
    """Finding 9: the default folders and files the examples write in the repository's root are ignored."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    paths = ["byom/beam.h5", "two_dof.h5", "two_dof_fast.h5", "two_dof_figures_fast/two_dof_fep.png",
             "paris_fep_figures/x.png"]
    r = subprocess.run(["git", "check-ignore", "--no-index", *paths], cwd=ROOT, capture_output=True, text=True)
    assert sorted(r.stdout.split()) == sorted(paths), r.stdout


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
    shipped = sha256(PARIS)
    # a separate process, so that the script's one-thread BLAS setting applies (see examples/paris_fep.py)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "paris_fep.py"), "--fast", "--out-dir",
                          str(tmp_path), "--out", str(out), "--summary", str(summary)],
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert sha256(PARIS) == shipped
    # issue 32: no raw scipy warning, and the table's introduction says what was computed
    assert "Warning" not in run.stderr and "Singular matrix" not in run.stderr, run.stderr[-2000:]
    assert "Floquet multipliers at every point" not in run.stdout
    assert "no Floquet multipliers: stability not computed (--fast)" in run.stdout
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


@pytest.mark.slow
def test_paris_tutorial_command_leaves_the_shipped_file_alone(tmp_path):
    """docs/tutorial.md's `python examples/paris_fep.py --fast` (issue 32, item 1) writes ./paris_fep.h5 and
    ./paris_fep_figures/ in the current folder; assets/paris.h5 (what `nnm-view paris.h5` shows) stays
    byte-identical, and docs/ is not written.  Run on a copy of the layout, so the test cannot damage anything;
    the real file is checked too.  Only --update-shipped writes the shipped file."""
    if not PARIS.exists():
        pytest.skip("assets/paris.h5 is not there (built by examples/build_paris.py)")
    real = sha256(PARIS)
    repo = paris_copy(tmp_path)
    shipped = repo / "assets" / "paris.h5"
    before = sha256(shipped)
    n_shipped = len(nnm.load_branches(shipped))
    run = run_paris(repo, "--fast")                      # exactly the tutorial's command, from the repository root
    assert run.returncode == 0, run.stderr[-2000:]
    assert "wrote 2 branches to paris_fep.h5" in run.stdout
    assert "open the branches with: nnm-view paris_fep.h5" in run.stdout
    assert sha256(shipped) == before and sha256(PARIS) == real
    assert not (repo / "docs").exists()                  # neither docs/img figures nor docs/paris_results.md
    assert sorted(f.name for f in (repo / "paris_fep_figures").glob("*.png")) == [
        "paris_fep_mode13.png", "paris_fep_mode20.png", "paris_fep_overview.png"]
    out = repo / "paris_fep.h5"
    model = nnm.load_model(out)                          # the shipped model, copied ...
    ref = nnm.load_model(shipped)
    assert model.n == ref.n and model.springs == ref.springs and model.mesh is not None
    assert sorted(b.name for b in nnm.load_branches(out, model)) == ["mode13", "mode20"]    # ... with the new branches
    assert len(nnm.load_branches(shipped, ref)) == n_shipped                                 # the shipped ones kept
    # the maintainers' regeneration, asked for explicitly (here from the branches just computed: no computation)
    run = run_paris(repo, "--branches-from", "paris_fep.h5", "--modes", "13,20", "--fast", "--update-shipped")
    assert run.returncode == 0, run.stderr[-2000:]
    assert f"wrote 2 branches to {shipped}" in run.stdout
    assert sorted(b.name for b in nnm.load_branches(shipped)) == ["mode13", "mode20"]
    assert (repo / "docs" / "img" / "paris_fep_overview.png").exists()
    assert sha256(PARIS) == real


def test_paris_refuses_to_write_the_shipped_file_without_update_shipped(tmp_path, monkeypatch, capsys):
    """An --out naming the shipped file is refused before anything is computed (exit 2, one line).  The
    script of the copied layout runs in this process (its ROOT is the copy)."""
    if not PARIS.exists():
        pytest.skip("assets/paris.h5 is not there (built by examples/build_paris.py)")
    repo = paris_copy(tmp_path)
    shipped = repo / "assets" / "paris.h5"
    before = sha256(shipped)
    spec = importlib.util.spec_from_file_location("example_paris_fep_copy", repo / "examples" / "paris_fep.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    assert ex.SHIPPED == shipped
    monkeypatch.chdir(repo)
    for args, msg in [(("--fast", "--out", "assets/paris.h5"),
                       "assets/paris.h5 is the shipped example (nnm-view shows it as paris.h5): write your branches "
                       "to another file with --out PATH (default ./paris_fep.h5), or regenerate the shipped file "
                       "with --update-shipped"),
                      (("--fast", "--save-to", shipped), "is the shipped example"),
                      (("--fast", "--update-shipped", "--out", "mine.h5"), "give one of them")]:
        assert ex.main([str(a) for a in args]) == 2, args
        out, err = capsys.readouterr()
        err = err.strip()
        assert "\n" not in err and err.startswith("error: ") and msg in err, err
        assert out == ""                                    # refused before loading the model or computing
    assert sha256(shipped) == before
    assert sorted(p.name for p in repo.iterdir()) == ["assets", "examples"]


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


def test_paris_fep_texts_say_no_fold_and_thin_only_what_it_thins(two_dof_nnm1, monkeypatch):
    """Finding 7: the results table said 'folds at none J' for a tongue without folds, and a branch short enough
    to be saved whole got '[saved 21 of 21 points to keep the file small]' in its message."""
    ex = load_example("paris_fep")
    t = dict(label="3:1", partner_mode=39, partner_hz=95.4, partner_label="tail torsion", partner_kind="tail",
             partner_mac=1.0, entry_energy=3.57, entry_frequency_hz=31.8, jumped=True, points=26,
             energy_range=(3.57, 276.0), folds=[], order=3, tip_fraction=0.99, tip_energy=246.0, status="done")
    text = ex.fmt_tongue(t)
    assert "no fold" in text and "none J" not in text and "folds at" not in text
    assert "folds at 276, 4.22 J" in ex.fmt_tongue({**t, "folds": [276.0, 4.22]})
    long, short = two_dof_nnm1, two_dof_nnm1.subset(slice(0, 21))
    monkeypatch.setattr(ex, "MAX_FILE_BYTES", 80e3)           # room for ~37 points per branch of 2 DOFs
    out = ex.thin([long, short], 0.0, log=lambda *a: None)
    assert out[1] is short and "keep the file small" not in out[1].message
    assert len(out[0]) < len(long) and f"of {len(long)} points to keep the file small" in out[0].message
