"""Real-browser test: Debian's Chromium (headless, software WebGL) driven by Playwright opens
the page served by `nnm-view` on the shipped aircraft (assets/paris.h5), checks the aircraft is
drawn, moves the energy slider, picks a point of the in-scene FEP, and saves screenshots under
artifacts/.  Skipped only when /usr/bin/chromium is absent.  (Several tabs: tests/test_viewer_session.py.)"""
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_viewer.browser import CHROMIUM, FLAGS, VIEWPORT, board_view, free_port, selected_text
from nnm_viewer.scene import fallback_mesh, project_points, view_geometry
from nnm_viewer.state import BranchEntry

ROOT = Path(__file__).resolve().parents[1]
ASSET = Path(os.environ.get("NNM_BROWSER_TEST_FILE", ROOT / "assets" / "paris.h5"))  # override: another model
ARTIFACTS = ROOT / "artifacts"

pytestmark = pytest.mark.browser


def viewer_file(tmp_path):
    """The shipped aircraft with at least one branch (a short one is computed on a copy if the file
    has none); the 2-DOF demo if the asset is missing."""
    if not ASSET.exists():
        from nnm_viewer.demo import write_demo_file
        path = tmp_path / "two.h5"
        write_demo_file(path, energy_max=10.0, max_points=30)
        return path, "demo"
    if nnm.load_branches(ASSET):
        return ASSET, ASSET.stem
    path = tmp_path / "paris.h5"
    shutil.copyfile(ASSET, path)
    model = nnm.load_model(path)
    # a short, cheap branch (coarse time step, no Floquet analysis): the test is about the page
    branch = nnm.continue_nnm(model, mode=min(10, model.n), energy_max=1e2, max_points=8, steps_per_period=64,
                              floquet=False)
    nnm.save_branch(path, branch)
    return path, ASSET.stem


def well_separated_point(series, geom, ranges, box, exclude, shown=None):
    """(branch index, point index) of the FEP point farthest on screen from every other point
    (dense branches put spheres on top of each other), other than ``exclude``, among the branches
    ``shown`` on the board (default: all)."""
    pts, ids = [], []
    for bi, ser in enumerate(series):
        if len(ser) and (shown is None or bi in shown):
            pts.append(project_points(geom.board.to_world(ser.energy, ser.frequency, ranges), geom, box))
            ids += [(bi, i) for i in range(len(ser))]
    xy = np.concatenate(pts)
    d = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    np.fill_diagonal(d, np.inf)
    gap = d.min(axis=1)
    gap[[k for k, bi_i in enumerate(ids) if bi_i == tuple(exclude)]] = -1
    return ids[int(np.argmax(gap))]


def _phase(t0, name):
    print(f"  [{time.time() - t0:5.1f} s] {name}", flush=True)


def test_viewer_in_chromium(tmp_path):
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian chromium is not installed (/usr/bin/chromium); apt-get install chromium")
    sync_api = pytest.importorskip("playwright.sync_api")
    t_start = time.time()
    path, kind = viewer_file(tmp_path)
    model = nnm.load_model(path)
    branches = nnm.load_branches(path)
    mesh = model.mesh if model.mesh is not None else fallback_mesh(model.n)
    branches[0].motion(0, samples=16)          # compile (and cache) the solver's kernels outside the timed page
    geom = view_geometry(mesh.vertices)
    port = free_port()
    exe = shutil.which("nnm-view")
    cmd = [exe] if exe else [sys.executable, "-m", "nnm_viewer"]
    server = subprocess.Popen(cmd + [str(path), "--port", str(port)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    ARTIFACTS.mkdir(exist_ok=True)
    try:
        _phase(t_start, "model loaded")
        line = server.stdout.readline()
        _phase(t_start, "server started")
        assert f":{port}" in line, line + server.stderr.read()
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS,
                                         headless=True)
            try:
                page = browser.new_page(viewport=VIEWPORT)
                page.goto(f"http://127.0.0.1:{port}/")
                page.wait_for_function("document.body.innerText.includes('Selected:')", timeout=90000)
                page.wait_for_function("document.querySelectorAll('canvas').length > 0", timeout=10000)
                _phase(t_start, "page populated")
                box = page.locator("canvas").first.bounding_box()

                # 1) the aircraft is drawn: its projected bounding box is not blank (polled: software
                #    WebGL needs a few seconds to load and draw the GLB)
                sub = mesh.vertices[:: max(1, len(mesh.vertices) // 2000)]
                xy = project_points(sub, geom, box)
                x0, y0 = np.clip(xy.min(axis=0), 0, [VIEWPORT["width"] - 1, VIEWPORT["height"] - 1]).astype(int)
                x1, y1 = np.clip(xy.max(axis=0), 0, [VIEWPORT["width"] - 1, VIEWPORT["height"] - 1]).astype(int)
                shot = ARTIFACTS / f"browser_{kind}_start.png"
                deadline = time.time() + 45
                while True:
                    page.screenshot(path=str(shot))
                    region = _read_png(shot)[y0:y1 + 1, x0:x1 + 1].astype(float)
                    assert region.size, "the model projects outside the view"
                    non_bg = np.mean(np.abs(region - region[0, 0]).sum(axis=2) > 30)
                    if non_bg > 0.05 or time.time() > deadline:
                        break
                    time.sleep(0.5)
                assert non_bg > 0.05, f"the model's screen area is blank ({non_bg:.1%} drawn)"
                assert len(np.unique(region.reshape(-1, 3) // 8, axis=0)) > 20  # shaded, not one flat colour
                _phase(t_start, "model drawn")
                # 2) the energy slider moves the selection
                before = selected_text(page)
                assert "point 1 of" in before, before
                slider = page.get_by_role("slider").first
                slider.focus()
                page.keyboard.press("End")
                page.wait_for_function("(old) => { const p = [...document.querySelectorAll('p')].find("
                                       "e => e.innerText.includes('Selected:')); return p && p.innerText != old; }",
                                       arg=before, timeout=20000)
                after = selected_text(page)
                top = int(np.argmax(branches[0].energy))     # the slider's end: the highest energy
                assert f"point {top + 1} of" in after, after        # 1-based for users

                _phase(t_start, "energy slider moved the selection")
                # 3) pick a point of the in-scene FEP with the mouse
                entries = [BranchEntry(b, "") for b in branches]
                series = [e.series(1.0) for e in entries]
                ranges, shown = board_view(series, 0)     # zoomed on branch 1 when it is narrow
                bi, target = well_separated_point(series, geom, ranges, box, exclude=(0, top), shown=shown)
                p3 = geom.board.to_world(series[bi].energy[[target]], series[bi].frequency[[target]], ranges)
                (px, py), = project_points(p3, geom, box)
                picked = False
                for dx, dy in [(0, 0), (1, 1), (-1, -1), (2, 0), (0, 2)]:
                    page.mouse.click(px + dx, py + dy)
                    try:
                        page.wait_for_function(
                            "(want) => [...document.querySelectorAll('p')].some(e => e.innerText.includes(want))",
                            arg=f"branch {bi + 1}, point {target + 1} of", timeout=8000)
                        picked = True
                        break
                    except sync_api.TimeoutError:
                        continue
                assert picked, f"clicking FEP point {target} at ({px:.0f}, {py:.0f}) did not select it"
                time.sleep(2.0)
                page.screenshot(path=str(ARTIFACTS / f"browser_{kind}_picked.png"))
                text = page.evaluate("document.body.innerText")
                assert re.search(r"peak displacement \S+ \S*m", text), "no peak displacement shown"

                _phase(t_start, "FEP point picked")
                # 4) issue 14, item 5: arrow keys on a focused slider move the slider, not the camera
                #    (viser turns the camera on arrow keys unless a text field has the focus)
                changed = board_change_on_arrow_keys(page, geom, box, tmp_path / "board.png")
                page.screenshot(path=str(ARTIFACTS / f"browser_{kind}_arrow_keys.png"))
                assert changed < 0.05, f"arrow keys on a slider moved the camera ({changed:.0%} of the board changed)"
                _phase(t_start, "arrow keys on a slider left the camera alone")
            finally:
                browser.close()
    finally:
        server.terminate()
        try:
            server.wait(10)
        except subprocess.TimeoutExpired:
            server.kill()
    print(f"browser test on {kind}: {time.time() - t_start:.1f} s")


def _read_png(path):
    import matplotlib.image as mpimg
    img = mpimg.imread(path)
    if img.dtype != np.uint8:
        img = (img[..., :3] * 255).astype(np.uint8)
    return img[..., :3]


def board_screen_box(geom, box):
    """Screen rectangle (x0, y0, x1, y1) of the FEP board's plotting area, seen by the initial camera."""
    b = geom.board
    corners = np.array([b.origin + a * b.width * b.right + c * b.height * b.up for a in (0, 1) for c in (0, 1)])
    xy = project_points(corners, geom, box)
    x0, y0 = np.floor(xy.min(axis=0)).astype(int)
    x1, y1 = np.ceil(xy.max(axis=0)).astype(int)
    return max(x0, 0), max(y0, 0), x1, y1


def board_change_on_arrow_keys(page, geom, box, shot):
    """Fraction of the FEP board's screen pixels changed by holding the arrow keys on the focused
    Speed slider (which changes nothing on the board); asserts that the slider moved."""
    x0, y0, x1, y1 = board_screen_box(geom, box)

    def board():
        page.screenshot(path=str(shot))
        return _read_png(shot)[y0:y1, x0:x1].astype(float)

    before = board()
    slider = page.locator('[role=slider][aria-valuemin="0.05"][aria-valuemax="3"]')     # Speed (cycles/s)
    value = slider.get_attribute("aria-valuenow")
    slider.focus()
    for key in ("ArrowRight", "ArrowUp"):
        page.keyboard.down(key)
        time.sleep(0.6)                     # held: viser would turn the camera by 30 degrees
        page.keyboard.up(key)
    time.sleep(0.5)
    assert slider.get_attribute("aria-valuenow") != value, "the slider did not move"
    return float(np.mean(np.abs(board() - before).sum(axis=2) > 30))


#: JavaScript: the Compute tab shows a job's line ('12 of at most 80 points ...' or '40 points in 1 min ...')
JOB_LINE_JS = "/\\b[1-9]\\d* (of at most \\d+ points|points in)/.test(document.body.innerText)"


@pytest.mark.slow
def test_five_clients_at_once(tmp_path):
    """Issue 14: five browser tabs on one server at once: each gets its own session (its own selection),
    a branch computed from one tab streams into all of them, and every tab stays responsive."""
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian chromium is not installed (/usr/bin/chromium); apt-get install chromium")
    sync_api = pytest.importorskip("playwright.sync_api")
    from nnm_viewer.browser import launch_chromium, viewer_process, wait_selection_change
    from nnm_viewer.demo import write_demo_file

    t_start = time.time()
    path = tmp_path / "two.h5"
    write_demo_file(path, energy_max=10.0, max_points=30)
    nnm.load_branches(path)[0].motion(0, samples=16)      # the solver's kernels compiled (disk cache)
    _phase(t_start, "demo file written")
    port = free_port()
    with viewer_process(path, port) as (_, line), sync_api.sync_playwright() as pw:
        assert f":{port}" in line, line
        browser = launch_chromium(pw)
        try:
            # small windows: five software-WebGL renderers share the machine's cores
            pages = [browser.new_page(viewport={"width": 1100, "height": 640}) for _ in range(5)]
            for page in pages:                              # five tabs connect at the same time
                page.goto(f"http://127.0.0.1:{port}/", wait_until="commit")
            for page in pages:
                page.wait_for_function("document.body.innerText.includes('Selected:')", timeout=120000)
            _phase(t_start, "5 tabs populated")
            texts = [selected_text(p) for p in pages]
            assert all("branch 1, point 1 of" in t for t in texts), texts
            # tab 0 moves its selection: the other tabs keep theirs
            pages[0].get_by_role("slider").first.focus()
            pages[0].keyboard.press("End")
            wait_selection_change(pages[0], texts[0], timeout_ms=30000)
            assert "point 1 of" not in selected_text(pages[0])
            time.sleep(1.0)
            assert all("branch 1, point 1 of" in selected_text(p) for p in pages[1:])
            _phase(t_start, "tab 0 moved its selection alone")
            # tab 1 computes a branch: it selects it; every tab sees the job in its Compute tab
            pages[1].get_by_role("tab", name="Compute").click()
            pages[1].get_by_role("button", name="Start").click()
            pages[1].wait_for_function("document.body.innerText.includes('Selected: branch 3')", timeout=120000)
            for page in pages[2:] + pages[:1]:
                page.get_by_role("tab", name="Compute").click()
                page.wait_for_function(JOB_LINE_JS, timeout=60000)
            _phase(t_start, "the branch computed from tab 1 reached every tab")
            stop = pages[1].get_by_role("button", name="Stop (keep points)")
            if stop.is_enabled():
                stop.click()
            for page in pages:
                page.wait_for_function("document.body.innerText.includes('points in')", timeout=60000)
            assert "branch 3" in selected_text(pages[1]) and "branch 3" not in selected_text(pages[2])
            pages[4].screenshot(path=str(ARTIFACTS / "browser_five_tabs_tab5.png"))
        finally:
            browser.close()
    print(f"five tabs: {time.time() - t_start:.1f} s")


#: JavaScript: click the button whose text is ``name`` at the wall-clock time ``at`` (ms since the epoch), so that
#: two tabs of one browser press it within a few milliseconds of each other
CLICK_AT_JS = ("([name, at]) => { const b = [...document.querySelectorAll('button')].find("
               "x => x.innerText.trim() === name); if (!b) return false; "
               "setTimeout(() => b.click(), Math.max(0, at - Date.now())); return true; }")


def test_start_in_two_tabs_at_once_runs_one_job_that_either_tab_stops(tmp_path):
    """Issue 53, finding 10: two tabs pressing Start together got two jobs (branches 3 and 4), the first no longer
    stoppable.  Now one job runs: one new branch in every tab's list, the other tab is told a job is running, and
    Stop in that other tab stops the job.  The texts number points from 1 (finding 3)."""
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian chromium is not installed (/usr/bin/chromium); apt-get install chromium")
    sync_api = pytest.importorskip("playwright.sync_api")
    from nnm_viewer.browser import launch_chromium, open_page, viewer_process
    from nnm_viewer.demo import write_demo_file

    path = tmp_path / "two.h5"
    write_demo_file(path, energy_max=10.0, max_points=30)
    nnm.load_branches(path)[0].motion(0, samples=16)          # the solver's kernels compiled (disk cache)
    port = free_port()
    with viewer_process(path, port) as (_, line), sync_api.sync_playwright() as pw:
        assert f":{port}" in line, line
        browser = launch_chromium(pw)
        try:
            pages = [open_page(browser, port, viewport={"width": 1100, "height": 640}) for _ in range(2)]
            assert all("branch 1, point 1 of 30" in selected_text(p) for p in pages)
            for p in pages:
                p.get_by_role("tab", name="Compute").click()
                field = p.get_by_label("Max energy (J)", exact=True)      # a job that runs until stopped
                field.fill("1000000")
                field.press("Enter")
            time.sleep(1.0)
            at = int(pages[0].evaluate("Date.now()")) + 1500
            assert all(p.evaluate(CLICK_AT_JS, ["Start", at]) for p in pages)
            time.sleep(3.0)
            texts = [p.evaluate("document.body.innerText") for p in pages]
            refused = [k for k, t in enumerate(texts) if "already running" in t]
            assert len(refused) == 1, [t[:300] for t in texts]
            for p in pages:                                         # one new branch in each list
                p.wait_for_function(JOB_LINE_JS, timeout=60000)
                options = p.evaluate("[...document.querySelectorAll('option')].map(o => o.innerText)")
                assert not any(o.startswith("4:") for o in options), options
            other = pages[refused[0]]
            other.get_by_role("button", name="Stop (keep points)").click()
            for p in pages:
                p.wait_for_function("document.body.innerText.includes('points in')", timeout=60000)
            assert "stopped" in pages[1 - refused[0]].evaluate("document.body.innerText")
        finally:
            browser.close()
