"""A new user's first day (issue 32, items 1 and 2): the tutorial's commands leave the shipped example
alone, and nnm-solve does not append a branch of another model to an existing file."""
import hashlib
import importlib.util
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import scipy.io

import nnm_solver as nnm

ROOT = Path(__file__).resolve().parents[1]


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def paris_fep():
    spec = importlib.util.spec_from_file_location("example_paris_fep_doc", ROOT / "examples" / "paris_fep.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def tutorial_commands(script):
    """The argument lists of the `python examples/<script>` commands in docs/tutorial.md's code blocks."""
    out, inside = [], False
    for line in (ROOT / "docs" / "tutorial.md").read_text().splitlines():
        if line.startswith("```"):
            inside = not inside
            continue
        words = shlex.split(line.split("#")[0]) if inside else []
        if words[:2] == ["python", f"examples/{script}"]:
            out.append(words[2:])
    return out


def test_tutorial_paris_commands_write_into_the_current_folder(tmp_path, monkeypatch):
    """Every paris_fep.py command of the tutorial writes ./paris_fep.h5 and ./paris_fep_figures/, not the
    shipped assets/paris.h5 nor docs/ (checked on the script's own argument parsing, nothing is run);
    --update-shipped, the maintainers' flag, is the one way to the shipped file."""
    ex = paris_fep()
    commands = tutorial_commands("paris_fep.py")
    assert ["--fast"] in commands
    monkeypatch.chdir(tmp_path)
    for argv in commands:
        args = ex.build_parser().parse_args(argv)
        target = ex.output_file(args)
        assert not isinstance(target, str), (argv, target)
        if "--update-shipped" in argv:
            assert target in (None, ex.SHIPPED)
            continue
        assert target == Path("paris_fep.h5") and not ex.same_file(target, ex.SHIPPED), argv
        assert args.out_dir is None and args.doc is None, argv   # figures: ./paris_fep_figures, no doc table
    text = (ROOT / "docs" / "tutorial.md").read_text()
    assert "nnm-view paris_fep.h5" in text and "--update-shipped" in text
    assert "branches into assets/paris.h5" not in text
    args = ex.build_parser().parse_args(["--fast", "--update-shipped"])
    assert ex.output_file(args) == ex.SHIPPED


def run(*args, cwd, timeout=180):
    return subprocess.run([sys.executable, "-m", "nnm_solver.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd)


def test_solve_refuses_a_branch_of_another_model_in_the_same_file(tmp_path):
    """`nnm-solve chain.toml --mode 1 ...` then `nnm-solve chain.mat --mode 1 ...` (other M, K and spring)
    in the same folder: both default to chain.h5; the second is refused (exit 2, one line naming the file,
    what differs and another file name) and chain.h5 stays byte-identical.  The same model again is fine."""
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
    scipy.io.mmwrite(tmp_path / "M.mtx", np.eye(3))
    scipy.io.mmwrite(tmp_path / "K.mtx", K)
    (tmp_path / "chain.toml").write_text('name = "chain"\n[matrices]\nformat = "matrixmarket"\nmass = "M.mtx"\n'
                                         'stiffness = "K.mtx"\n[[springs]]\ndof = 0\nk3 = 0.5\n')
    scipy.io.savemat(tmp_path / "chain.mat", {"M": 2 * np.eye(3), "K": 3 * K, "springs": np.array([[2, 0, 1.5]])})
    r = run("chain.toml", "--mode", 1, "--energy-max", 1, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    h5 = tmp_path / "chain.h5"
    before = sha256(h5)
    r = run("chain.mat", "--mode", 1, "--energy-max", 1, cwd=tmp_path)
    assert r.returncode == 2, (r.stdout, r.stderr)
    err = [line for line in r.stderr.replace("\r", "\n").splitlines() if "error" in line]
    assert err == ["nnm-solve: error: chain.h5 holds another model than this branch's (spring 0 joins DOFs "
                   "0-ground in the file, 1-ground in the branch's model; M differs by up to 50 % of its largest "
                   "entry; K differs by up to 66.7 % of its largest entry); the file was left unchanged: save the "
                   "branch to another file name, e.g. chain_2.h5 (nnm-solve: --out chain_2.h5)"], r.stderr
    assert "Traceback" not in r.stderr
    assert sha256(h5) == before
    # the remedy, and the same model again
    r = run("chain.mat", "--mode", 1, "--energy-max", 1, "--out", "chain_2.h5", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    r = run("chain.toml", "--mode", 2, "--energy-max", 1, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert [b.mode for b in nnm.load_branches(h5)] == [1, 2]
    assert nnm.load_model(tmp_path / "chain_2.h5").k3[0] == 1.5


def test_status_texts_name_the_tongue_once_and_count_what_they_say():
    """Issue 32: a status read 'the tongue 3:1 tongue ... (121 points inside it)'.  The backbone policy's messages
    (backbone/policy.py) name the resonance once ('the 3:1 internal-resonance tongue with mode 2') and say what was
    tried: the orbits of the skeleton that did not land, or the family's end."""
    import re

    from nnm_solver.backbone.policy import SkipPolicy
    from nnm_solver.results.tongues import TongueRecord

    t = TongueRecord(order=3, partner_mode=2, entry_energy=4708.0, entry_frequency_hz=0.22344)
    bpoint = nnm.Point(4708.0, 0.22344, 1 / 0.22344, np.zeros(2), np.zeros(2), np.ones(4), True)

    class Skeleton:
        energy = np.array([1.0, 5000.0])
        energy_peak, end, partner, message, sheet_starts = 5000.0, "peak", (1, 0), "its energy turns back", []

    pol = SkipPolicy(nnm.Skip(), None, "the skeleton could not be computed: singular")
    no_skeleton = pol.no_landing(bpoint, t, ()).message
    assert no_skeleton.startswith("the backbone entered the 3:1 internal-resonance tongue with mode 2 at E = 4708 J")
    tried = SkipPolicy(nnm.Skip(), type("S", (Skeleton,), dict(end="reach", energy_peak=None))()).no_landing(
        bpoint, t, (4731.5, 5179.0)).message
    assert "none of the skeleton's 2 orbits from 4732 to 5179 J landed on the family" in tried
    escape = SkipPolicy(nnm.Skip(), Skeleton()).no_landing(bpoint, t, (4731.5,))
    assert escape.status == "escape" and "energy maximum 5000 J" in escape.message
    for text in (no_skeleton, tried, escape.message):
        assert not re.search(r"\b(\w+) \1\b", text), text          # no doubled word
        assert "tongue 3:1" not in text and text.count("3:1 internal-resonance tongue") == 1, text


def test_a_tongue_branch_is_named_once():
    """continue_tongue's branch: 'NNM 1: 3:1 tongue at ... Hz', not 'tongue 3:1 tongue'."""
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    backbone = nnm.continue_nnm(model, mode=1, energy_max=1e4, tongues="skip")
    assert backbone.tongues and backbone.tongues[0]["label"] == "tongue 3:1"
    tongue = nnm.continue_tongue(backbone, 0, max_points=5)
    assert tongue.name.startswith("NNM 1: 3:1 tongue at 0.22"), tongue.name


def test_files_the_docs_write_in_the_repository_root_are_ignored():
    """Following README.md and docs/tutorial.md from the repository root writes these files; git ignores
    them (and still tracks the shipped assets/ and docs/img/)."""
    import shutil

    if shutil.which("git") is None or not (ROOT / ".git").exists():
        import pytest
        pytest.skip("not a git checkout")
    written = ["paris_branches.h5", "branches.h5", "fep.png", "paris_fep.h5", "paris_fep_figures/paris_fep_overview.png",
               "two_dof.h5", "hb.h5", "atlas.h5", "atlas.png", "nnm1.uff", "bb.csv", "chain.h5", "two_dof_branches.h5"]
    r = subprocess.run(["git", "-C", str(ROOT), "check-ignore", "--no-index", *written], capture_output=True, text=True)
    assert sorted(r.stdout.split()) == sorted(written), r.stdout
    r = subprocess.run(["git", "-C", str(ROOT), "check-ignore", "--no-index", "assets/paris.h5", "docs/img/viewer.png"],
                       capture_output=True, text=True)
    assert r.stdout == ""
