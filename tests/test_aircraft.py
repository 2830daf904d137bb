"""Paris-like aircraft: a coarse build in seconds, and the shipped assets/paris.h5."""
import re
from pathlib import Path

import numpy as np
import pytest

import nnm_solver
from nnm_fem import modes
from nnm_solver import analysis
from nnm_solver.analysis import mass_mac
from nnm_solver.errors import NNMInputError
from paris_aircraft import BUILDER_VERSION, ParisParams, build_paris
from paris_aircraft.fingerprint import build_fingerprint
from paris_aircraft.labels import label_modes
from paris_aircraft.tuning import PAPER_MODE_NAMES, TABLE2_HZ

ROOT = Path(__file__).resolve().parents[1]
ASSET = ROOT / "assets" / "paris.h5"
#: builds the current builder code reproduces though their fingerprints are another code's: {the fingerprint stored
#: in the file: the fingerprint of the code that builds the same file, why}.  The fingerprint hashes the builder's
#: text, so a change that leaves its output unchanged still changes it; such a change is recorded here with the
#: new fingerprint (a later change of the builder makes that entry fail again: rebuild then, and drop the entry).
SUPERSEDED_BUILDS = {
    "1cf245047c69160de9b077677f1ebfb18b74676347320ba4499ccd8f019d8cb2": (
        "7b199335d23f0ee9efd91ebc77280191baccbfb7c5111a2b4b138c846fee6e2a",
        "issue 53: build_paris.py writes the paper's mode names (/extra/reference/mode_names), which the shipped "
        "builder-1.4 file got after its build; the test checks they are the names the builder writes"),
}


@pytest.fixture(scope="module")
def coarse():
    ac = build_paris(ParisParams(mesh=0.4))
    f, V = modes(ac.K, ac.M, 14, sigma=-1.0, xyz=ac.fe.nodes)
    return ac, f, V


def test_coarse_aircraft_mass_and_structure(coarse):
    ac, f, V = coarse
    assert ac.fe.total_mass(ac.M) == pytest.approx(1945.0, rel=0.05)
    assert len(ac.retained_nodes) == 8 and len(ac.retained_dofs) == 48
    # mirror map is an involution on the nodes that have a mirror
    m = ac.mirror
    ok = m >= 0
    assert ok.mean() > 0.97 and np.all(m[m[ok]] == np.flatnonzero(ok))
    assert np.allclose(ac.fe.nodes[m[ok], 1], -ac.fe.nodes[ok, 1], atol=1e-6)
    # wing-side and tank-side nodes of each attachment are 5 cm apart, laterally
    X = ac.fe.nodes[ac.retained_nodes].reshape(4, 2, 3)
    d = X[:, 1] - X[:, 0]
    assert np.allclose(np.abs(d[:, 1]), ac.params.tank_gap) and np.allclose(d[:, [0, 2]], 0.0)


def test_coarse_aircraft_low_modes_and_labels(coarse):
    ac, f, V = coarse
    labels, kinds = label_modes(ac, V)
    low = labels[:9]
    assert sum(lab.startswith("gear suspension") for lab in low) == 6
    assert sum("rotation" in lab for lab in low) == 3
    assert np.all(f[:9] < 4.0) and f[9] > 4.0
    assert len(labels) == len(f) and all(isinstance(s, str) and s for s in labels)


def test_shipped_model():
    assert ASSET.exists(), "assets/paris.h5 is missing: run python examples/build_paris.py"
    assert ASSET.stat().st_size <= 25e6
    model = nnm_solver.load_model(ASSET)
    assert model.n == 548
    assert len(model.springs) == 4
    for s in model.springs:
        assert s.k3 == -1e13 and s.other == s.dof + 6 and s.dof % 12 == 2
    assert len(model.mode_labels) >= 24 and len(model.dof_labels) == 548
    assert model.dof_labels[2].endswith("uz") and "wing side" in model.dof_labels[2]
    assert model.mesh.displacement_map.shape == (3 * len(model.mesh.vertices), 548)
    cb = nnm_solver.load_extra(ASSET, "craig_bampton")
    assert np.max(np.abs(cb["freq_error"])) < 2e-3
    # mass-weighted MAC (all DOFs of the full model) > 0.999 for every mode below 90 Hz separated from its
    # neighbours by more than 0.2 %, > 0.996 up to 100 Hz (builder 1.2: mode 41 at 99.4 Hz, 0.99645)
    fh = cb["full_hz"]
    gap = np.minimum(np.r_[np.inf, np.diff(fh)], np.r_[np.diff(fh), np.inf]) / fh
    assert np.min(cb["mac"][(gap > 2e-3) & (fh < 90.0)]) > 0.999
    assert np.min(cb["mac"][gap > 2e-3]) > 0.996
    # the torsion modes deform the tip-tank attachments vertically
    _, Phi = model.linear_modes()
    B = model.spring_matrix
    for mode in (19, 20):
        x = Phi[:, mode - 1]
        assert np.min(np.abs(B @ x)) > 0.1 * np.max(np.abs(x[[2, 14, 26, 38]]))
    ref = nnm_solver.load_extra(ASSET, "reference")
    assert np.allclose(ref["table2_hz"], TABLE2_HZ)


@pytest.fixture(scope="module")
def shipped():
    return nnm_solver.load_model(ASSET)


#: Table-2 modes the shipped model (builder 1.4) matches within 3 %: all 24 (worst 24 -2.87 %), see docs/aircraft.md
#: (builder 1.3: all but 13 and 24; builder 1.2: all but 11 and 13)
TABLE2_WITHIN_3 = set(range(1, 25))


def test_shipped_table2_frequencies_and_kinds(shipped):
    """The shipped model against the paper's Table 2: exactly the modes of TABLE2_WITHIN_3 within 3 %
    (builder 1.4: all 24; builder 1.3's mode 13 was -4.85 %, builder 1.2's -4.22 %), in the paper's order and, for the modes whose kind
    the paper names, of that kind: 1-9 gear suspension or control-surface rotation, 10 first symmetric
    wing bending, 13 first tail bending, 19 symmetric wing torsion, 20 anti-symmetric wing torsion."""
    f, _ = shipped.linear_modes()
    err = f[:24] / TABLE2_HZ - 1
    assert {k + 1 for k in range(24) if abs(err[k]) <= 0.03} == TABLE2_WITHIN_3
    assert np.max(np.abs(err)) < 0.05
    labels = shipped.mode_labels
    assert all(lab.startswith("gear suspension:") or re.fullmatch(r"\w+ rotation \(.*\)", lab) for lab in labels[:9])
    assert labels[9] == "wing bending 1 (symmetric)"
    assert re.fullmatch(r"(fin|horizontal tail) bending 1 \(.*\)", labels[12])
    assert not any(re.match(r"(fin|horizontal tail) bending", lab) for lab in labels[:12])
    # mode 19 is a symmetric wing torsion; the model has a first one below it (mode 18, 29.6 Hz: the wing
    # and tanks pitching, with the fuselage bending less), see docs/aircraft.md
    assert re.fullmatch(r"wing torsion \d \(symmetric\)", labels[18])
    assert labels[19] == "wing torsion 1 (anti-symmetric)"


def test_shipped_tail_torsion_near_three_times_mode_19(shipped):
    """Builders 1.2-1.4: a global symmetric tail torsion (the horizontal tail twisting and pitching on its
    fittings, most of the strain energy in the empennage) just under three times mode 19, where mode 19's
    softening backbone meets it in a 3:1 internal resonance (the seed paper's Fig. 12)."""
    f, _ = shipped.linear_modes()
    labels = shipped.mode_labels
    k = labels.index("horizontal tail torsion 1 (symmetric)")
    assert 0.994 < f[k] / (3 * f[18]) < 0.999


def test_mass_mac_of_the_aircraft_modes(shipped):
    """Craig-Bampton coordinates are not orthonormal: the raw MAC of two mass-orthogonal linear modes
    can be near 1 (builder 1.3: modes 19 and 503, 0.966; builder 1.4: modes 97 and 509, 0.996); the mass-weighted
    MAC gives 0 for distinct modes."""
    model = shipped
    _, Phi = model.linear_modes()
    U = Phi / np.linalg.norm(Phi, axis=0)
    C = np.abs(U.T @ U)
    np.fill_diagonal(C, 0.0)
    i, j = np.unravel_index(int(np.argmax(C)), C.shape)         # the two modes most alike in raw coordinates
    assert nnm_solver.mac(Phi[:, i], Phi[:, j]) > 0.9            # the misleading raw-coordinates MAC
    assert mass_mac(model, Phi[:, i], Phi[:, j]) < 1e-12
    A = mass_mac(model, Phi[:, :40], Phi[:, [18, 19, 502]])
    assert A.shape == (40, 3)
    assert np.allclose(A[:, :2], np.eye(40)[:, [18, 19]], atol=1e-12)
    # scale and sign invariant; a mass matrix works in place of the model; same as the analysis tools
    x = Phi[:, 9] + 0.3 * Phi[:, 12]
    assert mass_mac(model.M, -3.0 * x, x) == pytest.approx(1.0)
    assert mass_mac(model, x, Phi[:, 9]) == pytest.approx(1 / 1.09)
    with pytest.raises(NNMInputError):
        mass_mac(model, x[:10], x[:10])
    with pytest.raises(NNMInputError):
        mass_mac(None, x, x)


def test_shipped_model_is_the_builders_output(shipped):
    """assets/paris.h5 cannot drift from the code: the fingerprint of the builder's parameters and
    source stored at build time equals the one of the code here, and the file is consistent with itself
    (the model's matrices give the frequencies the builder recorded; springs and DOF count as built)."""
    model = shipped
    prov = nnm_solver.load_extra(ASSET, "provenance")
    n_cb = int(model.info["n_fixed_interface_modes"])
    assert n_cb == 500 and model.n == 48 + n_cb
    expected = build_fingerprint(ParisParams(), n_cb, -1e13)
    stored = model.info["builder_fingerprint"]
    assert stored == prov["builder_fingerprint"]
    assert expected in (stored, SUPERSEDED_BUILDS.get(stored, ("",))[0]), (
        "assets/paris.h5 was built from other builder code or parameters: run python examples/build_paris.py")
    if stored != expected:              # what changed since its build is in the file already
        assert nnm_solver.load_extra(ASSET, "reference")["mode_names"] == list(PAPER_MODE_NAMES)
    assert prov["builder_version"] == BUILDER_VERSION
    f, _ = model.linear_modes()
    cb = nnm_solver.load_extra(ASSET, "craig_bampton")
    # eigenvalues (Hz^2) to round-off relative to the largest: the near-rigid suspension modes (0.09 Hz) move by
    # ~4e-7 relative between one and two BLAS threads
    f2, ref2 = f[cb["pair"]] ** 2, np.asarray(cb["reduced_hz"]) ** 2
    assert np.allclose(f2, ref2, rtol=1e-9, atol=1e-11 * ref2.max())
    assert np.allclose(np.sqrt(np.asarray(model.K.diagonal())[48:]) / (2 * np.pi), cb["fixed_interface_hz"], rtol=1e-9)
    assert [(s.dof, s.other, s.k3) for s in model.springs] == [(2, 8, -1e13), (14, 20, -1e13), (26, 32, -1e13),
                                                               (38, 44, -1e13)]


def test_superseded_build_entries_name_a_fingerprint_and_why():
    for old, (new, why) in SUPERSEDED_BUILDS.items():
        assert re.fullmatch("[0-9a-f]{64}", old) and re.fullmatch("[0-9a-f]{64}", new) and old != new and why


@pytest.mark.slow
def test_a_rebuild_writes_the_papers_mode_names_and_its_fingerprint(tmp_path):
    """Issue 53: examples/build_paris.py writes /extra/reference/mode_names (the paper's names, as the shipped file
    has them) and the fingerprint of its code and parameters (a small coarse build, ~30 s)."""
    import subprocess
    import sys

    out = tmp_path / "paris_coarse.h5"
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "build_paris.py"), "--coarse", "--cb-modes", "20",
                          "--fmax", "40", "--out", str(out)], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    ref = nnm_solver.load_extra(out, "reference")
    assert ref["mode_names"] == list(PAPER_MODE_NAMES) == nnm_solver.load_extra(ASSET, "reference")["mode_names"]
    assert np.array_equal(ref["table2_hz"], TABLE2_HZ) and ref["source"] == "seed paper Table 2"
    model = nnm_solver.load_model(out)
    assert model.n == 48 + 20
    assert model.info["builder_fingerprint"] == build_fingerprint(ParisParams(mesh=0.5), 20, -1e13)


def test_shipped_branches_each_tongue_once(shipped):
    """assets/paris.h5 carries the skip backbones of paper modes 10, 13, 19, 20 (model modes of the same
    numbers, builder 1.4) and each tongue they passed once, as its own branch named after its backbone
    (examples/paris_fep.py), computed with the solver's defaults (gauss6 at 100 steps per period, the accuracy
    target freq_tol = 1e-4 raising the steps where needed): estimated frequency errors below the target on every
    branch (largest in the shipped, thinned file: mode 20's 3:1 tongue branch, 2.8e-5; the gauss6-200 branches
    shipped before: 4.1e-4; the Newmark-200 ones before those: 0.56-5.1 %)."""
    branches = nnm_solver.load_branches(ASSET, shipped)
    for b in branches:
        assert (b.settings.integrator, b.settings.steps_per_period, b.settings.freq_tol) == ("gauss6", 100, 1e-4)
        assert np.isfinite(b.freq_error).all() and b.freq_error.max() < 1e-4, b.name
    backbones = {b.name: b for b in branches if ": tongue" not in b.name}
    assert set(backbones) == {"mode10", "mode13", "mode19", "mode20"}
    seen = {}
    for b in branches:
        if b.name in backbones:
            continue
        parent, rest = b.name.split(": tongue ")
        i, ratio = int(rest.split()[0]) - 1, rest.split()[1].strip("()")
        record = backbones[parent].tongues[i]
        assert record["label"] == f"tongue {ratio}"
        key = (parent, ratio, record["partner_mode"])
        for lo, hi in seen.get(key, []):          # no second branch over the same stretch of the same tongue
            assert b.energy.max() < lo or b.energy.min() > hi
        seen.setdefault(key, []).append((b.energy.min(), b.energy.max()))
    drop = {name: 1 - b.frequency_hz[np.argmax(b.energy)] / b.frequency_hz[0] for name, b in backbones.items()}
    # the backbones past their tongues (issue 29): none failed; each ends where its family ends (status
    # 'tongue') or at energy_max; builder 1.3 (issue 31): mode 20 follows its family to >= 4 % on points
    # labelled backbone, mode 13 stays within 1 %
    for name, b in backbones.items():
        assert b.status in ("done", "tongue", "escape"), (name, b.status, b.message)
        assert set(b.labels) == {"backbone"}, name
    assert drop["mode20"] > 0.04 and drop["mode19"] > 0.01 and drop["mode10"] > 0.005 and abs(drop["mode13"]) < 0.01
    # shapes (mass-weighted MAC of the orbit shapes at the lowest and highest energy, as paris_fep.py reports them):
    # mode 10 weakly changed (>= 0.98, paper 0.99), mode 13 practically unchanged, mode 20 0.96 (paper 0.97)
    mac = {name: analysis.mac_orbits(b, 0, b, int(np.argmax(b.energy))) for name, b in backbones.items()}
    assert mac["mode10"] >= 0.98 and mac["mode13"] >= 0.98 and mac["mode20"] > 0.9 and mac["mode19"] > 0.9
    # builder 1.4: mode 19 meets the 3:1 with the symmetric tail torsion (mode 39; the seed paper's Fig. 12) and ends
    # in it where its family ends in a 1:1 resonance with mode 18 (the skeleton's probe past its fold, on the
    # continuation engine since 2026-12-07: the energy folds and recovers as mode 18 grows); mode 20 jumps the 3:1 with
    # mode 42 (the second anti-symmetric wing torsion) and its family ends in that 3:1; mode 10's family ends at its
    # energy maximum (a family_end record, no tongue branch), the record naming the resonance nearest its end
    # frequency: the partner's linear frequency within 5 % of the order times it (the 7:1 with mode 29 since
    # 2026-12-07; the narrower tongues a skip run records, e.g. the 9:1 with mode 260 of the branches shipped
    # before, depend on where its steps fall and are not asserted); mode 13 meets none up to 11.3 J
    assert ("mode19", "3:1", 39) in seen
    assert backbones["mode19"].status == "tongue" and backbones["mode20"].status == "tongue"
    assert "1:1 internal resonance with mode 18" in backbones["mode19"].message
    end10 = backbones["mode10"].tongues[-1]
    assert backbones["mode10"].status == "escape" and end10["family_end"]
    f_lin = np.sqrt(np.maximum(shipped.eigensolution[0], 0.0)) / (2 * np.pi)
    ratio = f_lin[end10["partner_mode"] - 1] / (end10["order"] * end10["entry_frequency_hz"])
    assert abs(ratio - 1) < 0.05, (end10["order"], end10["partner_mode"], ratio)
    assert ("mode20", "3:1", 42) in seen and backbones["mode20"].tongues[-1]["partner_mode"] == 42
    # along the 3:1 tongue of mode 19 the motion turns towards the tail torsion (its third harmonic grows to
    # most of the amplitude in builder 1.4, about half in 1.3), and the tongue comes back onto the backbone (1.4: above
    # its entry; 1.3: a loop closing below it), where continue_tongue stops instead of retracing the backbone
    tb = next(b for b in branches if b.name.startswith("mode19: tongue") and "(3:1)" in b.name)
    entry = next(t for t in backbones["mode19"].tongues if t["label"] == "tongue 3:1")
    assert tb.energy.max() > 20.0 and tb.energy.min() > 0.5 * entry["entry_energy"]
    assert "closes back onto the backbone" in tb.message or "back on the backbone" in tb.message, tb.message
    share = analysis.harmonic_fractions(tb, 4)[:, 3]
    assert share[0] < 0.1 and np.nanmax(share) > 0.4
    assert shipped.mode_labels[38] == "horizontal tail torsion 1 (symmetric)"


def test_attachment_shares_and_partner_band_penalty(coarse):
    """Builder 1.3's tuning quantities (paris_aircraft.tuning_nonlinear).  attachment_shares, att_kz sum d^2 / w^2,
    is att_kz times the first-order sensitivity of ln w^2 to a linear spring added on each attachment's relative
    vertical displacement d (what the cubic springs see): checked against the eigenvalues of the model with such
    springs of 1e3 N/m.  The band penalty counts only coupled anti-symmetric modes just under n f."""
    import scipy.sparse as sp
    from paris_aircraft.tuning_nonlinear import attachment_deformations, attachment_shares, partner_band_penalty
    ac, f, V = coarse
    share = attachment_shares(ac, f, V)
    d = attachment_deformations(ac, V)
    assert d.shape == (4, V.shape[1])
    r, n, dk = ac.retained_dofs, ac.K.shape[0], 1e3
    rows = []
    for a in range(4):
        e = np.zeros(n)
        e[r[6 * (2 * a) + 2]], e[r[6 * (2 * a + 1) + 2]] = 1.0, -1.0
        rows.append(e)
    B = sp.csr_matrix(np.array(rows))
    f2, V2 = modes(ac.K + dk * (B.T @ B), ac.M, len(f), sigma=-1.0, xyz=ac.fe.nodes)
    el = np.flatnonzero(f > 4.0)                            # the structural modes (not the suspension ones)
    w2, w2b = (2 * np.pi * f[el]) ** 2, (2 * np.pi * f2[el]) ** 2
    fd = ac.params.att_kz * (w2b - w2) / (dk * w2)
    big = share[el] > 1e-3
    assert big.sum() >= 2 and np.allclose(fd[big], share[el][big], rtol=2e-2)
    labels = ["x (anti-symmetric)", "y (symmetric)", "z (anti-symmetric)"]
    assert partner_band_penalty([98.0, 98.0, 120.0], labels, [1e-2, 1e-2, 1e-2], 34.0) == pytest.approx(
        np.log(98.0 / (3 * 34.0 * 0.945)))                # only the first: anti-symmetric, coupled, in the band
    assert partner_band_penalty([98.0], labels[:1], [1e-3], 34.0) == 0.0      # not coupled
    assert partner_band_penalty([103.0], labels[:1], [1e-2], 34.0) == 0.0     # above 3 f: never met by a softening backbone


def test_tutorial_aircraft_numbers_are_the_shipped_ones(shipped):
    """docs/tutorial.md section 8 quotes the shipped backbones (drops, mode 13's last energy, the 3:1 entry of
    mode 19 and the tail torsion's frequency): each number, recomputed from assets/paris.h5, is in the text."""
    text = " ".join((Path(__file__).resolve().parents[1] / "docs" / "tutorial.md").read_text().split())
    branches = {b.name: b for b in nnm_solver.load_branches(ASSET, shipped)}
    drop = {m: 100 * (1 - branches[f"mode{m}"].frequency_hz[-1] / branches[f"mode{m}"].frequency_hz[0])
            for m in (10, 13, 19, 20)}
    assert f"-{drop[13]:.2f} % at {branches['mode13'].energy.max():.1f} J" in text
    assert f"softens by {drop[10]:.2f} %" in text and f"by {drop[19]:.2f} %" in text and f"({drop[20]:.2f} %)" in text
    entry = next(t for t in branches["mode19"].tongues if t["label"] == "tongue 3:1")
    f19 = shipped.linear_modes()[0][18]
    assert (f"meets at {entry['entry_energy']:.2f} J ({100 * (entry['entry_frequency_hz'] / f19 - 1):.2f} %)"
            in text)
    assert f"model mode 39, {shipped.linear_modes()[0][38]:.1f} Hz" in text


@pytest.mark.slow
def test_backbone_check_follows_a_softening_backbone_of_the_full_fe_model():
    """tuning_nonlinear.backbone_check (the tuning tool of builder 1.3): the condensed HB backbone of the full
    (here coarse, 17,514-DOF) FE model with the four springs; mode 20 softens (k3 < 0) from its linear frequency.
    At H = 1 (no higher harmonic: no k:1 resonance with k >= 2) its family ends at 4.64 J, 32.8 Hz, where its
    energy folds and recovers as mode 18's motion at the same frequency grows (a 1:1 resonance, the next test):
    status 'tongue', one record, 'tongue 1:1' with mode 18, the family's end."""
    from paris_aircraft.tuning_nonlinear import backbone_check
    (out,) = backbone_check(ParisParams(mesh=0.4), modes=(20,), harmonics=1, energy_max=5.0)
    assert out["mode"] == 20 and out["points"] > 10
    assert out["status"] == "tongue" and 0.02 < out["drop"] < 0.5 and out["energy_at_drop"] > 0
    assert [t[:2] for t in out["tongues"]] == [("tongue 1:1", 18)], out["tongues"]


@pytest.mark.slow
def test_single_harmonic_skeleton_of_the_full_fe_model_ends_in_a_one_to_one_resonance_without_jumping():
    """The coarse FE model's mode 20 at H = 1: stepping in the modal amplitude finds no solution above
    a ~ 0.01413 sqrt(kg) m (4.64 J).  Followed past that fold by arclength (amplitude_family._past_fold) the family's
    energy falls 4 % and comes back above it while mode 18's fundamental grows: a 1:1 resonance with mode 18, not
    the family's energy maximum (an escape).  The skeleton ends 'locked' there with partner (1, 18) and no jump: a 2 %
    jump in a used to land on another family (31.9 Hz) and carry the skeleton, and the branch after it, above.
    Checked against the branch's own pseudo-arclength continuation (tongues='follow') through the same fold: its
    energy reaches the skeleton's end, turns back, then rises above it, and its points past the fold are labelled
    'tongue 1:1' (no harmonic k >= 2 exists at H = 1: never a 3:1)."""
    from nnm_solver.driver.api import _skeleton_system
    from nnm_solver.backbone.skeleton import skeleton
    from paris_aircraft.builder import build_paris
    ac = build_paris(ParisParams(mesh=0.4))
    r = ac.retained_dofs
    springs = [nnm_solver.CubicSpring(dof=int(r[12 * a + 2]), other=int(r[12 * a + 8]), k3=-1e13) for a in range(4)]
    model = nnm_solver.Model(ac.M.tocsr(), ac.K.tocsr(), springs, name="coarse aircraft")
    sk = skeleton(model, 20, 5.0, _skeleton_system, 1)
    assert sk.end == "locked" and sk.partner == (1, 18) and sk.gaps == [] and sk.energy_peak is None, sk.message
    b = nnm_solver.continue_nnm(model, 20, 5.0, method="hb", harmonics=1, condensed=True, floquet=False,
                                tongues="follow")
    E = np.asarray(b.energy)
    i = int(np.argmax(E > sk.energy[-1] * (1 - 2e-3)))         # the first point at the fold
    assert i > 10 and E[i:].min() < E[i] * 0.99 and E[-1] > E[i]  # turns back, then rises above it
    assert set(b.labels[:i]) == {"backbone"} and set(b.labels[i + 1:]) == {"tongue 1:1"}, set(b.labels)
def test_minimax_step_of_the_table2_round():
    """tuning_table2.minimax_step on a synthetic linear spectrum whose minimax is known: slot 13 5 % low and one
    parameter that raises it one for one; the step stops at x_max (t = the rest), and a label-margin constraint that
    the same parameter erodes binds before it."""
    from paris_aircraft.tuning_table2 import minimax_step
    n_f = 46
    q0 = np.log(np.r_[TABLE2_HZ, np.full(n_f - 24, 200.0)])
    q0[19] = np.log(35.5)
    q0[23:27] = np.log(TABLE2_HZ[23] * np.array([1.0, 1.01, 1.02, 1.03]))
    q0[39:42] = np.log(0.9 * 3 * 35.5)
    q0[12] -= 0.05
    q0 = np.r_[q0, 0.05, np.log(0.12), np.log(0.33)]          # label margin, shares of slots 19 and 20
    J = np.zeros((len(q0), 2))
    J[12, 0] = 1.0
    x, t, pred = minimax_step(q0, J, x_max=0.03)
    assert x[0] == pytest.approx(0.03) and t == pytest.approx(0.02) and abs(x[1]) < 1e-9
    assert pred[12] == pytest.approx(np.log(TABLE2_HZ[12]) - 0.02)
    J[n_f, 0] = -1.0                                            # the step erodes slot 13's label margin
    x, t, _ = minimax_step(q0, J, x_max=0.1, label_margin=0.03)
    assert x[0] == pytest.approx(0.02) and t == pytest.approx(0.03)
    x, t, _ = minimax_step(q0, J, x_max=0.1, only_up=(0,), label_margin=0.03)
    assert x[0] >= 0.0
    J[12, 0] = -1.0                                             # only_up: a parameter that would have to fall
    x, t, _ = minimax_step(q0, J, x_max=0.1, only_up=(0,))
    assert x[0] == pytest.approx(0.0, abs=1e-12) and t == pytest.approx(0.05)
