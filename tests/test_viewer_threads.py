"""The viewer's shared state under concurrent tabs (issue 53, finding 10): Start pressed in two tabs at
once starts one job, which either tab can stop; a broken listener is logged, not swallowed; the view
state of a tab is one immutable record swapped under its lock."""
import logging
import threading
import time

import pytest

import nnm_solver as nnm
from nnm_viewer.controls import Session
from nnm_viewer.state import SharedState

from test_viewer_session import FakeJob, demo_file, server, wait_for  # noqa: F401 (fixtures)

viser = pytest.importorskip("viser")




class SlowStart:
    """A ``start_job`` that takes a while to return its job (as the solver's start does while it builds
    the problem): the window in which a second Start used to pass the 'a job is running' check."""

    def __init__(self, branch, delay=0.3):
        self.branch, self.delay, self.jobs = branch, delay, []
        self.lock = threading.Lock()

    def __call__(self, model, mode, energy_max, **kw):
        time.sleep(self.delay)
        job = FakeJob(self.branch)
        with self.lock:
            self.jobs.append(job)
        return job


def test_start_from_two_tabs_at_once_runs_one_job_that_either_tab_stops(server, demo_file):
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file))
    starter = SlowStart(shared.entries[0].branch)
    tabs = [Session(server, shared, sync=True, start_job=starter) for _ in range(2)]
    barrier = threading.Barrier(2)
    outcomes = [None, None]

    def press(k):
        barrier.wait()
        try:
            outcomes[k] = tabs[k]._on_start(None)
        except ValueError as exc:
            outcomes[k] = exc

    threads = [threading.Thread(target=press, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(10)
    runners = [o for o in outcomes if not isinstance(o, Exception)]
    refused = [o for o in outcomes if isinstance(o, Exception)]
    assert len(starter.jobs) == 1, "two jobs were started"
    assert len(runners) == 1 and len(refused) == 1 and "already running" in str(refused[0])
    runner = runners[0]
    assert shared.job is runner and runner.running
    assert sum(e.source == "running" for e in shared.snapshot()) == 1
    other = tabs[1 - outcomes.index(runner)]
    runner.poll = 0.01
    other._on_stop(None)                               # the tab that was refused stops the job
    assert runner.finished.wait(5)
    assert starter.jobs[0].cancelled and runner.entry.source == "stopped"
    wait_for(lambda: shared.job is None)
    for s in tabs:
        s.close()


def test_a_failed_start_releases_the_job_slot(server, demo_file):
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file))
    s = Session(server, shared, sync=True)
    with pytest.raises(nnm.NNMInputError):
        s._start(5, 10.0, 1.0)                        # the 2-DOF model has no mode 5
    assert shared.job is None or not shared.job.running
    assert not [e for e in shared.snapshot() if e.source == "running"]
    s.close()


def test_listener_errors_are_logged(demo_file, caplog):
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file)
    seen = []

    def broken(kind):
        raise RuntimeError("tab gone")

    shared.subscribe(broken)
    shared.subscribe(seen.append)
    with caplog.at_level(logging.ERROR, logger="nnm_viewer"):
        shared.notify("branches")
    assert seen == ["branches"]                       # the other listeners still run
    assert any("tab gone" in (r.exc_text or "") + r.getMessage() for r in caplog.records)


def test_view_state_is_one_immutable_record(server, demo_file):
    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file))
    s = Session(server, shared, sync=True)
    e = shared.entries[1]
    before = s.view
    s.pick(e.uid, 3)
    after = s.view
    assert after is not before and (after.sel_uid, after.s) == (e.uid, 3.0)
    assert (before.sel_uid, before.s) == (shared.entries[0].uid, 0.0)     # the old record is unchanged
    with pytest.raises(Exception):
        after.s = 1.0
    s.close()


def test_downloads_contain_the_orbit_their_name_says_while_the_drawing_catches_up(server, demo_file):
    """A drawn tab (its own draw thread, as nnm-view): while the drawing has not yet drawn the point the view asks
    for (here: its lock held), the orbit CSV and the GIF are of the view's position and k3 factor, as their names
    say, not of the last orbit drawn."""
    import csv
    import io

    import numpy as np

    from nnm_viewer.info import point_data

    model = nnm.load_model(demo_file)
    shared = SharedState(model, path=demo_file, branches=nnm.load_branches(demo_file))
    s = Session(server, shared)                            # drawn in its own thread
    try:
        wait_for(lambda: s.view.current_point is not None, timeout=60)
        e = shared.entries[0]
        assert s.view.current_of == (e.uid, 0.0)

        def first_row(data):
            return np.array(list(csv.reader(io.StringIO(data.decode())))[1], dtype=float)

        with s.drawing._draw_lock:                         # the drawing busy: it has not drawn point 10 yet
            s.h_along.value = 10.0
            assert s.view.current_of == (e.uid, 0.0)          # point 1 still shown
            name, data = s.orbit_csv()
            assert name.endswith("_point10_orbit.csv") and "k3x" not in name
            row = first_row(data)
            pd = point_data(e.branch, 9.0, reference=not shared.orbits_ready.is_set())
            np.testing.assert_allclose(row[1:], pd.x[0], rtol=1e-9, atol=1e-15)
            assert not np.allclose(row[1:], e.branch.x0[0], rtol=1e-3)
            s.h_k3.value = 1.0                             # every k3 x 10: displacements / sqrt(10)
            name2, data2 = s.orbit_csv()
            assert "k3x10" in name2 and name2.endswith("_point10_orbit.csv")
            np.testing.assert_allclose(first_row(data2)[1:], pd.x[0] / np.sqrt(10), rtol=1e-9, atol=1e-15)
            gif_name, gif = s.animation_gif()
            assert "k3x10" in gif_name and gif_name.endswith("_point10.gif") and gif[:6] == b"GIF89a"
            assert s.view.current_of == (e.uid, 0.0)          # the downloads did not change what is shown
        wait_for(lambda: s.view.current_of == (e.uid, 9.0) and s.view.ratio == pytest.approx(10.0), timeout=60)
        name3, data3 = s.orbit_csv()                       # drawn now: the orbit shown, the same file
        assert name3 == name2 and data3 == data2
    finally:
        s.close()
