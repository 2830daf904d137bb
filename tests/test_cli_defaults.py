"""nnm-solve's progress line and default output file (issue 14, item 12)."""
import hashlib
import io
from pathlib import Path

import numpy as np

import nnm_solver as nnm
from nnm_solver.cli import outputs
from nnm_solver.cli import solve as cli

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "nnm_viewer" / "data" / "two_dof.h5"


class _Job:
    """A job with no point for two polls, then one point, then done."""

    def __init__(self, model):
        self.model, self.polls = model, 0

    @property
    def done(self):
        return self.polls >= 4

    @property
    def progress(self):
        return 0.0 if self.polls < 3 else 0.5

    def rows(self, start=0):
        """(the progress reads the points' energies and frequencies, not a Branch snapshot: job.rows / latest)"""
        self.polls += 1
        return [(1.5, 0.2)][start:] if self.polls >= 3 else []

    def latest(self):
        rows = self.rows()
        return (len(rows), *rows[-1]) if rows else (0, np.nan, np.nan)

    def points(self):
        raise AssertionError("the progress line builds no Branch snapshot (it costs a copy of every point's state)")


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_shows_no_nan_before_the_first_point():
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    out = _Terminal()
    cli._progress(_Job(model), out, interval=0.0)
    lines = out.getvalue().split("\r")
    assert "nan" not in out.getvalue().lower()
    assert "waiting for the first point" in lines[1]
    assert "E = 1.500e+00 J" in lines[-1] and "f = 0.20000 Hz" in lines[-1]


def test_progress_into_a_file_is_one_line_per_point_not_a_rewritten_line():
    """Into a log file or a pipe the progress line is not rewritten with carriage returns several times a second
    (a 2-minute run wrote 500 copies of it): each new point is one line."""
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    out = io.StringIO()
    cli._progress(_Job(model), out, interval=0.0)
    assert "\r" not in out.getvalue()
    assert out.getvalue().splitlines() == ["point    1  E = 1.5000e+00 J  f = 0.200000 Hz"]


def test_branch_on_a_shipped_example_goes_to_the_current_folder(tmp_path, monkeypatch, capsys):
    before = hashlib.sha1(SHIPPED.read_bytes()).hexdigest()
    monkeypatch.chdir(tmp_path)
    assert outputs.default_out(SHIPPED) == (tmp_path / "two_dof_branches.h5", "two_dof.h5 is a shipped example")
    code = cli.main([str(SHIPPED), "--mode", "2", "--energy-max", "0.01", "--max-points", "3"])
    out = capsys.readouterr().out
    assert code == 0
    assert "two_dof.h5 is a shipped example: the branch will be saved to" in out
    assert [b.mode for b in nnm.load_branches(tmp_path / "two_dof_branches.h5")] == [2]
    assert hashlib.sha1(SHIPPED.read_bytes()).hexdigest() == before


def test_default_out_is_the_file_unless_it_cannot_be_written(tmp_path, monkeypatch):
    p = tmp_path / "m.h5"
    p.write_bytes(b"")
    assert outputs.default_out(p) == (p, "")
    assert outputs.default_out(tmp_path / "m.mat") == (tmp_path / "m.h5", "")
    monkeypatch.chdir(tmp_path / "..")
    monkeypatch.setattr("os.access", lambda path, mode: False)        # (root may write anywhere)
    out, reason = outputs.default_out(p)
    assert out == Path.cwd() / "m_branches.h5" and reason == f"{p} is not writable"


def test_job_rows_and_latest_are_the_branch_points():
    """What the progress line reads (Job.rows, Job.latest) is the points' own energies and frequencies."""
    from nnm_solver.driver.jobs import start_branch
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    job = start_branch(model, 1, 1.0, max_points=12)
    b = job.result(timeout=300)
    rows = job.rows()
    assert len(rows) == len(b) > 3
    assert np.allclose([r[0] for r in rows], b.energy, rtol=0, atol=0)
    assert np.allclose([r[1] for r in rows], b.frequency_hz, rtol=0, atol=0)
    assert job.rows(2) == rows[2:]
    assert job.latest() == (len(b), rows[-1][0], rows[-1][1])
