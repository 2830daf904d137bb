"""Real-browser test of the FEP board's spheres (issue 53, finding 7): the translucent halo viser 1.1 draws around
the sphere under the pointer (the hover outline of a clickable batched mesh, right after a click it is on the
picked sphere) was stretched once the canvas had been resized: viser sizes that screen-space outline with the
canvas size it read when the spheres were added.  The viewer adds them anew when the canvas changes size
(controls.Session._on_camera); here the halo is measured on a screenshot after a resize.  Debian's Chromium,
headless (skipped when /usr/bin/chromium is absent)."""
import os
import time

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_viewer.browser import (CHROMIUM, CLOSE_NOTIFICATIONS_JS, board_view, free_port, launch_chromium, open_page,
                                viewer_process)
from nnm_viewer.scene import fallback_mesh, project_points, view_geometry
from nnm_viewer.state import BranchEntry

pytestmark = pytest.mark.browser


def yellow_extent(png, xy, r=45):
    """(width, height) px of the yellow pixels (the picked point's marker and the hover halo around it) in a
    (2r+1)-px square around screen point ``xy`` of the screenshot ``png``."""
    import matplotlib.image as mpimg

    img = mpimg.imread(png)
    a = (img[..., :3] * 255).astype(int) if img.dtype != np.uint8 else img[..., :3].astype(int)
    x, y = (int(round(v)) for v in xy)
    sub = a[y - r:y + r + 1, x - r:x + r + 1]
    R, G, B = sub[..., 0], sub[..., 1], sub[..., 2]
    ys, xs = np.nonzero((R > 150) & (G > 140) & (B < 150) & (R - B > 80))
    assert len(xs), "no yellow near the picked point"
    return xs.max() - xs.min() + 1, ys.max() - ys.min() + 1


def test_hover_halo_on_the_picked_sphere_stays_round_after_a_resize(tmp_path):
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian chromium is not installed (/usr/bin/chromium); apt-get install chromium")
    sync_api = pytest.importorskip("playwright.sync_api")
    from nnm_viewer.demo import write_demo_file

    path = tmp_path / "two.h5"
    write_demo_file(path, energy_max=10.0, max_points=30)
    model, branches = nnm.load_model(path), nnm.load_branches(path)
    branches[0].motion(0, samples=16)                       # the solver's kernels compiled (disk cache)
    geom = view_geometry((model.mesh if model.mesh is not None else fallback_mesh(model.n)).vertices)
    series = [BranchEntry(b, "").series(1.0) for b in branches]
    ranges, _ = board_view(series, 0)
    target = 9                                              # NNM 1's 10th point: apart from its neighbours
    world = geom.board.to_world(series[0].energy[[target]], series[0].frequency[[target]], ranges)
    port = free_port()
    with viewer_process(path, port) as (_, line), sync_api.sync_playwright() as pw:
        assert f":{port}" in line, line
        browser = launch_chromium(pw)
        try:
            page = open_page(browser, port)
            page.evaluate(CLOSE_NOTIFICATIONS_JS)
            time.sleep(2.0)
            (px, py), = project_points(world, geom, page.locator("canvas").first.bounding_box())
            page.mouse.click(px, py)
            page.wait_for_function("(want) => [...document.querySelectorAll('p')].some(e => e.innerText.includes(want))",
                                   arg=f"point {target + 1} of", timeout=30000)
            page.set_viewport_size({"width": 1000, "height": 900})      # the canvas narrows
            time.sleep(3.0)                                               # its camera message; spheres re-added
            (qx, qy), = project_points(world, geom, page.locator("canvas").first.bounding_box())
            page.mouse.move(5, 5)
            time.sleep(1.5)
            page.screenshot(path=str(tmp_path / "away.png"))
            page.mouse.move(qx, qy)
            time.sleep(1.5)
            page.screenshot(path=str(tmp_path / "hover.png"))
        finally:
            browser.close()
    w0, h0 = yellow_extent(tmp_path / "away.png", (qx, qy))             # the marker alone
    w1, h1 = yellow_extent(tmp_path / "hover.png", (qx, qy))            # with the halo
    assert w1 >= w0 + 6 and h1 >= h0 + 6, ((w0, h0), (w1, h1))         # a halo on both axes ...
    assert 0.8 < w1 / h1 < 1.25, (w1, h1)                              # ... round (it was 17 x 30 px)
