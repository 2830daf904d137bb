"""nnm.sweep on a local Dask cluster (2 worker processes, 1 thread each): the atlas equals the serial
branches point for point, a killed worker's branch is retried or reported, a cancelled sweep keeps its
finished branches and a rerun skips them, bad scheduler addresses and bad input give one-line errors;
model variants and the TOML sweep file."""
import dataclasses
import importlib
import os
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

import nnm_solver as nnm
from conftest import two_dof_model

sweeps = importlib.import_module("nnm_solver.sweeps.dask_sweep")

SHORT = dict(steps_per_period=64, max_points=40)            # ~0.1-0.5 s per branch
LONG = dict(energy_max=1e4, steps_per_period=200, max_points=200)   # 2-DOF NNM1 through the 3:1 tongue (~1 s)


def chain(n=5):
    """n unit masses in a fixed-fixed chain of unit springs, a grounded and a relative cubic spring."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.eye(n), K, [nnm.CubicSpring(dof=0, k3=0.5), nnm.CubicSpring(dof=3, other=4, k3=0.2)],
                     name="chain")


def assert_same(a, b):
    assert (len(a), a.status, a.message, a.mode) == (len(b), b.status, b.message, b.mode)
    for key in ("energy", "frequency_hz", "period", "x0", "v0", "stable"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)
    np.testing.assert_array_equal(a.floquet, b.floquet)
    assert a.events == b.events


def file_names(path):
    return [b.name for b in nnm.load_branches(path)]


# ---------------------------------------------------------------------- variants, sweep file (no Dask)
def test_variants_change_the_model():
    m = chain()
    v = nnm.Variant(spring_factor=2.0, added_stiffness=[(1, 0.3), (2, 4, 0.5)], mass_factor=4.0, mass_dofs=[2])
    assert v.name == "springs2_k[0.3@1,0.5@2-4]_mass4@2"
    mv = v.apply(m)
    np.testing.assert_allclose(mv.k3, 2 * m.k3)
    dK = mv.K - m.K
    assert mv.K[1, 1] == 2.3 and mv.K[2, 2] == mv.K[4, 4] == 2.5 and dK[2, 4] == dK[4, 2] == -0.5
    assert np.count_nonzero(dK) == 5
    assert mv.M[2, 2] == 4.0 and np.trace(mv.M) == 8.0
    assert nnm.Variant().apply(m) is m and nnm.Variant().name == "base"
    per_spring = nnm.Variant(spring_factor=[1.0, 0.0]).apply(m)
    assert list(per_spring.k3) == [0.5, 0.0]
    grid = nnm.variant_grid(spring_factor=[0.5, 1.0], stiffness=[0.0, 1e3], stiffness_dofs=[0, 4])
    assert [g.name for g in grid] == ["springs0.5", "springs0.5_k1000@0,4", "base", "k1000@0,4"]
    assert grid[3].apply(m).K[4, 4] == 1002.0
    with pytest.raises(nnm.NNMInputError, match="3 values but the model has 2 springs"):
        nnm.Variant(spring_factor=[1, 2, 3]).apply(m)
    with pytest.raises(nnm.NNMInputError, match="DOF 7 is not a DOF"):
        nnm.Variant(added_stiffness=[(7, 1.0)]).apply(m)
    with pytest.raises(nnm.NNMInputError, match="may not contain"):
        nnm.Variant(name="a:b")
    with pytest.raises(nnm.NNMInputError, match="mass_factor must be positive"):
        nnm.Variant(mass_factor=0)


def test_sweep_file(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('modes = "2-4,7"\nenergy_max = 3.5\n[options]\nmax_points = 12\n'
                 '[grid]\nspring_factor = [1.0, 2.0]\n'
                 '[[variant]]\nname = "stiff"\nadded_stiffness = [[1, 2.5]]\nmass_factor = 1.2\nmass_dofs = [0]\n')
    spec = nnm.load_sweep_file(p)
    assert spec.modes == [2, 3, 4, 7] and spec.energy_max == 3.5 and spec.options == {"max_points": 12}
    assert [v.name for v in spec.variants] == ["base", "springs2", "stiff"]
    assert spec.variants[2].added_stiffness == ((1, 2.5),) and spec.variants[2].mass_dofs == (0,)
    p.write_text("[grid]\nspring_factr = [1.0]\n")
    with pytest.raises(nnm.NNMInputError, match="grid"):
        nnm.load_sweep_file(p)
    p.write_text("modes = [1, 1]\n")
    with pytest.raises(nnm.NNMInputError, match="repeats"):
        nnm.load_sweep_file(p)
    p.write_text("modes = \n")
    with pytest.raises(nnm.NNMInputError, match="not valid TOML"):
        nnm.load_sweep_file(p)


def test_bad_input_fails_before_any_cluster(tmp_path):
    m = chain()
    for kwargs, match in [(dict(modes="1-9"), "mode 6 is out of range"), (dict(modes="3-1"), "empty"),
                          (dict(modes=[1], steps_per_period=4), "steps_per_period"),
                          (dict(modes=[1], harmonics=3), "unknown option 'harmonics'"),
                          (dict(modes=[1], on_point=print), "on_point"),
                          (dict(modes=[1], client=object()), "client must be")]:
        with pytest.raises(nnm.NNMInputError, match=match):
            nnm.sweep(m, energy_max=1.0, **kwargs)
    with pytest.raises(nnm.NNMInputError, match="unique"):
        nnm.sweep(m, [1], 1.0, variants=[nnm.Variant(name="a"), nnm.Variant(name="a", mass_factor=2)])
    other = tmp_path / "other.h5"
    nnm.save_model(other, two_dof_model())
    with pytest.raises(nnm.NNMInputError, match="holds another model"):
        nnm.sweep(m, [1], 1.0, out=other, client=object())


def test_bad_scheduler_address(monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(sweeps, "SWEEPS", dataclasses.replace(sweeps.SWEEPS, connect_timeout=1.0))
    for address in ("tcp://127.0.0.1:1", "nonsense://nowhere:x"):
        with pytest.raises(nnm.NNMInputError, match="cannot reach the Dask scheduler"):
            nnm.sweep(chain(), [1], 1.0, client=address, **SHORT)


# ---------------------------------------------------------------------- on a LocalCluster
@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       env=dict(sweeps.WORKER_ENV))
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_atlas_equals_serial_point_for_point(client, tmp_path):
    m = chain()
    variants = nnm.variant_grid(spring_factor=[1.0, 2.0]) + [
        nnm.Variant(name="stiff-heavy", added_stiffness=[(2, 0.5)], mass_factor=1.5, mass_dofs=[4])]
    out = tmp_path / "atlas.h5"
    got = nnm.sweep(m, "1-3", 2.0, variants=variants, client=client, out=out, **SHORT)
    want = [nnm.continue_nnm(v.apply(m), mode, 2.0, **SHORT) for v in variants for mode in (1, 2, 3)]
    names = [f"{v.name}:mode{mode}" for v in variants for mode in (1, 2, 3)]
    assert [b.name for b in got] == names
    for a, b in zip(want, got):
        assert_same(a, b)
        assert b.sweep_info["source"] == "computed" and b.sweep_info["worker"].startswith("tcp://")
    assert got[-1].model.M[4, 4] == 1.5 and got[-1].model.K[2, 2] == 2.5
    # the file holds every branch once, under its name; load_sweep gives each its variant's model
    assert sorted(file_names(out)) == sorted(names)
    loaded = {b.name: b for b in nnm.load_sweep(out)}
    plain = {b.name: b for b in nnm.load_branches(out)}        # so does load_branches (the viewer's loader)
    for a, name in zip(want, names):
        np.testing.assert_array_equal(plain[name].model.M, a.model.M)
        np.testing.assert_array_equal(loaded[name].x0, a.x0)
        np.testing.assert_array_equal(loaded[name].model.M, a.model.M)
        np.testing.assert_array_equal(loaded[name].model.K, a.model.K)
    assert nnm.load_model(out).n == 5 and list(nnm.load_model(out).k3) == [0.5, 0.2]
    ax = nnm.plot_atlas(list(loaded.values()), path=tmp_path / "atlas.png")
    assert (tmp_path / "atlas.png").stat().st_size > 10_000
    lines = [ln for ln in ax.get_lines() if ln.get_label().endswith("NNM 1")]
    assert abs(lines[0].get_ydata()[0]) < 1e-3                   # relative change starts at 0 %
    # a rerun finds everything in the file: nothing to compute, so no scheduler is even contacted
    again = nnm.sweep(m, "1-3", 2.0, variants=variants, client="tcp://127.0.0.1:1", out=out, **SHORT)
    assert [b.sweep_info["source"] for b in again] == ["file"] * 9
    for a, b in zip(want, again):
        np.testing.assert_array_equal(a.energy, b.energy)
    assert again[-1].model is got[-1].model or np.array_equal(again[-1].model.M, got[-1].model.M)
    with pytest.raises(nnm.NNMInputError, match="energy_max"):
        nnm.sweep(m, "1-3", 5.0, variants=variants, client=client, out=out, **SHORT)


def test_cancel_keeps_finished_branches_and_rerun_skips_them(client, tmp_path):
    m = chain()
    variants = nnm.variant_grid(spring_factor=[1.0, 2.0])
    opts = dict(steps_per_period=128, max_points=80)
    out = tmp_path / "cancel.h5"
    stop = threading.Event()
    seen = []

    def progress(state):
        seen.append((state.finished, state.all_points))
        if state.finished >= 1:
            stop.set()

    first = nnm.sweep(m, "1-5", 2.0, variants=variants, client=client, out=out, progress=progress, stop=stop, **opts)
    done = [b.name for b in first if b.status != "cancelled"]
    cancelled = [b.name for b in first if b.status == "cancelled"]
    assert done and len(cancelled) >= 5, [b.status for b in first]
    assert all(len(b) == 0 and "run it again" in b.message for b in first if b.status == "cancelled")
    assert sorted(file_names(out)) == sorted(done)
    assert max(p for _, p in seen) > 0
    second = nnm.sweep(m, "1-5", 2.0, variants=variants, client=client, out=out, **opts)
    assert {b.name for b in second if b.sweep_info["source"] == "file"} == set(done)
    assert {b.name for b in second if b.sweep_info["source"] == "computed"} == set(cancelled)
    assert all(b.status in ("done", "max_points") for b in second)
    assert sorted(file_names(out)) == sorted(b.name for b in second)    # each branch exactly once


def _killer(target):
    """progress callable killing (SIGKILL) the worker process computing ``target`` once it has a point."""
    killed = []

    def progress(state):
        if not killed and state.running.get(target, 0) >= 1:
            pid = state.workers[target]["pid"]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
    progress.killed = killed
    return progress


def test_killed_worker_branch_is_retried(client, tmp_path):
    m = two_dof_model()
    out = tmp_path / "killed.h5"
    progress = _killer("base:mode1")
    got = nnm.sweep(m, [1, 2], client=client, out=out, progress=progress, **LONG)
    assert progress.killed, "the branch finished before the worker could be killed"
    assert got[0].sweep_info["pid"] != progress.killed[0]       # computed again by another process
    assert_same(nnm.continue_nnm(m, 1, **LONG), got[0])
    assert sorted(file_names(out)) == ["base:mode1", "base:mode2"]


def test_killed_worker_branch_is_reported_then_rerun(client, tmp_path):
    def allow(dask_scheduler, n):
        old, dask_scheduler.allowed_failures = dask_scheduler.allowed_failures, n
        return old

    old = client.run_on_scheduler(allow, n=0)     # no retry: the branch is reported lost
    try:
        m = two_dof_model()
        out = tmp_path / "reported.h5"
        progress = _killer("base:mode1")
        got = nnm.sweep(m, [1, 2], client=client, out=out, progress=progress, **LONG)
    finally:
        client.run_on_scheduler(allow, n=old)
    assert progress.killed
    assert got[0].status == "failed" and len(got[0]) == 0 and got[0].sweep_info["source"] == "lost"
    assert "worker computing this branch died" in got[0].message and "run the sweep again" in got[0].message
    assert got[1].status in ("done", "max_points") and len(got[1])
    assert file_names(out) == ["base:mode2"]              # nothing saved for the lost branch
    again = nnm.sweep(m, [1, 2], client=client, out=out, **LONG)
    assert [b.sweep_info["source"] for b in again] == ["computed", "file"]
    assert_same(nnm.continue_nnm(m, 1, **LONG), again[0])


# ---------------------------------------------------------------------- command line
def run(*args, timeout=240):
    return subprocess.run([sys.executable, "-m", "nnm_solver.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


def test_cli_sweep(tmp_path):
    pytest.importorskip("distributed")
    p = tmp_path / "m.h5"
    nnm.save_model(p, chain())
    toml = tmp_path / "s.toml"
    toml.write_text('energy_max = 1.0\n[options]\nsteps_per_period = 64\n[grid]\nspring_factor = [1.0, 2.0]\n')
    out, png = tmp_path / "out.h5", tmp_path / "atlas.png"
    r = run(p, "--modes", "1-2", "--sweep", toml, "--max-points", 30, "--workers", 2, "--out", out, "--plot", png)
    assert r.returncode == 0, r.stderr
    assert "4 computed, 0 already in" in r.stdout and "atlas written" in r.stdout
    assert sorted(file_names(out)) == ["base:mode1", "base:mode2", "springs2:mode1", "springs2:mode2"]
    assert all(b.settings["steps_per_period"] == 64 for b in nnm.load_branches(out))
    assert png.stat().st_size > 10_000
    r = run(p, "--modes", "1-2", "--sweep", toml, "--max-points", 30, "--out", out)
    assert r.returncode == 0, r.stderr
    assert "0 computed, 4 already in" in r.stdout
    r = run(p, "--modes", "1-2", "--mode", 1, "--energy-max", 1)
    assert r.returncode == 2 and "not both" in r.stderr
    r = run(p, "--modes", "1-9", "--energy-max", 1)
    assert r.returncode == 2 and "out of range" in r.stderr and "Traceback" not in r.stderr


def test_branch_is_recomputed_when_the_cluster_loses_its_scattered_model(client):
    """The model goes to every worker (scattered, broadcast), but the scheduler's memory manager drops the copies on
    workers that no running branch needs, keeping one (it runs every 2 s; forced here at every progress call: with
    one branch, the copy kept is its worker's), and a worker dying with that copy takes the model with it: its
    branch was then cancelled on its retry (lost dependencies) and reported lost (a sweep in a full test session lost
    both its branches that way, 2026-12-06).  The sweep now submits such a branch again with the model scattered
    anew: it comes back computed, the serial branch point for point."""
    m = two_dof_model()
    killed = []

    def progress(state):
        if killed:
            return
        client.amm.run_once()
        holders = [list(w) for key, w in client.who_has().items() if str(key).startswith("Model-")]
        if state.running.get("base:mode1", 0) >= 1 and len(holders) == 1 and len(holders[0]) == 1:
            pid = client.run(os.getpid, workers=holders[0])[holders[0][0]]        # the worker computing it
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    got = nnm.sweep(m, [1], client=client, progress=progress, **LONG)
    assert killed, "the model's replicas were not reduced to one while the branch ran"
    assert got[0].sweep_info["source"] == "computed", got[0].message
    assert got[0].sweep_info["pid"] != killed[0]
    assert_same(nnm.continue_nnm(m, 1, **LONG), got[0])


def test_cli_sweep_takes_the_branch_flags(monkeypatch, tmp_path, capsys):
    """--modes / --sweep compute every branch with the branch flags a single --mode N takes (method, integrator,
    steps, harmonics, condensed, freq_tol, tongues, tol, max_points, energy_min: they were dropped, so a sweep with
    --tongues skip --method hb ran shooting with the default tongues), the flags over the sweep file's options, and
    refuse in one line the flags a sweep does not use."""
    from nnm_solver.cli import solve

    seen = []

    def fake_sweep(model, modes, energy_max, variants=None, client=None, out=None, progress=None, **options):
        seen.append(options)
        return []

    monkeypatch.setattr(sweeps, "sweep", fake_sweep)
    p = tmp_path / "m.h5"
    nnm.save_model(p, chain())
    base = [str(p), "--modes", "1-2", "--energy-max", "1", "--out", str(tmp_path / "o.h5")]
    assert solve.main(base + ["--tongues", "skip", "--method", "hb", "--harmonics", "5", "--condensed",
                              "--freq-tol", "1e-5", "--tol", "1e-7", "--max-points", "30"]) == 0
    assert seen[-1] == dict(method="hb", harmonics=5, condensed=True, freq_tol=1e-5, tongues="skip", tol=1e-7,
                            max_points=30)
    assert solve.main(base + ["--integrator", "newmark", "--steps-per-period", "64", "--energy-min", "0.01"]) == 0
    assert seen[-1] == dict(integrator="newmark", steps_per_period=64, energy_min=0.01)
    assert solve.main(base) == 0 and seen[-1] == {}
    toml = tmp_path / "s.toml"
    toml.write_text('[options]\nmethod = "hb"\nharmonics = 7\ncondensed = true\ntongues = "follow"\n')
    assert solve.main(base + ["--sweep", str(toml), "--harmonics", "9", "--tongues", "skip"]) == 0
    assert seen[-1] == dict(method="hb", harmonics=9, condensed=True, tongues="skip")
    hb_only = tmp_path / "hb.toml"
    hb_only.write_text('[options]\nmethod = "hb"\n')
    assert solve.main(base + ["--sweep", str(hb_only), "--method", "shooting", "--floquet"]) == 0
    assert seen[-1] == dict(method="shooting", floquet=True)         # an explicit --method over the file's
    capsys.readouterr()
    assert solve.main(base + ["--sweep", str(toml), "--steps-per-period", "64"]) == 2
    assert "belong(s) to --method shooting" in capsys.readouterr().err
    assert solve.main(base + ["--csv", str(tmp_path / "t.csv"), "--tongue", "1"]) == 2
    err = capsys.readouterr().err
    assert "--tongue, --csv: not used by a sweep" in err and len(err.strip().splitlines()) == 1
    assert solve.main(base + ["--damping", "0.02"]) == 2
    assert "--damping: goes with --forced" in capsys.readouterr().err
    assert len(seen) == 5


def test_cli_sweep_branch_equals_continue_nnm_with_the_same_flags(tmp_path):
    pytest.importorskip("distributed")
    p, out = tmp_path / "m.h5", tmp_path / "out.h5"
    nnm.save_model(p, chain())
    r = run(p, "--modes", "1", "--energy-max", 1.0, "--method", "hb", "--harmonics", 5, "--tongues", "skip",
            "--max-points", 30, "--workers", 1, "--out", out)
    assert r.returncode == 0, r.stderr
    (b,) = nnm.load_branches(out)
    ref = nnm.continue_nnm(chain(), 1, 1.0, method="hb", harmonics=5, tongues="skip", max_points=30)
    for key in ("method", "harmonics", "condensed", "tol"):
        assert b.settings[key] == ref.settings[key], key
    assert b.settings["method"] == "harmonic_balance"            # (shooting before: --method was dropped)
    np.testing.assert_array_equal(b.energy, ref.energy)
    np.testing.assert_array_equal(b.frequency_hz, ref.frequency_hz)


def test_a_saved_branch_computed_otherwise_is_refused(tmp_path):
    """A rerun keeps a saved branch only if it is what the sweep asks for: another method, a method field
    recorded otherwise, or a branch that stopped at fewer points than max_points now allows give one line
    (they were returned as they were: 'raise max_points to go on' did nothing); harmonic balance's harmonics
    raised by its accuracy target are not a difference."""
    from nnm_solver.driver.api import from_keywords
    from nnm_solver.sweeps.sweep_files import prepare_file, stale_reason

    def request(method=None, **kw):
        return from_keywords(method, None, None, kw)[:2]

    m = chain()
    b = nnm.continue_nnm(m, 1, 1.0, steps_per_period=64, max_points=5)
    assert b.status == "max_points"
    assert stale_reason(b, *request(steps_per_period=64, max_points=5)) == ""
    assert "max_points = 5" in stale_reason(b, *request(steps_per_period=64, max_points=10))
    assert "this sweep: harmonic_balance" in stale_reason(b, *request("hb", max_points=5))
    assert "integrator" in stale_reason(b, *request(integrator="newmark", max_points=5))
    assert "tol" in stale_reason(b, *request(steps_per_period=64, tol=1e-8, max_points=5))
    h = nnm.continue_nnm(m, 1, 1.0, method="hb", harmonics=3)
    assert stale_reason(h, *request("hb", harmonics=3)) == ""
    assert stale_reason(h, *request("hb", harmonics=5)) == ""       # (the target decides the harmonics)
    assert "harmonics" in stale_reason(h, *request("hb", harmonics=5, freq_tol=None))
    out = tmp_path / "s.h5"
    variants = sweeps.as_variants(None)
    prepare_file(out, m, variants, 1.0, {"base:mode1"})
    nnm.save_branch(out, b, name="base:mode1")
    found = prepare_file(out, m, variants, 1.0, {"base:mode1"}, request(steps_per_period=64, max_points=5))
    assert list(found) == ["base:mode1"]
    with pytest.raises(nnm.NNMInputError, match="already holds branch base:mode1 computed to max_points = 5"):
        prepare_file(out, m, variants, 1.0, {"base:mode1"}, request(steps_per_period=64, max_points=50))
