"""Exports: CSV round trips, UFF 55 shapes (and UFF 58 orbits) read back by pyuff, amplitude-frequency
backbones (peak / first harmonic) checked against the linear limit, and the nnm-solve export options."""
import csv
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver import NNMInputError
from nnm_solver.cli.solve import main as solve_main

from conftest import two_dof_model

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def beam_branch():
    spec = importlib.util.spec_from_file_location("byom", ROOT / "examples" / "bring_your_own_model.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    model, _, _ = mod.beam_model()
    return nnm.continue_nnm(model, mode=1, energy_max=1.0, max_points=15)


@pytest.fixture(scope="module")
def two_dof_branch():
    return nnm.continue_nnm(two_dof_model(), mode=1, energy_max=1.0, max_points=8)


def _read_csv(path):
    with open(path, newline="") as fh:
        rows = [r for r in fh if not r.startswith("#")]
    return list(csv.DictReader(rows))


def test_csv_round_trip(beam_branch, tmp_path):
    p = nnm.export_csv(tmp_path / "b.csv", beam_branch)
    rows = _read_csv(p)
    assert list(rows[0]) == ["energy", "frequency", "period", "stable", "label"] and len(rows) == len(beam_branch)
    for key, col in (("energy", "energy"), ("frequency", "frequency_hz"), ("period", "period")):
        assert np.array_equal([float(r[key]) for r in rows], getattr(beam_branch, col))      # exact
    assert [r["stable"] == "True" for r in rows] == list(beam_branch.stable)
    assert {r["label"] for r in rows} == {"backbone"}
    # a branch with labels (e.g. from a future classifier) labels its rows
    labelled = beam_branch.subset(slice(0, 3))
    labelled.labels = ["backbone", "3:1 tongue", "backbone"]
    assert [r["label"] for r in _read_csv(nnm.export_csv(tmp_path / "l.csv", labelled))] == labelled.labels


def test_uff55_read_back_by_pyuff_has_the_same_shapes(beam_branch, tmp_path):
    pyuff = pytest.importorskip("pyuff", reason="pyuff is the optional UFF writer (nnm[io], in the test extra)")
    model = beam_branch.model
    dm = nnm.DofMap.from_labels(model.dof_labels)
    points = [0, 7, 14]
    p = nnm.export_uff(tmp_path / "shapes.uff", beam_branch, points=points)
    sets = pyuff.UFF(str(p)).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    assert [s["type"] for s in sets] == [55] * len(points)
    for s, i in zip(sets, points):
        assert s["analysis_type"] == 2 and s["mode_n"] == i + 1 and s["freq"] == pytest.approx(
            beam_branch.frequency_hz[i], rel=1e-5)
        assert list(s["node_nums"]) == [2, 3, 4, 5, 6, 7]                # node 1 is clamped
        x0 = beam_branch.x0[i]
        scale = np.max(np.abs(x0))
        for r, d in enumerate(("ux", "uy", "uz", "rx", "ry", "rz")):
            expected = [x0[dm.index(n, d)] for n in s["node_nums"]]
            # UFF 55 stores 6 significant digits (E13.5)
            np.testing.assert_allclose(s[f"r{r + 1}"], expected, rtol=1e-5, atol=1e-9 * scale)


def test_uff_without_dof_map_and_with_mesh(two_dof_branch, tmp_path):
    pyuff = pytest.importorskip("pyuff", reason="pyuff is the optional UFF writer (nnm[io], in the test extra)")
    sets = pyuff.UFF(str(nnm.export_uff(tmp_path / "a.uff", two_dof_branch, points=3))).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    assert len(sets) == 1 and list(sets[0]["node_nums"]) == [1, 2]      # one node per DOF
    np.testing.assert_allclose(sets[0]["r1"], two_dof_branch.x0[3], rtol=1e-5)
    # with a display mesh (and no DOF map), the nodes are the mesh vertices
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    D = np.zeros((9, 2))
    D[2, 0] = D[5, 1] = 1.0
    m = nnm.Model(two_dof_branch.model.M, two_dof_branch.model.K, two_dof_branch.model.springs,
                  mesh=nnm.DisplayMesh(V, [[0, 1, 2]], D))
    b = nnm.Branch(m, 1, two_dof_branch.energy, two_dof_branch.frequency_hz, two_dof_branch.period,
                   two_dof_branch.x0, two_dof_branch.v0, settings=two_dof_branch.settings)
    s = pyuff.UFF(str(nnm.export_uff(tmp_path / "m.uff", b, points=[3]))).read_sets()
    s = s[0] if isinstance(s, list) else s
    np.testing.assert_allclose(s["r3"], [b.x0[3, 0], b.x0[3, 1], 0.0], rtol=1e-5, atol=1e-12)


def test_uff58_orbit(beam_branch, tmp_path):
    pyuff = pytest.importorskip("pyuff", reason="pyuff is the optional UFF writer (nnm[io], in the test extra)")
    dof = beam_branch.model.springs[0].dof
    p = nnm.export_uff_orbit(tmp_path / "orbit.uff", beam_branch, 10, dofs=[dof, "node 6 uz"], samples=64)
    sets = pyuff.UFF(str(p)).read_sets()
    t, x = beam_branch.motion(10, 64)
    assert [(s["rsp_node"], s["rsp_dir"]) for s in sets] == [(7, 3), (6, 3)]
    np.testing.assert_allclose(sets[0]["data"], x[:, dof], rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(sets[0]["x"], t, rtol=1e-6, atol=1e-12)


def test_amplitude_backbone_peak_and_first_harmonic(beam_branch, tmp_path):
    model = beam_branch.model
    tip = model.springs[0].dof
    f, peak = nnm.amplitude_backbone(beam_branch, tip, kind="peak")
    bb = nnm.amplitude_backbone(beam_branch, "node 7 uz", kind="harmonic1")
    assert np.array_equal(f, beam_branch.frequency_hz) and np.array_equal(bb.frequency_hz, f)
    assert np.array_equal(nnm.amplitude_backbone(beam_branch, (7, "uz")).amplitude, peak)
    # linear limit: E = omega^2 q^2 / 2 for the mass-normalised mode, amplitude phi_tip q
    f_lin, shapes = model.linear_modes()
    q = np.sqrt(2 * beam_branch.energy[0]) / (2 * np.pi * f_lin[0])
    assert peak[0] == pytest.approx(abs(shapes[tip, 0]) * q, rel=1e-3)
    assert bb.amplitude[0] == pytest.approx(peak[0], rel=1e-3)
    # a hardening backbone: amplitude and frequency grow together; peak >= harmonic 1 (odd harmonics add)
    assert np.all(np.diff(peak) > 0) and np.all(np.diff(f) > 0)
    assert np.all(peak >= bb.amplitude * (1 - 1e-9))
    # peak from a dense direct sampling of the orbit
    _, x = beam_branch.motion(14, 4096)
    assert peak[14] == pytest.approx(np.max(np.abs(x[:, tip])), rel=1e-6)
    # by mesh vertex: the two ribbon points of the tip follow node 7's uz
    v = nnm.amplitude_backbone(beam_branch, vertex=len(model.mesh.vertices) - 1, direction="z").amplitude
    np.testing.assert_allclose(v, peak, rtol=1e-12)
    nnm.export_backbone_csv(tmp_path / "bb.csv", beam_branch, tip, "harmonic1")
    rows = _read_csv(tmp_path / "bb.csv")
    assert np.array_equal([float(r["amplitude"]) for r in rows], bb.amplitude)
    with pytest.raises(NNMInputError, match="kind 'rms'"):
        nnm.amplitude_backbone(beam_branch, tip, kind="rms")
    with pytest.raises(NNMInputError, match="node 9 is not a node"):
        nnm.amplitude_backbone(beam_branch, (9, "uz"))
    with pytest.raises(NNMInputError, match="dof 99 is not a DOF"):
        nnm.amplitude_backbone(beam_branch, 99)


def test_bad_export_paths_write_nothing(beam_branch, tmp_path):
    with pytest.raises(NNMInputError, match="folder .* does not exist"):
        nnm.export_csv(tmp_path / "no" / "b.csv", beam_branch)
    with pytest.raises(NNMInputError, match="point index 99 is out of range"):
        nnm.export_uff(tmp_path / "s.uff", beam_branch, points=[0, 99])
    with pytest.raises(NNMInputError, match="expected an nnm_solver.Branch"):
        nnm.export_csv(tmp_path / "b.csv", "branch")
    assert list(tmp_path.iterdir()) == []


def test_cli_export_options_and_subcommand(beam_branch, tmp_path, capsys):
    h5 = tmp_path / "beam.h5"
    nnm.save_model(h5, beam_branch.model)
    out = {k: tmp_path / f"nnm1.{k}" for k in ("csv", "uff")}
    bb = tmp_path / "backbone.csv"
    args = [str(h5), "--mode", "1", "--energy-max", "1", "--max-points", "6", "--csv", str(out["csv"]),
            "--uff", str(out["uff"]), "--backbone", str(bb), "--backbone-dof", "node 7 uz"]
    assert solve_main(args) == 0
    text = capsys.readouterr().out
    assert "peak backbone at node 7 uz written to" in text and len(_read_csv(out["csv"])) == 6
    assert len(_read_csv(bb)) == 6 and out["uff"].stat().st_size > 0
    # exporting a stored branch
    again = tmp_path / "again.csv"
    assert solve_main(["export", str(h5), "--csv", str(again), "--backbone", str(bb), "--backbone-kind",
                       "harmonic1"]) == 0
    assert again.read_text() == out["csv"].read_text()
    # bad input: one line, exit code 2, nothing computed or written
    capsys.readouterr()
    assert solve_main([str(h5), "--mode", "1", "--energy-max", "1", "--backbone", str(tmp_path / "x.csv"),
                       "--backbone-dof", "node 99 uz"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--backbone-dof node 99 uz: node 99 is not a node" in err
    assert not (tmp_path / "x.csv").exists() and len(nnm.load_branches(h5)) == 1
    assert solve_main(["export", str(h5), "--branch", "nope", "--csv", str(tmp_path / "y.csv")]) == 2
    assert "no such branch" in capsys.readouterr().err and not (tmp_path / "y.csv").exists()
    # --branch by its 1-based number, as --tongue / --switch take it (it was 0-based here: 1 was the second branch)
    assert solve_main([str(h5), "--mode", "2", "--energy-max", "1", "--max-points", "4"]) == 0
    first, second = tmp_path / "first.csv", tmp_path / "second.csv"
    assert solve_main(["export", str(h5), "--branch", "1", "--csv", str(first)]) == 0
    assert solve_main(["export", str(h5), "--branch", "2", "--csv", str(second)]) == 0
    assert first.read_text() == out["csv"].read_text() and len(_read_csv(second)) == 4
    capsys.readouterr()
    assert solve_main(["export", str(h5), "--branch", "0", "--csv", str(tmp_path / "z.csv")]) == 2
    err = capsys.readouterr().err
    assert "1: " in err and "2: " in err and "1..2" in err and not (tmp_path / "z.csv").exists()


def test_stability_not_computed_is_exported_as_unknown(tmp_path):
    """With floquet off a point's ``stable`` is True for want of a test: the CSV and backbone exports say 'unknown'
    (they wrote True, also for the 2-DOF's points past its branch point at 40.97 J, which are unstable)."""
    model = two_dof_model()
    ref = nnm.continue_nnm(model, 1, energy_max=100.0)
    off = nnm.continue_nnm(model, 1, energy_max=100.0, floquet=False)
    assert ref.stability_known.all() and not off.stability_known.any() and (~ref.stable).sum() > 0
    for b, path in ((ref, tmp_path / "ref.csv"), (off, tmp_path / "off.csv")):
        nnm.export_csv(path, b)
    assert [r["stable"] for r in _read_csv(tmp_path / "ref.csv")] == [str(bool(s)) for s in ref.stable]
    assert {r["stable"] for r in _read_csv(tmp_path / "off.csv")} == {"unknown"}
    nnm.export_backbone_csv(tmp_path / "bb.csv", off, dof=0)
    rows = list(csv.reader(line for line in open(tmp_path / "bb.csv") if not line.startswith("#")))
    assert rows[0][3] == "stable" and {r[3] for r in rows[1:]} == {"unknown"}
