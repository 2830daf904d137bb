"""Writes through symbolic links and concurrent appends from several processes (h5file.atomic_file, file_lock)."""
import dataclasses
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver import NNMFileError
from nnm_solver.files import h5file


def small_model():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])


@pytest.fixture(scope="module")
def tiny_branch():
    return nnm.continue_nnm(small_model(), 1, 0.1, max_points=3)


def _file_with_two_branches(path, branch):
    nnm.save_branch(path, branch)
    nnm.save_branch(path, branch)
    assert len(nnm.load_branches(path)) == 2


def _leftovers(folder, keep):
    return sorted(f for f in os.listdir(folder) if f not in keep)


@pytest.mark.skipif(not hasattr(os, "symlink") or sys.platform == "win32", reason="needs symbolic links")
def test_save_through_a_link_updates_the_linked_file_and_keeps_the_link(tmp_path, tiny_branch):
    (tmp_path / "data").mkdir()
    (tmp_path / "sl").mkdir()
    real, link = tmp_path / "data" / "real.h5", tmp_path / "sl" / "link.h5"
    _file_with_two_branches(real, tiny_branch)
    os.symlink(os.path.join("..", "data", "real.h5"), link)

    nnm.save_branch(link, tiny_branch)

    assert link.is_symlink() and os.path.realpath(link) == os.path.realpath(real)
    assert len(nnm.load_branches(real)) == 3
    assert len(nnm.load_branches(link)) == 3
    assert _leftovers(tmp_path / "sl", {"link.h5"}) == []           # no temporary or lock file beside the link
    assert _leftovers(tmp_path / "data", {"real.h5"}) == []         # none left beside the real file either

    nnm.save_model(link, small_model())                            # a whole-file write through the link too
    assert link.is_symlink()
    assert nnm.load_branches(real) == [] and nnm.load_model(real).n == 2


@pytest.mark.skipif(not hasattr(os, "symlink") or sys.platform == "win32", reason="needs symbolic links")
def test_dangling_link_creates_the_file_it_points_to(tmp_path, tiny_branch):
    (tmp_path / "data").mkdir()
    link = tmp_path / "link.h5"
    os.symlink(tmp_path / "data" / "new.h5", link)
    nnm.save_branch(link, tiny_branch)
    assert link.is_symlink() and len(nnm.load_branches(tmp_path / "data" / "new.h5")) == 1


_WRITER = textwrap.dedent("""
    import os, sys, time
    import numpy as np
    import nnm_solver as nnm
    path, go, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    m = nnm.Model(np.eye(2), np.array([[2., -1.], [-1., 2.]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    b = nnm.continue_nnm(m, 1, 0.1, max_points=3)
    open(path + "." + str(os.getpid()) + ".ready", "w").close()
    while not os.path.exists(go):
        time.sleep(0.005)
    for i in range(n):
        nnm.save_branch(path, b, name=f"p{os.getpid()}_{i}")
""")


def test_two_processes_appending_to_one_file_keep_all_branches(tmp_path, tiny_branch):
    path = tmp_path / "shared.h5"
    _file_with_two_branches(path, tiny_branch)
    go, n = tmp_path / "go", 20
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(Path(nnm.__file__).resolve().parents[1])] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    procs = [subprocess.Popen([sys.executable, "-c", _WRITER, str(path), str(go), str(n)], env=env,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    deadline = time.monotonic() + 60
    while len(list(tmp_path.glob("shared.h5.*.ready"))) < 2 and time.monotonic() < deadline \
            and all(p.poll() is None for p in procs):
        time.sleep(0.01)
    go.touch()                                                      # both start appending at the same moment
    errors = [p.communicate(timeout=120)[1] for p in procs]
    assert [p.returncode for p in procs] == [0, 0], errors

    names = [b.name for b in nnm.load_branches(path)]
    assert len(names) == 2 + 2 * n
    for p in procs:
        assert sum(name.startswith(f"p{p.pid}_") for name in names) == n
    for f in tmp_path.glob("shared.h5.*.ready"):
        f.unlink()
    assert _leftovers(tmp_path, {"shared.h5", "go"}) == []          # no lock or temporary file left


def test_a_held_lock_is_waited_for_a_bounded_time_with_one_line_naming_the_file(tmp_path, tiny_branch, monkeypatch):
    path = tmp_path / "held.h5"
    _file_with_two_branches(path, tiny_branch)
    before = path.read_bytes()
    monkeypatch.setattr(h5file, "FILES", dataclasses.replace(h5file.FILES, lock_timeout=0.2))
    with h5file.file_lock(path):                   # another open of the lock file blocks like another process
        t0 = time.monotonic()
        with pytest.raises(NNMFileError) as info:
            nnm.save_branch(path, tiny_branch)
        assert time.monotonic() - t0 < 5
    message = str(info.value)
    assert "\n" not in message and str(path) in message and "held.h5.lock" in message
    assert path.read_bytes() == before
    nnm.save_branch(path, tiny_branch)             # released: the next save goes through
    assert len(nnm.load_branches(path)) == 3
    assert _leftovers(tmp_path, {"held.h5"}) == []


def test_a_leftover_lock_file_does_not_block(tmp_path, tiny_branch):
    path = tmp_path / "left.h5"
    _file_with_two_branches(path, tiny_branch)
    (tmp_path / "left.h5.lock").touch()            # e.g. from a writer that was killed (its lock died with it)
    nnm.save_branch(path, tiny_branch)
    assert len(nnm.load_branches(path)) == 3
