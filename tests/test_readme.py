"""README.md's Python blocks run as written, and what their comments say is true (issue 32: the
iter_nnm example's `break` was never reached, so `partial.status` was 'done', not 'stopped')."""
import re
import time
from types import SimpleNamespace

import numpy as np
import pytest

from doc_blocks import ROOT, python_blocks, run_blocks


@pytest.mark.slow
def test_readme_solver_block_runs_and_its_comments_are_true(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                         # it writes fep.png and two_dof.h5
    blocks = python_blocks("README.md")
    assert len(blocks) == 2 and "iter_nnm" in blocks[0]
    # the 2-DOF solver tour (the second block, large models and forced responses, is docs/condensed_hb.md's
    # and docs/forced.md's)
    t0 = time.perf_counter()
    ns, times = run_blocks("README.md", only=[0])      # checks what each print prints against its comment
    assert time.perf_counter() - t0 < 600
    branch, partial, backbone = ns["branch"], ns["partial"], ns["backbone"]
    # print(branch.status, branch.message) and print(partial.status) were checked against their comments
    assert branch.status == "done" and branch.message == "reached energy_max = 10000 J"
    # "every point seen, the last one above 0.2 Hz" and "NNM 1 rises from 0.159 Hz towards 0.225 Hz"
    assert partial.status == "stopped" and partial.frequency_hz[-1] > 0.2 >= partial.frequency_hz[:-1].max()
    assert abs(ns["freqs_hz"][0] - 0.159) < 5e-4 and branch.frequency_hz.max() < 0.225
    assert np.allclose(ns["shapes"].T @ np.eye(2) @ ns["shapes"], np.eye(2))       # mass-normalised
    assert len(ns["t"]) == ns["x"].shape[-1] or len(ns["t"]) == ns["x"].shape[0]
    assert set(branch.labels) <= {"backbone", "tongue 3:1"}
    assert {e["kind"] for e in branch.events} >= {"fold", "branch_point"}
    assert (tmp_path / "fep.png").stat().st_size > 10_000 and (tmp_path / "two_dof.h5").is_file()
    # the background job: Points on the queue, then None, and a result
    assert ns["job"].done
    # "[{'label': 'tongue 3:1', 'partner_mode': 2, ...}, ...]" and "the 3:1 tongue as its own branch"
    first = backbone.tongues[0]
    assert first["label"] == "tongue 3:1" and first["partner_mode"] == 2 and len(backbone.tongues) > 1
    assert "3:1 tongue" in ns["tongue"].name and len(ns["tongue"]) > 10
    # the pitchfork at 40.9748 J (shared/reference: the 2-DOF benchmark; Newmark at 200 steps put it at 41.08 J)
    assert ns["born"].message.startswith("family from the branch_point at E = 40.97") and len(ns["born"]) > 1
    # the default (gauss6) and freq_tol: estimated errors, smaller than Newmark's at 200 steps (`paper`)
    paper = ns["paper"]
    assert np.nanmax(branch.freq_error) < 1e-5 < np.nanmax(paper.freq_error)
    refined = ns["refined"]
    assert np.nanmedian(refined.freq_error) < np.nanmedian(paper.freq_error)
    assert max(refined.steps) > 200
    # "its cost grows as freq_tol tightens": measured in work, not seconds (the first run also compiles the kernels)
    assert np.sum(refined.steps) > 1.5 * np.sum(paper.steps) * len(refined) / len(paper)
    assert ns["hb_branch"].coefficients is not None and ns["hb_branch"].status == "done"



def test_readme_viewer_address_is_the_one_nnm_view_prints():
    """README: `nnm-view ...  # prints "... Open http://127.0.0.1:8080 in a browser"`: the default host and
    port of nnm-view, and the address it prints for them."""
    from nnm_viewer.app import ViewerApp, parse_args

    text = (ROOT / "README.md").read_text()
    claimed = re.findall(r"Open (http://[^ ]+) in a browser", text)
    args = parse_args(["x.h5"])
    url = ViewerApp.url.fget(SimpleNamespace(host=args.host, port=args.port))
    assert claimed == [url] == ["http://127.0.0.1:8080"]
    assert ViewerApp.url.fget(SimpleNamespace(host="0.0.0.0", port=9000)) == "http://127.0.0.1:9000"
    assert "localhost" not in text
    viewer_md = (ROOT / "docs" / "viewer.md").read_text()
    assert set(re.findall(r"Open (http://[^ ]+) in a browser", viewer_md)) == {url}
