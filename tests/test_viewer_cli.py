"""`nnm-view` command line: one-line errors with a non-zero exit, and a served page."""
import os
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from nnm_viewer.demo import write_demo_file

ROOT = Path(__file__).resolve().parents[1]


def run_cli(*args, timeout=60):
    return subprocess.run([sys.executable, "-m", "nnm_viewer", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def in_process(capsys, *args):
    """main() in this process (fast); returns an object like subprocess.run's."""
    from types import SimpleNamespace
    from nnm_viewer.app import main
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return SimpleNamespace(returncode=code, stdout=out.out, stderr=out.err)


def assert_one_line_error(res, *words):
    assert res.returncode != 0
    err = res.stderr.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert err.startswith("nnm-view: error:")
    for w in words:
        assert w in err


@pytest.fixture(scope="module")
def demo_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "two.h5"
    write_demo_file(path, energy_max=1.0, modes=(1,))
    return path


def test_missing_file(tmp_path):
    assert_one_line_error(run_cli(tmp_path / "nope.h5"), "no such file", "paris.h5", "two_dof.h5")


def test_shipped_examples_are_found_by_name_from_any_folder(tmp_path, monkeypatch):
    """Issue 14, item 2: `nnm-view paris.h5` / `two_dof.h5` from any folder, `nnm-view` alone opens
    the aircraft, a local file of the same name wins, the README's `assets/paris.h5` still works."""
    from nnm_viewer.app import find_file, parse_args
    from nnm_viewer.examples import data_dir

    monkeypatch.chdir(tmp_path)
    for name in ("paris.h5", "two_dof.h5", "two_dof", "assets/paris.h5"):
        path, shipped = find_file(name)
        assert shipped and path.parent == data_dir() and path.is_file(), name
    assert parse_args([]).file is None and find_file(None)[0].name == "paris.h5"
    (tmp_path / "two_dof.h5").write_bytes(b"mine")
    assert find_file("two_dof.h5") == (Path("two_dof.h5"), False)
    monkeypatch.chdir(ROOT)
    assert find_file("assets/paris.h5")[0] == Path("assets/paris.h5")


def _can_build_wheels():
    """True if this venv's setuptools has bdist_wheel (setuptools >= 70.1 or the wheel package)."""
    import importlib.util
    import setuptools
    major, minor = (int(x) for x in setuptools.__version__.split(".")[:2])
    return (major, minor) >= (70, 1) or importlib.util.find_spec("wheel") is not None


def test_wheel_ships_the_examples(tmp_path):
    """Issue 14, item 2: a plain (non-editable) install has the examples: build the wheel from a copy
    of the source tree, list it, install it in a folder of its own and find the examples from elsewhere."""
    import shutil
    import zipfile

    src = tmp_path / "src"
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("nnm_solver", "nnm_viewer", "nnm_fem", "assets"):
        shutil.copytree(ROOT / name, src / name, symlinks=True, ignore=ignore)
    wheels = tmp_path / "wheels"
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    # offline with this venv's setuptools when it can build wheels, else pip's isolated build (network)
    r = subprocess.run(pip + ["wheel", str(src), "-w", str(wheels), "--no-deps"]
                       + (["--no-build-isolation"] if _can_build_wheels() else []),
                       capture_output=True, text=True, timeout=300)
    if r.returncode and not _can_build_wheels() and "network" in r.stderr.lower():
        pytest.skip("no network for pip's isolated build, and this setuptools cannot build wheels")
    assert r.returncode == 0, r.stderr
    (wheel,) = wheels.glob("nnm-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert {"nnm_viewer/data/paris.h5", "nnm_viewer/data/two_dof.h5", "nnm_viewer/examples.py"} <= set(names)
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)                    # a pure wheel unpacks as installed
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    code = ("import nnm_viewer, nnm_solver as nnm\n"
            "from nnm_viewer.app import find_file\n"
            "print(nnm_viewer.__file__)\n"
            "for name in ('paris.h5', 'two_dof.h5', None):\n"
            "    p, shipped = find_file(name)\n"
            "    print(p, shipped, len(nnm.load_branches(p)))\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=elsewhere, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(site)})
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith(str(site))                      # the installed copy, not the source tree
    for line, name in zip(lines[1:], ("paris.h5", "two_dof.h5", "paris.h5")):
        path, shipped, n = line.split()
        assert path == str(site / "nnm_viewer" / "data" / name) and shipped == "True" and int(n) >= 1


def test_invalid_file(tmp_path, capsys):
    bad = tmp_path / "bad.h5"
    bad.write_text("not hdf5 at all")
    assert_one_line_error(in_process(capsys, bad), "bad.h5")


def test_busy_port(demo_file, capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        assert_one_line_error(in_process(capsys, demo_file, "--port", port), f"port {port}", "in use")


def test_serves_page_and_prints_url(demo_file):
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "nnm_viewer", str(demo_file), "--port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert f"Open http://127.0.0.1:{port} " in line and "1 branch" in line     # the address it listens on
        for _ in range(50):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=2) as r:
                    assert r.status == 200 and b"<html" in r.read(2000).lower()
                break
            except OSError:
                time.sleep(0.1)
        else:
            raise AssertionError("no page served")
        assert proc.poll() is None
    finally:
        proc.terminate()
        proc.wait(10)


def test_file_without_model_group(tmp_path, capsys):
    import h5py
    path = tmp_path / "empty.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "nnm"
        f.attrs["format_version"] = 1
    assert_one_line_error(in_process(capsys, path), "empty.h5")


def test_invalid_port(demo_file, capsys):
    assert_one_line_error(in_process(capsys, demo_file, "--port", 70000), "70000")
