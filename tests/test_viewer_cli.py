"""`nnm-view` command line: one-line errors with a non-zero exit, and a served page."""
import socket
import subprocess
import sys
import time
import urllib.request

import pytest

from nnm_viewer.demo import write_demo_file


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
    assert_one_line_error(run_cli(tmp_path / "nope.h5"), "no such file")


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
        assert f"http://localhost:{port}" in line and "1 branch" in line
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
