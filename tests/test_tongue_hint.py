"""Issue 53, item 5 (two numberings): a branch that stops in a tongue names it as a user follows it, in the API
(0-based index into branch.tongues) and on the command line (nnm-solve's 1-based --tongue K, which does not count
the records where the family itself ends); both texts are run as they read."""
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nnm_solver as nnm
from nnm_solver.results.tongues import TongueRecord, continue_hint

TWO_DOF = Path(__file__).resolve().parents[1] / "assets" / "two_dof.h5"


def test_hint_numbers_as_the_api_and_the_cli_do():
    end = TongueRecord(order=3, partner_mode=2, family_end=True)
    t = TongueRecord(order=5, partner_mode=3)
    tongues = [TongueRecord(order=3, partner_mode=2), end, t]
    assert continue_hint(tongues, 2) == " (tongue 2: continue_tongue(branch, 2) or nnm-solve FILE --tongue 2 follows it)"
    assert continue_hint(tongues, 0).startswith(" (tongue 1: continue_tongue(branch, 0) ")
    assert continue_hint(tongues, 1) == ""                    # where the family ends: nothing to follow
    assert continue_hint(tongues, 2, shooting=False) == ""    # continue_tongue takes shooting branches only
    assert continue_hint(tongues, 3) == "" and continue_hint([], 0) == ""
    assert continue_hint([t.as_dict()], 0).startswith(" (tongue 1:")   # records read from older files (dicts)


def test_a_branch_stopped_in_a_tongue_says_what_to_type_and_it_runs(tmp_path):
    """NNM 1 of the 2-DOF model, tongues skipped with no jump allowed: it stops at the 3:1 tongue near 1.84 kJ
    and its message names the tongue; the API call and the command it gives both follow the tongue."""
    model = nnm.load_model(TWO_DOF)
    b = nnm.continue_nnm(model, 1, 1e4, tongues=nnm.Skip(max_jumps=0), max_points=200)
    assert b.status == "tongue", b.message
    m = re.search(r"\(tongue (\d+): continue_tongue\(branch, (\d+)\) or nnm-solve FILE --tongue (\d+) follows it\)",
                  b.message)
    assert m, b.message
    k, i, k_cli = map(int, m.groups())
    assert (k, i, k_cli) == (1, 0, 1) and not b.tongues[i].family_end
    api = nnm.continue_tongue(b, i, max_points=6)
    assert len(api) == 6 and abs(api.energy[0] / b.tongues[i]["entry_energy"] - 1) < 0.05
    path = tmp_path / "two.h5"
    shutil.copyfile(TWO_DOF, path)
    name = nnm.save_branch(path, b)
    r = subprocess.run([sys.executable, "-m", "nnm_solver.cli", str(path), "--tongue", str(k_cli), "--branch", name,
                        "--max-points", "6", "--out", str(tmp_path / "t.h5")], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    assert f"continuing tongue {k_cli} (tongue 3:1)" in r.stdout, r.stdout
    cli = nnm.load_branches(tmp_path / "t.h5")[-1]
    assert len(cli) == 6 and abs(cli.energy[0] - api.energy[0]) < 1e-6 * api.energy[0]
