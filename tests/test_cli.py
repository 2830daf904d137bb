"""nnm-solve: listing modes, computing and saving a branch, Ctrl-C, and one-line errors."""
import signal
import subprocess
import sys
import time

import numpy as np
import scipy.io

import nnm_solver as nnm

from conftest import two_dof_model


def run(*args, timeout=120):
    return subprocess.run([sys.executable, "-m", "nnm_solver.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


def test_list_modes(tmp_path):
    p = tmp_path / "m.h5"
    nnm.save_model(p, nnm.Model(np.eye(2), np.array([[2.0, -1], [-1, 2]]), mode_labels=["in phase", "out"]),
                   extra={"reference": {"table2_hz": np.array([0.16, 0.28])}})
    r = run(p, "--list-modes")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert "reference" in lines[0]
    assert lines[1].split()[:3] == ["1", "0.1592", "0.1600"] and "in phase" in lines[1]
    assert lines[2].split()[1] == "0.2757"
    # a legend names every column of the header
    assert lines[3].startswith("columns: ") and len(lines) == 4
    for column in ("mode:", "freq:", "reference:", "diff:", "label:"):
        assert column in lines[3], column
    assert "(1-based)" in lines[3] and "(Hz" in lines[3]
    nnm.save_model(p, nnm.Model(np.eye(2), np.array([[2.0, -1], [-1, 2]])))      # no reference, no labels
    r = run(p, "--list-modes")
    assert r.returncode == 0, r.stderr
    legend = r.stdout.splitlines()[-1]
    assert legend.startswith("columns: mode:") and "reference" not in legend and "label" not in legend


def test_mode_out_of_range_on_a_shipped_example_is_one_line(tmp_path):
    """`nnm-solve assets/paris.h5 --mode 999 ...`: the error alone (no notice about where the branch would
    have been saved), exit code 2, nothing written."""
    from pathlib import Path
    shipped = Path(__file__).resolve().parents[1] / "assets" / "paris.h5"
    for extra in ((), ("--energy-max", "1")):
        r = subprocess.run([sys.executable, "-m", "nnm_solver.cli", str(shipped), "--mode", "999", *extra],
                           capture_output=True, text=True, timeout=120, cwd=tmp_path)
        assert r.returncode == 2, (r.stdout, r.stderr)
        lines = (r.stdout + r.stderr).strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("nnm-solve: error: "), lines
    assert lines == ["nnm-solve: error: mode 999 is out of range: this model has modes 1..548"]
    r = subprocess.run([sys.executable, "-m", "nnm_solver.cli", str(shipped), "--mode", "2", "--energy-max", "-1"],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == "", (r.stdout, r.stderr)
    assert r.stderr.strip() == "nnm-solve: error: energy_max must be a positive number, got -1.0"
    assert list(tmp_path.iterdir()) == []


def test_solve_saves_branch_and_plot(tmp_path):
    p = tmp_path / "m.h5"
    nnm.save_model(p, two_dof_model())
    out = tmp_path / "out.h5"
    png = tmp_path / "fep.png"
    r = run(p, "--mode", 1, "--energy-max", 10, "--out", out, "--plot", png)
    assert r.returncode == 0, r.stderr
    assert "reached energy_max" in r.stdout
    b = nnm.load_branches(out)
    assert len(b) == 1 and b[0].energy[-1] >= 10
    assert png.stat().st_size > 10_000
    r = run(p, "--mode", 2, "--energy-max", 1)       # default: appended to the input file
    assert r.returncode == 0, r.stderr
    assert [x.mode for x in nnm.load_branches(p)] == [2]


def test_mat_input(tmp_path):
    p = tmp_path / "m.mat"
    scipy.io.savemat(p, {"M": np.eye(2), "K": np.array([[2.0, -1], [-1, 2]]), "springs": np.array([[1, 0, 0.5]])})
    r = run(p, "--mode", 1, "--energy-max", 1)
    assert r.returncode == 0, r.stderr
    assert len(nnm.load_branches(tmp_path / "m.h5")) == 1


def test_ctrl_c_keeps_points(tmp_path):
    p = tmp_path / "m.h5"
    nnm.save_model(p, two_dof_model())
    proc = subprocess.Popen([sys.executable, "-m", "nnm_solver.cli", str(p), "--mode", "1", "--energy-max", "1e12",
                             "--max-points", "100000", "--steps-per-period", "5000"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            # a runner started in the background ignores SIGINT, and children inherit that
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # Ctrl-C once the first point is there (its progress line says so): under load the import alone can take
    # seconds, and a signal during it is not the case under test
    import os
    import selectors
    sel = selectors.DefaultSelector()
    sel.register(proc.stderr, selectors.EVENT_READ)          # (the progress line is on stderr)
    seen, deadline = b"", time.time() + 120
    while b" points " not in seen and time.time() < deadline and proc.poll() is None:
        if sel.select(timeout=1.0):
            seen += os.read(proc.stderr.fileno(), 4096)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    b = nnm.load_branches(p)
    assert len(b) == 1 and b[0].status == "cancelled" and len(b[0]) >= 1


def test_errors_are_one_line(tmp_path):
    p = tmp_path / "m.h5"
    nnm.save_model(p, two_dof_model())
    junk = tmp_path / "junk.h5"
    junk.write_text("no")
    cases = [
        ((tmp_path / "missing.h5", "--list-modes"), "no such file"),
        ((junk, "--list-modes"), "not a readable HDF5"),
        ((p, "--mode", 3, "--energy-max", 1), "out of range"),
        ((p, "--mode", 1, "--energy-max", -1), "energy_max"),
        ((p, "--mode", 1), "--energy-max"),
        ((p, "--list-modes", "--count", 0), "--count"),
        ((p, "--mode", 1, "--energy-max", 1, "--damping", 0.02), "--damping: goes with --forced"),
        ((p, "--mode", 1, "--energy-max", 1, "--workers", 2), "--workers: goes with --modes"),
        ((p, "--mode", 1, "--energy-max", 1, "--plot", tmp_path / "fep.xyz"), "fep.xyz"),
    ]
    for args, fragment in cases:
        r = run(*args)
        assert r.returncode == 2, (args, r.stdout, r.stderr)
        assert fragment in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
        assert r.stdout == "", (args, r.stdout)


def test_progress_into_a_pipe_has_every_point(tmp_path):
    """Into a pipe (not a terminal) one progress line per point, the last ones too (the lines of the points
    computed after the last poll were dropped: 8 of 57 lines), and --floquet goes to the branch."""
    p = tmp_path / "m.h5"
    nnm.save_model(p, two_dof_model())
    r = run(p, "--mode", 1, "--energy-max", 10, "--out", tmp_path / "o.h5", "--method", "hb", "--floquet")
    assert r.returncode == 0, r.stderr
    (b,) = nnm.load_branches(tmp_path / "o.h5")
    lines = [line for line in r.stderr.splitlines() if line.startswith("point ")]
    assert len(lines) == len(b) and lines[-1].startswith(f"point {len(b):4d}")
    assert b.settings["floquet"] is True and np.all(np.isfinite(b.floquet))
