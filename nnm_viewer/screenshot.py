"""Screenshot of the viewer (for the documentation), taken with Debian's Chromium headless.

    python -m nnm_viewer.screenshot assets/paris.h5 docs/img/viewer.png [--point 0.6] [--tab FEP]
    python -m nnm_viewer.screenshot --all [DIR]    # every viewer screenshot of the docs (doc_screenshots.py)

Starts ``nnm-view`` on FILE, opens it in Chromium (Playwright, software WebGL), picks the point
at fraction ``--point`` of the first branch by clicking its sphere in the 3D FEP, pauses the
animation at a phase of large displacement, and saves the page.  Needs the ``playwright``
package and /usr/bin/chromium (never downloads a browser; see browser.py).
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from .browser import (CLOSE_NOTIFICATIONS_JS, ZOOM_CHECKBOX_LABEL, free_port, launch_chromium, open_page,
                      selected_text, viewer_process, wait_selection_change)


#: scroll every scrolled element of the page back to its top (the panels show their first controls)
SCROLL_TO_TOP_JS = "document.querySelectorAll('*').forEach(e => { if (e.scrollTop) e.scrollTop = 0; })"


def take(path, out, point=0.6, tab="FEP", size=(1600, 900), branch=0):
    """Save a PNG of the viewer on ``path`` with point ``point`` (fraction 0..1) of branch
    ``branch`` (0-based position in the file) picked; returns the selection text shown."""
    import nnm_solver as nnm
    from playwright.sync_api import sync_playwright

    from .fep import axis_ranges, should_zoom
    from .scene import fallback_mesh, project_points, view_geometry
    from .state import BranchEntry

    model = nnm.load_model(path)
    branches = nnm.load_branches(path)
    if not branches:
        raise SystemExit(f"{path} has no branch to show")
    mesh = model.mesh if model.mesh is not None else fallback_mesh(model.n)
    geom = view_geometry(mesh.vertices)
    series = [BranchEntry(b, "").series(1.0) for b in branches]
    ranges = axis_ranges(series)
    target = int(round(point * (len(series[branch]) - 1)))
    port = free_port()
    with viewer_process(path, port), sync_playwright() as pw:
        browser = launch_chromium(pw)
        try:
            page = open_page(browser, port, viewport={"width": size[0], "height": size[1]})
            time.sleep(3.0)
            if should_zoom(series, 0):        # zoomed on branch 1 by default: show every branch
                page.get_by_text(ZOOM_CHECKBOX_LABEL).click()
                time.sleep(3.0)
            box = page.locator("canvas").first.bounding_box()
            p3 = geom.board.to_world(series[branch].energy[[target]], series[branch].frequency[[target]], ranges)
            (px, py), = project_points(p3, geom, box)
            before = selected_text(page)
            page.mouse.click(px, py)
            wait_selection_change(page, before)
            if tab != "FEP":
                page.get_by_role("tab", name=tab).click()
            time.sleep(5.0)
            page.evaluate(CLOSE_NOTIFICATIONS_JS)
            page.evaluate(SCROLL_TO_TOP_JS)       # ticking the zoom box scrolled the control panel down
            time.sleep(1.0)
            page.screenshot(path=str(out))
            text = selected_text(page)
        finally:
            browser.close()
    return text


def main(argv=None):
    ap = argparse.ArgumentParser(description="Screenshot of nnm-view (docs)")
    ap.add_argument("file", nargs="?", help="nnm file to show (not with --all)")
    ap.add_argument("out", nargs="?", help="PNG written (not with --all)")
    ap.add_argument("--point", type=float, default=0.6, help="fraction along the first branch (0..1)")
    ap.add_argument("--branch", type=int, default=1, help="branch number (1-based, in file order)")
    ap.add_argument("--tab", default="FEP", help="right panel tab: FEP, Point, Compute or Modes")
    ap.add_argument("--all", nargs="?", const="", default=None, metavar="DIR",
                    help="every viewer screenshot of the documentation (doc_screenshots.SCREENSHOTS) into DIR "
                         "(default: docs/img)")
    args = ap.parse_args(argv)
    if args.all is not None:
        if args.file or args.out:
            ap.error("--all takes no FILE or OUT (its folder is --all DIR)")
        from .doc_screenshots import regenerate
        regenerate(take, args.all or None)
        return 0
    if not (args.file and args.out):
        ap.error("FILE and OUT are needed (or --all)")
    text = take(args.file, args.out, point=float(np.clip(args.point, 0, 1)), tab=args.tab, branch=args.branch - 1)
    print(f"wrote {args.out}: {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
