"""Viewer latency benchmark: start -> first rendered frame, pick -> animation.

    python benchmarks/bench_viewer.py [FILE.h5] [--starts 3] [--picks 5]

FILE defaults to assets/paris.h5 (the 2-DOF demo, computed on the fly, if it is missing).
    python benchmarks/bench_viewer.py FILE --cold     # every start with an empty numba cache
    python benchmarks/bench_viewer.py FILE --cold --solve-starts 3   # and the first nnm-solve of the 2-DOF

Measured (medians):
  * in-process: pick -> GLB ready (orbit integrated by the solver, Fourier fit, morph-target
    GLB built and handed to viser), with its parts, and the GLB size;
  * in Debian's Chromium (headless, software WebGL, Playwright), with `nnm-view` as a
    subprocess, from the start of the command: server ready (URL printed), page populated,
    first frame showing the model (screenshots polled), model animated (the orbit's text shown and
    two screenshots of the model differing), solver ready ("preparing the solver" gone); Start in the
    Compute tab -> first streamed point (the job's "N of at most M points"); mouse click on an in-scene FEP
    point -> page updated with the new orbit (the GLB is sent before the text, on the same
    ordered websocket).
"""
from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import nnm_solver as nnm  # noqa: E402
from nnm_viewer.animation import MeshMapper, orbit_animation  # noqa: E402
from nnm_viewer.browser import (CHROMIUM, VIEWPORT, free_port, launch_chromium, screen_box,  # noqa: E402
                                selected_text, viewer_process, wait_selection_change)
from nnm_viewer.browser import board_view  # noqa: E402
from nnm_viewer.info import point_data  # noqa: E402
from nnm_viewer.scene import fallback_mesh, project_points as project, view_geometry  # noqa: E402
from nnm_viewer.state import BranchEntry  # noqa: E402


def in_process(model, branch, mesh, picks):
    """Median seconds of the pick -> GLB path, by part."""
    rows = {"point_data (solver orbit)": [], "Fourier fit + morph targets": [], "GLB build": [], "total": []}
    size = 0
    N = len(branch)
    mapper = MeshMapper(mesh)
    for k in range(picks):
        s = (k + 0.5) * (N - 1) / picks
        t0 = time.perf_counter()
        pd = point_data(branch, s)
        t1 = time.perf_counter()
        anim = orbit_animation(mesh.vertices, mesh.faces, mapper, pd.t, pd.x, pd.period)
        t2 = time.perf_counter()
        glb = anim.glb(1.0)
        t3 = time.perf_counter()
        size = len(glb)
        rows["point_data (solver orbit)"].append(t1 - t0)
        rows["Fourier fit + morph targets"].append(t2 - t1)
        rows["GLB build"].append(t3 - t2)
        rows["total"].append(t3 - t0)
    return {k: statistics.median(v) for k, v in rows.items()}, size


def blank_fraction(png_bytes, region):
    import io
    import matplotlib.image as mpimg
    img = mpimg.imread(io.BytesIO(png_bytes), format="png")[..., :3]
    x0, y0, x1, y1 = region
    sub = img[y0:y1, x0:x1]
    return float(np.mean(np.abs(sub - sub[0, 0]).sum(axis=2) > 30 / 255))


def in_browser(path, model, branches, mesh, starts, picks, cold=False):
    """Per start of ``nnm-view`` (seconds from the command): server ready (its URL printed), page
    populated (the selection text shown), model drawn (screenshots polled), solver ready ('preparing
    the solver' gone); then Start in the Compute tab -> first streamed point.  Picks on the first
    start.  cold: each start with an empty numba cache (a fresh install)."""
    from playwright.sync_api import sync_playwright, TimeoutError as PWTimeout

    geom = view_geometry(mesh.vertices)
    series = [BranchEntry(b, "").series(1.0) for b in branches]
    ranges, _ = board_view(series, 0)          # the board as a new tab shows it (zoomed on branch 1 if narrow)
    rows = {k: [] for k in ("server ready", "page populated", "model drawn", "model animated", "solver ready",
                            "Start -> first streamed point", "pick")}
    loads = []
    with sync_playwright() as pw:
        browser = launch_chromium(pw)
        try:
            for run in range(starts):
                port = free_port()
                page = browser.new_page(viewport=VIEWPORT)
                env, cache = None, None
                if cold:
                    cache = tempfile.mkdtemp(prefix="nnm-numba-")
                    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
                t0 = time.perf_counter()
                try:
                    with viewer_process(path, port, env=env):
                        rows["server ready"].append(time.perf_counter() - t0)
                        page.goto(f"http://127.0.0.1:{port}/")
                        page.wait_for_function("document.body.innerText.includes('Selected:')", timeout=120000)
                        rows["page populated"].append(time.perf_counter() - t0)
                        # the page notes (every 0.1 s, its own clock) when "preparing the solver" is gone
                        page.evaluate(WATCH_SOLVER_JS)
                        now_js, now = page.evaluate("performance.now()"), time.perf_counter()
                        x0, y0, x1, y1 = screen_box(mesh.vertices, geom, page.locator("canvas").first.bounding_box())
                        while blank_fraction(page.screenshot(), (x0, y0, x1 + 1, y1 + 1)) <= 0.05:
                            if time.perf_counter() - t0 > 120:
                                raise RuntimeError("the model never appeared")
                        rows["model drawn"].append(time.perf_counter() - t0)
                        page.wait_for_function("document.body.innerText.includes('real period')", timeout=300000,
                                               polling=100)
                        box = (x0, y0, x1 + 1, y1 + 1)
                        shot = model_pixels(page.screenshot(), box)
                        while True:                    # the animation runs: the model's pixels change
                            new = model_pixels(page.screenshot(), box)
                            if not np.array_equal(new, shot):
                                break
                            shot = new
                        rows["model animated"].append(time.perf_counter() - t0)
                        page.wait_for_function("window.__nnmSolverReady !== null", timeout=300000)
                        ready_js = page.evaluate("window.__nnmSolverReady")
                        rows["solver ready"].append(now - t0 + (ready_js - now_js) / 1000.0)
                        if run == 0:
                            rows["pick"] += pick_points(page, series[0], geom, ranges, picks, PWTimeout)
                        rows["Start -> first streamed point"].append(first_point(page))
                        loads.append(os.getloadavg()[0])
                        print(f"  start {run + 1}: " + ", ".join(f"{k} {v[-1]:.2f} s" for k, v in rows.items()
                                                                 if v and k != "pick")
                              + f" (load {loads[-1]:.2f})", flush=True)
                finally:
                    page.close()
                    if cache:
                        shutil.rmtree(cache, ignore_errors=True)
        finally:
            browser.close()
    return rows, loads


def model_pixels(png_bytes, region):
    import io
    import matplotlib.image as mpimg
    x0, y0, x1, y1 = region
    return mpimg.imread(io.BytesIO(png_bytes), format="png")[y0:y1, x0:x1, :3]


def cold_solve(starts):
    """Seconds (wall) of ``nnm-solve two_dof.h5 --mode 1 --energy-max 10`` (on a copy of the shipped file) with an
    empty numba cache, and the 1-minute load average at its end, per start."""
    import subprocess
    times, loads = [], []
    for run in range(starts):
        tmp = tempfile.mkdtemp(prefix="nnm-solve-cold-")
        try:
            shutil.copy(ROOT / "assets" / "two_dof.h5", Path(tmp) / "two_dof.h5")
            env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / "numba"),
                   "PYTHONPATH": os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "nnm_solver.cli", "two_dof.h5", "--mode", "1", "--energy-max", "10"],
                           cwd=tmp, env=env, check=True, stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
            loads.append(os.getloadavg()[0])
            print(f"  cold nnm-solve {run + 1}: {times[-1]:.2f} s (load {loads[-1]:.2f})", flush=True)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return times, loads


#: JavaScript: note in window.__nnmSolverReady the time (performance.now(), ms) at which the page
#: no longer says "Preparing the solver" (polled every 0.1 s)
WATCH_SOLVER_JS = """() => {
  window.__nnmSolverReady = null;
  const check = () => {
    if (!document.body.innerText.includes('Preparing the solver')) window.__nnmSolverReady = performance.now();
    else setTimeout(check, 100);
  };
  check();
}"""


def first_point(page):
    """Seconds from a click on Start (Compute tab, default mode and energies) to the first point."""
    page.get_by_role("tab", name="Compute").click()
    page.get_by_role("button", name="Start").click()
    t1 = time.perf_counter()
    page.wait_for_function("/\\b[1-9]\\d* (of at most \\d+ points|points in \\d)/.test(document.body.innerText)",
                           timeout=300000, polling=50)
    dt = time.perf_counter() - t1
    stop = page.get_by_role("button", name="Stop (keep points)")
    if stop.is_enabled():             # a short branch may have ended already
        try:
            stop.click(timeout=5000)
        except Exception:
            pass
    return dt


def pick_points(page, series, geom, ranges, picks, timeout_error):
    """Seconds from a mouse click on ``picks`` FEP points of ``series`` to the page showing a new selection."""
    page.wait_for_function("document.body.innerText.includes('Selected:')", timeout=60000)
    time.sleep(2.0)
    box = page.locator("canvas").first.bounding_box()   # after the panels docked
    N = len(series)
    times = []
    for k in range(picks):
        target = int(round((k + 1) * (N - 1) / (picks + 1)))
        p3 = geom.board.to_world(series.energy[[target]], series.frequency[[target]], ranges)
        (px, py), = project(p3, geom, box)
        before = selected_text(page)
        t1 = time.perf_counter()
        page.mouse.click(px, py)
        try:   # any new selection counts (neighbouring spheres may overlap)
            wait_selection_change(page, before, timeout_ms=30000)
            times.append(time.perf_counter() - t1)
        except timeout_error:
            print(f"  click on point {target} selected nothing", file=sys.stderr)
    return times


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file", nargs="?", default=str(ROOT / "assets" / "paris.h5"))
    ap.add_argument("--starts", type=int, default=3)
    ap.add_argument("--picks", type=int, default=5)
    ap.add_argument("--cold", action="store_true", help="every start with an empty numba cache (fresh install)")
    ap.add_argument("--solve-starts", type=int, default=0,
                    help="also time the first `nnm-solve two_dof.h5 --mode 1 --energy-max 10` with an empty numba "
                         "cache this many times")
    ap.add_argument("--no-in-process", action="store_true", help="skip the in-process pick timings")
    args = ap.parse_args()
    path = Path(args.file)
    tmp = None
    if not path.exists():
        from nnm_viewer.demo import write_demo_file
        tmp = tempfile.mkdtemp()
        path = Path(tmp) / "two.h5"
        print(f"{args.file} missing: using the 2-DOF demo")
        write_demo_file(path, energy_max=10.0)
    model = nnm.load_model(path)
    branches = nnm.load_branches(path)
    if not branches:
        sys.exit(f"{path} has no branch: compute one first (nnm-solve {path} --mode N --energy-max E)")
    mesh = model.mesh if model.mesh is not None else fallback_mesh(model.n)
    print(f"model {model.name or path.name}: {model.n} DOFs, mesh {len(mesh.vertices)} vertices / "
          f"{len(mesh.faces)} faces, branch 1: {len(branches[0])} points")
    med = (lambda v: statistics.median(v) if v else float("nan"))
    rows, size, loads = [], 0, []
    if args.solve_starts:
        times, solve_loads = cold_solve(args.solve_starts)
        rows.append(("first nnm-solve two_dof.h5 --mode 1 --energy-max 10 (cold numba cache)", med(times),
                     len(times)))
        loads += solve_loads
    if not args.no_in_process:
        parts, size = in_process(model, branches[0], mesh, args.picks)
        rows += [(f"pick -> GLB ready, in-process: {k}", v, args.picks) for k, v in parts.items()]
    if os.path.exists(CHROMIUM) and args.starts:
        cache = "cold numba cache" if args.cold else "warm cache"
        browser_rows, browser_loads = in_browser(path, model, branches, mesh, args.starts, args.picks, cold=args.cold)
        loads += browser_loads
        for name, v in browser_rows.items():
            what = "pick (click) -> page updated" if name == "pick" else \
                name if name.startswith("Start") else f"start -> {name}"
            rows.append((f"{what} (Chromium, {cache})", med(v), len(v)))
    else:
        print("no /usr/bin/chromium: browser timings skipped")
    if size:
        print(f"\nGLB size: {size / 1e6:.2f} MB")
    print(f"{'measure':68s} {'median (s)':>10s} {'n':>3s}")
    for name, v, n in rows:
        print(f"{name:68s} {v:10.3f} {n:3d}")
    if loads:
        print(f"1-minute load average during the runs: median {med(loads):.2f}, {min(loads):.2f}..{max(loads):.2f}")
    print(f"load average at the end: {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    if tmp:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
