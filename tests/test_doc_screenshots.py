"""`python -m nnm_viewer.screenshot --all` regenerates every viewer screenshot of the documentation (issue 32,
item 5): the list names each image the pages show, and each one's nnm file is there (the shipped aircraft)
or is built by docs/byom.md's commands; the browser part (screenshot.take) is replaced by a recorder here,
tests/test_browser.py drives the real one."""
import re

import pytest

import nnm_solver as nnm
from nnm_viewer import doc_screenshots, screenshot
from nnm_viewer.doc_screenshots import ROOT, SCREENSHOTS


def test_every_viewer_screenshot_of_the_docs_is_listed():
    names = {s.name for s in SCREENSHOTS}
    for shot in SCREENSHOTS:
        for page in shot.pages:
            assert f"img/{shot.name}" in (ROOT / page).read_text(), (page, shot.name)
        assert (ROOT / "docs" / "img" / shot.name).is_file()
    # the images the docs call viewer screenshots (their alt text or caption says nnm-view / the viewer)
    shown = set()
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for alt, img in re.findall(r"!\[([^\]]*)\]\((?:docs/)?img/([^)]+\.png)\)", page.read_text()):
            if "nnm-view" in alt or "viewer" in alt.lower():
                shown.add(img)
    assert shown == names
    assert "python -m nnm_viewer.screenshot --all" in (ROOT / "docs" / "viewer.md").read_text()


@pytest.mark.slow
def test_regenerate_builds_each_file_and_takes_each_shot(tmp_path):
    calls = []

    def take(path, out, point, branch):
        branches = nnm.load_branches(path)
        calls.append((path, out, point, branch, len(branches[branch])))
        return "selected"

    written = doc_screenshots.regenerate(take, tmp_path, log=lambda *_: None)
    assert [p.name for p in written] == [s.name for s in SCREENSHOTS]
    by_name = {c[1].rsplit("/", 1)[-1]: c for c in calls}
    path, _, point, branch, n = by_name["viewer.png"]
    assert path.endswith("assets/paris.h5") and (point, branch) == (0.9, 5) and n > 1      # mode 20's 3:1 tongue
    path, _, point, branch, n = by_name["byom_viewer.png"]
    assert path.endswith("beam_mtx.h5") and (point, branch) == (0.9, 0) and n > 10   # NNM 1 to 0.05 J


def test_all_option_takes_no_file(capsys):
    with pytest.raises(SystemExit):
        screenshot.main(["assets/paris.h5", "x.png", "--all"])
    with pytest.raises(SystemExit):
        screenshot.main([])
