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
