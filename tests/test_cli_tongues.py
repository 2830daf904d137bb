"""nnm-solve reaches the backbone and the families started on a saved branch (issue 53, findings 1, 2, 3, 9):
--tongues skip|follow, --tongue K (continue_tongue), --switch K (switch_branch), the lists they number from 1,
events numbered from 1, the solver's defaults in --help, and the points off the backbone marked on every plot."""
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.cli.defaults import solver_defaults

ROOT = Path(__file__).resolve().parents[1]
TWO_DOF = ROOT / "assets" / "two_dof.h5"


def run(*args, timeout=600):
    return subprocess.run([sys.executable, "-m", "nnm_solver.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


@pytest.fixture(scope="module")
def backbone(tmp_path_factory):
    """NNM 1 of the 2-DOF model to 1e4 J with the tongues skipped: the 3:1 tongue at 1.8 kJ jumped, two branch
    points located (41 J, 6.7 kJ)."""
    out = tmp_path_factory.mktemp("cli_tongues") / "b.h5"
    plot = out.with_suffix(".png")
    r = run(TWO_DOF, "--mode", 1, "--energy-max", 1e4, "--tongues", "skip", "--max-points", 200, "--out", out,
            "--plot", plot)
    assert r.returncode == 0, r.stderr
    return out, plot, r.stdout


def test_help_gives_the_solvers_defaults_and_every_flag_its_text():
    r = run("--help")
    assert r.returncode == 0
    text = " ".join(r.stdout.split())
    text = text[text.index("options:"):]                  # the flags' texts, not the usage line
    D = solver_defaults()
    for flag, default in (("--steps-per-period", D["steps_per_period"]), ("--max-points", D["max_points"]),
                          ("--tongues", D["tongues"]), ("--harmonics", D["harmonics"]), ("--integrator", D["integrator"])):
        block = text[text.index(f"{flag} "):]
        assert f"default {default}" in block[:block.index(" --", len(flag) + 1) if flag != "--tongues" else 400], flag
    assert re.search(r"--steps-per-period STEPS shooting: time steps per period", text)
    assert re.search(r"--max-points N largest number of points", text)
    for flag in ("--tongue K", "--switch K", "--branch NAME"):
        assert flag in text


def test_tongues_skip_saves_a_backbone_that_lists_its_tongues(backbone):
    out, plot, stdout = backbone
    (b,) = nnm.load_branches(out)
    assert plot.stat().st_size > 10_000
    assert b.tongues and b.tongues[0]["label"] == "tongue 3:1" and b.tongues[0]["skipped"]
    assert f"tongue 1: tongue 3:1 with mode 2, entered at E = {b.tongues[0]['entry_energy']:.4g} J" in stdout
    assert abs(b.tongues[0]["entry_energy"] / 1838 - 1) < 0.01          # the 3:1's entrance near 1.84 kJ
    assert set(b.labels) == {"backbone"}
    # events and branch points numbered from 1, as the lists --switch K reads
    bps = [e for e in b.events if e["kind"] == "branch_point"]
    assert len(bps) == 2
    for k, e in enumerate(bps, 1):
        assert f"branch_point near point {e['index'] + 1:>4}:" in stdout
        assert f"switch {k}: branch point near point {e['index'] + 1}," in stdout


def test_tongue_k_continues_the_listed_tongue_and_the_plot_marks_it(backbone, tmp_path):
    out, _, _ = backbone
    target = tmp_path / "t.h5"
    plot = tmp_path / "t.png"
    r = run(out, "--tongue", 1, "--max-points", 80, "--out", target, "--plot", plot)
    assert r.returncode == 0, r.stderr
    assert "continuing tongue 1 (tongue 3:1)" in r.stdout and plot.exists()
    (t,) = nnm.load_branches(target)
    off = int(np.sum(t.labels == "tongue 3:1"))
    assert off > 10 and f"points off the backbone: tongue 3:1 ({off} of {len(t)}" in r.stdout
    entry = nnm.load_branches(out)[0].tongues[0]["entry_energy"]
    assert t.energy.min() < 0.5 * entry                   # the tongue's excursion to lower energies
    # out of range: one line, exit 2, nothing written
    r = run(out, "--tongue", 2, "--out", tmp_path / "none.h5")
    assert r.returncode == 2 and "--tongue 2" in r.stderr and "1..1" in r.stderr and len(r.stderr.splitlines()) == 1
    assert not (tmp_path / "none.h5").exists()


def test_switch_k_continues_the_family_born_at_the_branch_point(backbone, tmp_path):
    out, _, _ = backbone
    target = tmp_path / "s.h5"
    r = run(out, "--switch", 1, "--energy-max", 100, "--max-points", 30, "--out", target)
    assert r.returncode == 0, r.stderr
    (s,) = nnm.load_branches(target)
    (b,) = nnm.load_branches(out)
    bp = [e for e in b.events if e["kind"] == "branch_point"][0]
    assert abs(s.energy[0] / bp["energy"] - 1) < 0.2 and "switched at branch_point" in s.name
    for args, words in ((("--switch", 1), "needs --energy-max"), (("--switch", 3, "--energy-max", 10), "(1..2)")):
        r = run(out, *args)
        assert r.returncode == 2 and words in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr


def test_a_family_needs_a_saved_branch_with_what_it_starts_from(tmp_path):
    p = tmp_path / "m.h5"
    model = nnm.load_model(TWO_DOF)
    nnm.save_model(p, model)
    nnm.save_branch(p, nnm.continue_nnm(model, 2, 0.01, max_points=3))
    r = run(p, "--tongue", 1)
    assert r.returncode == 2 and "no branch with tongues" in r.stderr and len(r.stderr.splitlines()) == 1


def test_every_plot_marks_the_points_off_the_backbone(two_dof_nnm1):
    """plot_fep and plot_atlas draw the points labelled off the backbone in another colour and marker, named in
    the legend by their label; a backbone gets no such entry."""
    import matplotlib
    matplotlib.use("Agg")
    from nnm_solver.results.plotting import OFF_BACKBONE_COLOR, plot_atlas, plot_fep

    b = two_dof_nnm1                                   # followed through its 3:1 tongue
    off = b.labels != "backbone"
    assert 0 < off.sum() < len(b)
    for draw in (plot_fep, plot_atlas):
        ax = draw(b)
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any("tongue 3:1 (off the backbone)" in t for t in legend), legend
        marked = [ln for ln in ax.get_lines() if ln.get_color() == OFF_BACKBONE_COLOR]
        assert sum(len(ln.get_xdata()) for ln in marked) == off.sum()
        np.testing.assert_array_equal(np.sort(np.concatenate([ln.get_xdata() for ln in marked])),
                                      np.sort(b.energy[off]))
        ax = draw(b.subset(~off))
        assert not any("off the backbone" in t.get_text() for t in (ax.get_legend().get_texts()))


def test_tongue_lines_say_what_the_branch_did_at_each_tongue():
    """'jumped' (skip, landed beyond), 'not passed' (the last record of a branch that ended in it: the aircraft's
    mode 19 to 10 J printed 'passed' for the 9:1 tongue it ended in), 'followed through' (follow)."""
    from types import SimpleNamespace

    from nnm_solver.cli.families import tongue_lines
    from nnm_solver.results.tongues import TongueRecord

    def record(skipped):
        return TongueRecord(order=3, partner_mode=2, entry_energy=10.0, entry_frequency_hz=1.0, entry_x0=(1.0, 0.0),
                            skipped=skipped, exit_energy=12.0 if skipped else None)

    ended = SimpleNamespace(status="tongue", tongues=[record(True), record(False)])
    lines = tongue_lines(ended)
    assert "(jumped, back on the backbone at 12 J;" in lines[0]
    assert "(not passed: the branch ends at its entry;" in lines[1]
    followed = SimpleNamespace(status="done", tongues=[record(False)])
    assert "(followed through;" in tongue_lines(followed)[0]


def test_a_family_refuses_the_options_it_does_not_use(tmp_path):
    """Found in the fresh-clone trial of issue 53: `--switch 1 --integrator gauss6 --steps-per-period 100` ran with
    newmark at 200 steps (the parent's), the options silently dropped, and its accuracy line then advised exactly
    those options.  Now an option a family does not use is one line (exit 2) before anything is computed or
    written, and the advice names what the family takes."""
    cases = ((("--switch", 1, "--energy-max", 10, "--integrator", "gauss6", "--steps-per-period", 100),
              "--integrator, --steps-per-period: not used by --switch K"),
             (("--switch", 1, "--energy-max", 10, "--freq-tol", 1e-6), "--freq-tol: not used by --switch K"),
             (("--tongue", 1, "--method", "hb"), "--method: not used by --tongue K"),
             (("--tongue", 1, "--tongues", "skip", "--freq-tol", 1e-6), "--freq-tol, --tongues: not used by --tongue"))
    for args, words in cases:
        out = tmp_path / "never.h5"
        r = run(TWO_DOF, *args, "--out", out)
        assert r.returncode == 2 and words in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
        assert not out.exists()


def test_the_accuracy_advice_names_the_options_that_apply():
    from nnm_solver.cli.report import ACCURACY_ADVICE, accuracy_line

    model = nnm.load_model(TWO_DOF)
    coarse = nnm.continue_nnm(model, 1, 0.01, max_points=3, integrator="newmark", steps_per_period=16, freq_tol=None)
    assert np.nanmax(coarse.freq_error) > 1e-4                     # newmark at 16 steps: about 1 % off
    assert accuracy_line(coarse).endswith(f"({ACCURACY_ADVICE['branch']})")
    assert "--freq-tol" not in accuracy_line(coarse, "tongue")
    switch = accuracy_line(coarse, "switch")
    assert "parent" in switch and "--freq-tol" not in switch


def test_the_tongue_and_switch_lists_give_the_command_with_the_file(backbone):
    """The lists after a run name the file the branch was saved in (a command to copy, not 'nnm-solve ...');
    --switch with the --energy-max it needs."""
    from types import SimpleNamespace

    from nnm_solver.cli.families import tongue_lines
    from nnm_solver.results.tongues import TongueRecord

    out, _, stdout = backbone
    assert f"nnm-solve {out} --tongue 1 continues it" in stdout
    assert f"nnm-solve {out} --switch 1 --energy-max E continues the family born there" in stdout
    ended = SimpleNamespace(status="tongue", tongues=[TongueRecord(order=9, partner_mode=238, entry_energy=6.6,
                                                                   entry_frequency_hz=31.5, entry_x0=(1.0, 0.0))])
    assert "(not passed: the branch ends at its entry; nnm-solve 'my file.h5' --tongue 1 continues it)" in \
        tongue_lines(ended, "my file.h5")[0]
