"""docs/tutorial.md's numbers cannot drift (issue 32): its Python blocks run as written and print what
their comments say, and the numbers of its prose (sections 4, 6 and 7) are rebuilt here from the shipped
run (assets/two_dof.h5, the branches drawn in the page's figures) or from section 2's fresh branch, then
looked up in the page.  A number that changes in the file or in the solver fails the test, and so does a
sentence of the page that is reworded without updating the claim checked here."""
import numpy as np
from doc_blocks import ROOT, python_blocks, run_blocks

import nnm_solver as nnm
from nnm_solver import analysis

PAGE = "docs/tutorial.md"


def prose():
    """The page with every run of white space made one space (the claims span line breaks)."""
    return " ".join((ROOT / PAGE).read_text().split())


def assert_says(text, *claims):
    for claim in claims:
        assert claim in text, f"{PAGE} should say {claim!r}"


def sci(x, digits=2):
    """1.0915e5 -> '1.09e5', the page's way of writing large energies."""
    mantissa, exponent = f"{x:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def test_tutorial_blocks_run_and_print_what_their_comments_say(tmp_path, monkeypatch):
    """Section 2 (a fresh NNM1 and NNM2, `266 orbits: done ...`) and the analysis tools on the shipped run
    (find_tongues' summaries, the points (a) (b) (c), describe_orbit, dominant_harmonic at the tip),
    checked line by line by doc_blocks; section 6's stability changes are those of section 2's branch."""
    monkeypatch.chdir(tmp_path)                      # section 2 writes fep.png
    (tmp_path / "assets").symlink_to(ROOT / "assets")
    blocks = python_blocks(PAGE)
    assert len(blocks) == 2 and "find_tongues" in blocks[1]
    ns, _ = run_blocks(PAGE, only=[0])
    fresh = ns["nnm1"]
    assert fresh.status == "done" and (tmp_path / "fep.png").stat().st_size > 10_000
    # section 6: "loses stability at 41.08 J ... lists it ... as a branch_point ... regains stability at 2747 J"
    bp = [e for e in fresh.events if e["kind"] == "branch_point"]
    lose, gain = bp[0], bp[1]
    assert fresh.stable[: lose["index"] - 1].all() and not fresh.stable[lose["index"] + 1: gain["index"] - 1].any()
    assert_says(prose(), f"NNM1 loses stability at {lose['energy']:.2f} J", "as a `branch_point`",
                f"It regains stability at {gain['energy']:.0f} J")

    ns, _ = run_blocks(PAGE, only=[1])               # the shipped run, loaded from assets/two_dof.h5
    t31 = ns["t31"]
    assert t31.label == "3:1" and ns["k"] == 3 and t31.tip == int(np.argmin(ns["nnm1"].energy[t31.start:t31.end])) + t31.start


def shipped():
    branches = nnm.load_branches(ROOT / "assets" / "two_dof.h5")
    shooting = next(b for b in branches if b.name == "NNM1")
    hb = next(b for b in branches if b.name.startswith("NNM1 harmonic balance"))
    return shooting, hb


def test_tutorial_prose_numbers_are_those_of_the_shipped_run():
    """Sections 4, 6 and 7: folds, tips, frequencies, harmonic shares, amplitudes and stability of the
    shipped NNM1 (shooting) and of its harmonic-balance check, as the page writes them."""
    b, hb = shipped()
    text = prose()
    t31, t51 = analysis.find_tongues(b)
    assert (t31.label, t51.label) == ("3:1", "5:1")
    entry, tip = t31.energy_range[1], t31.tip_energy
    folds = [e for e in b.events if e["kind"] == "fold"]
    # a located fold's index is the first point past it: the tip's own fold is at t31.tip + 1
    inner = [e["energy"] for e in folds if t31.tip + 1 < e["index"] < t31.end]  # the second fold pair
    f_in = b.frequency_hz[t31.start: t31.tip + 1]
    # section 4, the 3:1 tongue
    assert_says(text, f"entry fold at **{entry:.0f} J** ({t31.entry_frequency_hz:.4f} Hz), tip at "
                      f"**{tip:.0f} J** ({t31.tip_frequency_hz:.4f} Hz)",
                f"second fold pair at {inner[0]:.0f} J / {inner[1]:.0f} J",
                f"past the entry energy again at ~{round(b.energy[t31.end], -3):.0f} J",
                f"({f_in.min():.4f}-{f_in.max():.4f} Hz) while the energy varies by a factor of {entry / tip:.0f}",
                f"dips to {b.frequency_hz[t31.tip: t31.end + 1].min():.4f} Hz")
    # the motions (a), (b), (c): energies, amplitudes and harmonic shares
    fr = analysis.harmonic_fractions(b, 15)
    a, m, c = t31.start, t31.middle(b), t31.tip
    _, x = b.motion(a)
    peak = np.abs(x).max(axis=0)
    assert_says(text, f"(a) {b.energy[a]:.0f} J, near the backbone",
                f"(x2 = {peak[1]:.0f} m, x1 = {peak[0]:.0f} m;",
                f"The harmonic 1 carries {100 * fr[a, 1]:.0f} % of the mass-weighted amplitude, the 3rd harmonic "
                f"{100 * fr[a, 3]:.0f} %",
                f"(b) {b.energy[m]:.0f} J, in the middle",
                f"(c) {b.energy[c]:.0f} J, the tip: the 3rd harmonic carries {100 * fr[c, 3]:.0f} %")
    assert_says(text, f"about as much as the fundamental ({100 * fr[m, 3]:.0f} % and {100 * fr[m, 1]:.0f} %)")
    assert abs(fr[m, 3] - fr[m, 1]) < 0.1
    # the 5:1 tongue
    pair = [e["energy"] for e in folds if t51.tip + 1 < e["index"] < t51.end]
    assert_says(text, f"entry fold at {sci(t51.energy_range[1])} J, tip at {t51.tip_energy:.0f} J and "
                      f"{t51.tip_frequency_hz:.4f} Hz where the 5th harmonic carries {100 * t51.tip_fraction:.0f} %",
                f"fold pair at {sci(pair[0], 1)} J / {sci(pair[1], 1)} J")
    # section 6 on the shipped run: where it marks the changes, and stability along the 3:1 tongue
    marks = [e for e in b.events if e["kind"] == "branch_point"][:2]
    assert [e["stability_change"] for e in marks] == ["loss", "gain"] and all(e["located"] for e in marks)
    assert_says(text, f"locates the same two events at {marks[0]['energy']:.2f} J and {marks[1]['energy']:.0f} J")
    s = b.stable
    fold_2118, fold_1796 = [e["index"] for e in folds if t31.tip + 1 < e["index"] < t31.end]
    assert not s[t31.start: t31.tip + 1].any() and s[t31.tip + 1: fold_2118].all()
    assert not s[fold_2118: fold_1796].any() and s[fold_1796: t31.end + 1].all() and not s[t31.end + 1]
    assert_says(text, f"from the {entry:.0f} J fold down to the tip at {tip:.0f} J) is unstable",
                f"stable up to the small fold at {inner[0]:.0f} J, unstable again down to the fold at {inner[1]:.0f} J",
                f"past the entry energy up to {b.energy[t31.end]:.0f}-{b.energy[t31.end + 1]:.0f} J")
    # section 7's table, shooting against harmonic balance
    h31, h51 = analysis.find_tongues(hb)
    rows = {"3:1 entry fold": [(t31.energy_range[1], t31.entry_frequency_hz, "{:.0f}"),
                               (h31.energy_range[1], h31.entry_frequency_hz, "{:.0f}")],
            "3:1 tip": [(t31.tip_energy, t31.tip_frequency_hz, "{:.1f}"), (h31.tip_energy, h31.tip_frequency_hz, "{:.1f}")],
            "5:1 entry fold": [(t51.energy_range[1], t51.entry_frequency_hz, "sci"),
                               (h51.energy_range[1], h51.entry_frequency_hz, "sci")],
            "5:1 tip": [(t51.tip_energy, t51.tip_frequency_hz, "{:.0f}"), (h51.tip_energy, h51.tip_frequency_hz, "{:.0f}")]}
    for row, cells in rows.items():
        cols = [(sci(e) if fmt == "sci" else fmt.format(e)) + f" J, {f:.5f} Hz" for e, f, fmt in cells]
        assert_says(text, f"| {row} | {cols[0]} | {cols[1]} |")
    assert hb.settings.harmonics >= 15 and (b.settings.integrator, b.settings.steps_per_period) == ("gauss6", 200)
    assert_says(text, "| | shooting (gauss6, 200 steps / period) | harmonic balance (H = 15, raised to "
                      f"{hb.settings.harmonics} by its accuracy target) |")
