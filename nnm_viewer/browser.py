"""Driving the viewer in Debian's Chromium (headless, software WebGL) with Playwright: shared by
the screenshot tool, the latency benchmark and the browser test.

Needs the ``playwright`` package and /usr/bin/chromium (``apt-get install chromium``); Playwright's
own browser is never downloaded.
"""
from __future__ import annotations

import contextlib
import shutil
import socket
import subprocess
import sys

import numpy as np

CHROMIUM = "/usr/bin/chromium"
#: software WebGL without a GPU, and no network traffic of Chromium's own
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync"]
VIEWPORT = {"width": 1600, "height": 900}
#: JavaScript returning the selection text of the control panel ('Selected: branch i, point s ...')
SELECTED_JS = ("() => { const p = [...document.querySelectorAll('p')].find(e => e.innerText.includes('Selected:'));"
               " return p ? p.innerText : ''; }")
#: JavaScript closing the notifications (e.g. headless Chromium's 'software WebGL rendering' notice)
CLOSE_NOTIFICATIONS_JS = "document.querySelectorAll('button.mantine-Notification-closeButton').forEach(b => b.click())"


def free_port():
    """A TCP port free on 127.0.0.1 at the time of the call."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def viewer_command(path, port):
    """The command line of ``nnm-view FILE --port PORT`` (the module if the script is not installed)."""
    exe = shutil.which("nnm-view")
    return ([exe] if exe else [sys.executable, "-m", "nnm_viewer"]) + [str(path), "--port", str(port)]


@contextlib.contextmanager
def viewer_process(path, port, cwd=None, env=None):
    """Run ``nnm-view`` on ``path`` (a file or a shipped example's name) in a subprocess, in folder
    ``cwd`` with environment ``env`` (default: this one); yields (process, the line it printed when
    ready).  The process is terminated (killed after 10 s) on exit; RuntimeError with its stderr if it
    does not start."""
    import tempfile

    err = tempfile.TemporaryFile(mode="w+")    # a pipe nobody reads could fill up and stall the server
    proc = subprocess.Popen(viewer_command(path, port), stdout=subprocess.PIPE, stderr=err, text=True,
                            cwd=cwd, env=env)
    try:
        line = proc.stdout.readline()
        if not line:
            proc.wait(10)
            err.seek(0)
            raise RuntimeError(f"nnm-view did not start: {err.read().strip()}")
        yield proc, line
    finally:
        err.close()
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


def launch_chromium(playwright):
    """Debian's Chromium, headless with software WebGL, from a ``sync_playwright()`` context."""
    return playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)


def open_page(browser, port, viewport=VIEWPORT, timeout_ms=120000):
    """A new page on the viewer at ``port``, once the selection text is shown (the session is built)."""
    page = browser.new_page(viewport=dict(viewport))
    page.goto(f"http://127.0.0.1:{port}/")
    page.wait_for_function("document.body.innerText.includes('Selected:')", timeout=timeout_ms)
    return page


def selected_text(page):
    """The selection text shown in the page ('' before the session is drawn)."""
    return page.evaluate(SELECTED_JS)


def wait_selection_change(page, before, timeout_ms=60000):
    """Wait until the selection text differs from ``before`` (Playwright's TimeoutError otherwise)."""
    page.wait_for_function(f"(old) => ({SELECTED_JS})() != old", arg=before, timeout=timeout_ms)


def board_view(series, selected=0):
    """(axis ranges, indices of the branches drawn) of the FEP board as a new tab shows it with branch
    ``selected`` picked: zoomed on that branch when it spans a small part of the frequency range
    (fep.should_zoom; the other branches are then hidden), else every branch."""
    from .fep import axis_ranges, should_zoom

    if should_zoom(series, selected):
        return axis_ranges([series[selected]]), [selected]
    return axis_ranges(series), [k for k, s in enumerate(series) if len(s)]


#: label of the checkbox "FEP: zoom on selected branch" (the screenshot unticks it to show every branch)
ZOOM_CHECKBOX_LABEL = "FEP: zoom on selected branch"


def screen_box(points, geom, box, viewport=VIEWPORT):
    """Integer screen rectangle (x0, y0, x1, y1), clipped to the viewport, of world points seen by
    the initial camera in the canvas ``box`` (Playwright bounding box)."""
    from .scene import project_points

    sub = np.asarray(points)[:: max(1, len(points) // 2000)]
    xy = project_points(sub, geom, box)
    top = [viewport["width"] - 1, viewport["height"] - 1]
    x0, y0 = np.clip(xy.min(axis=0), 0, top).astype(int)
    x1, y1 = np.clip(xy.max(axis=0), 0, top).astype(int)
    return x0, y0, x1, y1
