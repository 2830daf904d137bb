"""Every screenshot of the viewer in the documentation (docs/img), with what it shows and how its file is made,
and the one command that regenerates them all (from the source tree, with Debian's Chromium):

    python -m nnm_viewer.screenshot --all              # into docs/img (maintainers)
    python -m nnm_viewer.screenshot --all /tmp/shots   # elsewhere, to look at them first

``viewer.png`` (README.md, docs/viewer.md) is ``assets/paris.h5`` as shipped, so it changes whenever that
file is rebuilt; ``byom_viewer.png`` (docs/byom.md) is the cantilever of docs/byom.md, rebuilt here by the
page's own commands (examples/bring_your_own_model.py, ``nnm-solve import``, ``nnm-solve --mode 1
--energy-max 0.05``) in a temporary folder.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class DocScreenshot:
    """One screenshot: its file name in docs/img, the pages showing it, the branch (1-based) and point
    (fraction 0..1 along it) picked, and how the nnm file is obtained (``source``: a path relative to
    the source tree, or "byom" for the cantilever built by docs/byom.md's commands)."""

    name: str
    pages: tuple
    source: str
    branch: int = 1
    point: float = 0.6


SCREENSHOTS = (
    DocScreenshot("viewer.png", ("README.md", "docs/viewer.md"), "assets/paris.h5", branch=6, point=0.9),
    DocScreenshot("byom_viewer.png", ("docs/byom.md",), "byom", branch=1, point=0.9),
)


def build_byom(folder):
    """docs/byom.md's cantilever with its NNM 1 branch, by the page's commands: the model files
    (examples/bring_your_own_model.py), ``nnm-solve import byom/beam_mtx.toml --out byom/beam_mtx.h5`` and
    ``nnm-solve byom/beam_mtx.h5 --mode 1 --energy-max 0.05``; returns the .h5 file."""
    script = ROOT / "examples" / "bring_your_own_model.py"
    if not script.is_file():
        raise SystemExit(f"{script} not found: run the documentation screenshots from the source tree")
    spec = importlib.util.spec_from_file_location("bring_your_own_model", script)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    folder = Path(folder)
    mod.write_all(folder)
    h5 = folder / "beam_mtx.h5"
    for args in (["import", str(folder / "beam_mtx.toml"), "--out", str(h5)],
                 [str(h5), "--mode", "1", "--energy-max", "0.05"]):
        subprocess.run([sys.executable, "-m", "nnm_solver.cli", *args], check=True, capture_output=True, text=True)
    return h5


def regenerate(take, out_dir=None, log=print):
    """Write every screenshot of SCREENSHOTS into ``out_dir`` (default: docs/img of the source tree) with
    ``take(file, out, point=, branch=)`` (screenshot.take, which passes itself; tests pass a recorder).
    Returns the files written."""
    out_dir = Path(out_dir) if out_dir is not None else ROOT / "docs" / "img"
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    with tempfile.TemporaryDirectory(prefix="nnm-doc-shots-") as tmp:
        for shot in SCREENSHOTS:
            path = build_byom(Path(tmp) / "byom") if shot.source == "byom" else ROOT / shot.source
            out = out_dir / shot.name
            text = take(str(path), str(out), point=shot.point, branch=shot.branch - 1)
            log(f"wrote {out} ({', '.join(shot.pages)}): {text}")
            written.append(out)
    return written
