"""nnm-solve --forced: a forced response from the command line, saved under /forced; bad input one line."""
import shutil
import subprocess
import sys
from pathlib import Path

import nnm_solver as nnm

ROOT = Path(__file__).resolve().parents[1]


def run(*args, cwd):
    return subprocess.run([sys.executable, "-m", "nnm_solver.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=600)


def test_forced_response_from_the_command_line(tmp_path):
    shutil.copy(ROOT / "assets" / "two_dof.h5", tmp_path / "model.h5")
    p = run("model.h5", "--forced", "--force-dof", 0, "--force", 0.05, "--f-range", 0.12, 0.25, "--damping", 0.01,
            "--harmonics", 5, "--out", "fr.h5", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "peak at DOF 0" in p.stdout and "saved as /forced/" in p.stdout
    (r,) = nnm.load_forced_responses(tmp_path / "fr.h5")
    assert r.status == "done" and r.frequency_hz.min() <= 0.1201 and r.frequency_hz.max() >= 0.2499
    assert len(r.folds) == 2                              # the hardening resonance's two folds at this level
    bad = run("model.h5", "--forced", "--force-dof", 7, "--force", 0.05, "--f-range", 0.12, 0.25, cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0 and "--force-dof 7" in bad.stderr
    missing = run("model.h5", "--forced", "--force-dof", 0, cwd=tmp_path)
    assert missing.returncode == 2 and "--f-range" in missing.stderr


def test_forced_defaults_flags_and_plot(tmp_path):
    """Without --harmonics the solver's default (it failed: 'harmonics must be a positive integer, got None');
    --max-points, --condensed and --plot are used; an NNM branch's flags are refused in one line (they were
    ignored); a file of another model as --out is refused before anything is computed."""
    shutil.copy(ROOT / "assets" / "two_dof.h5", tmp_path / "model.h5")
    force = ("--forced", "--force-dof", 0, "--force", 0.05, "--f-range", 0.12, 0.25)
    p = run("model.h5", *force, "--max-points", 30, "--plot", "frf.png", "--out", "fr.h5", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    (r,) = nnm.load_forced_responses(tmp_path / "fr.h5")
    assert len(r) == 30 and r.status == "max_points" and r.harmonics == 7
    assert (tmp_path / "frf.png").stat().st_size > 10_000
    for extra in (["--csv", "frf.csv"], ["--method", "hb"], ["--tongues", "skip", "--tol", 1e-7], ["--floquet"]):
        bad = run("model.h5", *force, *extra, "--out", "fr2.h5", cwd=tmp_path)
        assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0, bad.stderr
        assert "not used by --forced" in bad.stderr and not (tmp_path / "fr2.h5").exists()
    other = tmp_path / "other.h5"
    nnm.save_model(other, nnm.Model([[1.0]], [[1.0]], [nnm.CubicSpring(dof=0, k3=1.0)]))
    before = other.read_bytes()
    bad = run("model.h5", *force, "--out", other, cwd=tmp_path)
    assert bad.returncode == 2 and "holds another model" in bad.stderr and "forced response:" not in bad.stdout
    assert other.read_bytes() == before
    bad = run("model.h5", *force, "--plot", "frf.xyz", "--out", "fr3.h5", cwd=tmp_path)
    assert bad.returncode == 2 and "frf.xyz" in bad.stderr and not (tmp_path / "fr3.h5").exists()
