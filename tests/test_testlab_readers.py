"""Measured data in (issue 54): UFF 58 written by pyuff itself, CSV by numpy, .mat by scipy.io (v5) and hdf5storage
(v7.3), read into one Measurement in SI with labels; bad files give one line; rfs and fit_backbone take records."""
import re

import numpy as np
import pytest
import scipy.io

import nnm_solver as nnm
from nnm_solver.errors import NNMFileError, NNMInputError
from nnm_solver.files.importers.measured_units import G0, parse_unit

pyuff = pytest.importorskip("pyuff")

T = np.arange(400) / 1000.0                                  # 1 kHz, 0.4 s
A = np.sin(2 * np.pi * 25 * T) + 0.3 * np.cos(2 * np.pi * 60 * T)


def set58(data, x, **kw):
    """A complete UFF 58 data set as pyuff prepares it (a time response in g at node 14, +Z, by default)."""
    base = dict(binary=0, id1="test", id2="", id3="", id4="", id5="", func_type=1, ver_num=0, load_case_id=0,
                rsp_ent_name="x", rsp_node=14, rsp_dir=3, ref_ent_name="x", ref_node=0, ref_dir=0, ord_data_type=4,
                num_pts=len(x), abscissa_spacing=1, abscissa_min=float(x[0]), abscissa_inc=float(x[1] - x[0]),
                z_axis_value=0.0, abscissa_spec_data_type=17, abscissa_len_unit_exp=0, abscissa_force_unit_exp=0,
                abscissa_temp_unit_exp=0, abscissa_axis_units_lab="s", ordinate_spec_data_type=12,
                ordinate_len_unit_exp=1, ordinate_force_unit_exp=0, ordinate_temp_unit_exp=0,
                ordinate_axis_units_lab="g", orddenom_spec_data_type=0, orddenom_len_unit_exp=0,
                orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0, orddenom_axis_units_lab="",
                z_axis_spec_data_type=0, z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
                z_axis_axis_units_lab="", data=data, x=x)
    base.update(kw)
    return pyuff.prepare_58(**base)


def write(path, sets):
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


@pytest.mark.parametrize("text, quantity, si, factor", [
    ("g", "acceleration", "m/s^2", G0), ("mm/s^2", "acceleration", "m/s^2", 1e-3), ("in/s", "velocity", "m/s", 0.0254),
    ("mm", "displacement", "m", 1e-3), ("um", "displacement", "m", 1e-6), ("lbf", "force", "N", 4.4482216152605),
    ("kN", "force", "N", 1e3), ("g/N", "accelerance", "m/s^2/N", G0), ("(m/s^2)/N", "accelerance", "m/s^2/N", 1.0),
    ("mm/N", "receptance", "m/N", 1e-3), ("m/s/lbf", "mobility", "m/s/N", 1 / 4.4482216152605),
    ("ms", "time", "s", 1e-3), ("Hz", "frequency", "Hz", 1.0)])
def test_units_become_si(text, quantity, si, factor):
    u = parse_unit(text)
    assert (u.quantity, u.si) == (quantity, si)
    assert u.factor == pytest.approx(factor, rel=1e-12)


def test_uff58_time_series_written_by_pyuff(tmp_path):
    path = write(tmp_path / "gvt.uff", [
        pyuff.prepare_164(units_code=1, units_description="SI", temp_mode=1, length=1.0, force=1.0, temp=1.0,
                          temp_offset=273.15),
        set58(A, T),                                                        # node 14 +Z, in g
        set58(2 * A, T, rsp_node=20, rsp_dir=-3, ordinate_axis_units_lab="m/s^2"),   # node 20 -Z
        set58(5 * A, T, rsp_node=20, rsp_dir=1, ordinate_spec_data_type=13, ordinate_axis_units_lab="lbf"),
    ])
    rec = nnm.read_measured(path)
    assert rec.kind == "time" and len(rec) == len(T) and rec.sampling == pytest.approx(1000.0)
    assert rec.labels == ("node 14 uz", "node 20 uz", "node 20 ux force")
    assert rec.quantities == ("acceleration", "acceleration", "force")
    assert rec.units == ("m/s^2", "m/s^2", "N") and rec.file_units == ("g", "m/s^2", "lbf")
    assert rec.nodes == (14, 20, 20) and rec.directions == ("uz", "uz", "ux")
    np.testing.assert_allclose(rec.t, T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.channel("node 14 uz"), G0 * A, rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(rec.channel((20, "z")), -2 * A, rtol=1e-5, atol=1e-9)    # -Z flipped to +uz
    np.testing.assert_allclose(rec.channel(2), 5 * 4.4482216152605 * A, rtol=1e-5, atol=1e-9)
    assert not rec.data.flags.writeable


def test_uff58_without_labels_uses_the_data_type_and_data_set_164(tmp_path):
    """No unit label: the specific data type (8 displacement) in the file's units (164: mm, factor 1000)."""
    path = write(tmp_path / "mm.uff", [
        pyuff.prepare_164(units_code=5, units_description="mm", temp_mode=1, length=1000.0, force=1.0, temp=1.0,
                          temp_offset=273.15),
        set58(A, T, ordinate_spec_data_type=8, ordinate_axis_units_lab="")])
    rec = nnm.read_measured(path)
    assert rec.quantities == ("displacement",) and rec.units == ("m",) and "164" in rec.file_units[0]
    np.testing.assert_allclose(rec.channel(0), 1e-3 * A, rtol=1e-5, atol=1e-12)


def test_uff58_frfs_are_complex_with_their_reference(tmp_path):
    f = np.arange(1, 201) * 0.5
    h = 1.0 / (30.0 ** 2 - f ** 2 + 0.5j * f)
    path = write(tmp_path / "frf.uff", [set58(h, f, func_type=4, ord_data_type=6, abscissa_spec_data_type=18,
                                              abscissa_axis_units_lab="Hz", ordinate_axis_units_lab="g/N",
                                              orddenom_spec_data_type=13, ref_node=20, ref_dir=3)])
    rec = nnm.read_measured(path)
    assert rec.kind == "frequency" and rec.quantities == ("accelerance",) and rec.references == ("node 20 uz",)
    assert np.iscomplexobj(rec.data) and rec.sampling == pytest.approx(0.5)
    np.testing.assert_allclose(rec.frequency_hz, f)
    np.testing.assert_allclose(rec.channel("node 14 uz"), G0 * h, rtol=1e-5)


def test_write_uff58_round_trip_through_pyuff(tmp_path):
    rec = nnm.read_measured(write(tmp_path / "a.uff", [set58(A, T), set58(3 * A, T, rsp_node=20)]))
    out = nnm.write_uff58(tmp_path / "b.uff", rec)
    raw = pyuff.UFF(str(out)).read_sets()                     # read by pyuff alone: SI values with SI labels
    assert [s["type"] for s in raw] == [164, 58, 58] and raw[1]["ordinate_axis_units_lab"] == "m/s^2"
    np.testing.assert_allclose(raw[2]["data"], 3 * G0 * A, rtol=1e-5, atol=1e-9)
    back = nnm.read_measured(out)
    assert back.labels == rec.labels and back.quantities == rec.quantities
    np.testing.assert_allclose(back.data, rec.data, rtol=1e-6, atol=1e-9)


def test_csv_written_by_numpy(tmp_path):
    path = tmp_path / "run.csv"
    np.savetxt(path, np.column_stack([1e3 * T, A, 2 * A, 3 * A]), delimiter=",", comments="# shaker run 3\n",
               header="time (ms), node 14 uz (g), 20:-z [mm/s^2], force (N)")
    rec = nnm.read_measured(path)
    assert rec.labels == ("node 14 uz", "node 20 uz", "force") and rec.quantities[2] == "force"
    np.testing.assert_allclose(rec.t, T, atol=1e-12)
    np.testing.assert_allclose(rec.channel(0), G0 * A, rtol=1e-12)
    np.testing.assert_allclose(rec.channel(1), -2e-3 * A, rtol=1e-12)
    np.testing.assert_allclose(rec.channel("force"), 3 * A, rtol=1e-12)


def test_csv_backbone_and_complex_frf(tmp_path):
    path = tmp_path / "frf.csv"
    f = np.linspace(30, 40, 21)
    h = 1.0 / (35.0 ** 2 - f ** 2 + 2j * f)
    np.savetxt(path, np.column_stack([f, h.real, h.imag, 1e3 * np.abs(h)]), delimiter=";",
               header="frequency (Hz);H re (mm/N);H im (mm/N);amplitude (mm)", comments="")
    rec = nnm.read_measured(path)
    assert rec.kind == "frequency" and rec.quantities == ("receptance", "displacement")
    np.testing.assert_allclose(rec.channel("H"), 1e-3 * h, rtol=1e-12)
    np.testing.assert_allclose(rec.channel("amplitude"), np.abs(h), rtol=1e-12)


def test_mat_files_v5_and_v73(tmp_path):
    import hdf5storage

    labels = np.array(["node 14 uz", "node 20 uz"], dtype=object)
    units = np.array(["g", "mm/s^2"], dtype=object)
    scipy.io.savemat(tmp_path / "a.mat", dict(t=T, data=np.column_stack([A, 2 * A]), labels=labels, units=units))
    hdf5storage.savemat(str(tmp_path / "b.mat"), dict(t=T, data=np.column_stack([A, 2 * A]), labels=labels,
                                                      units=units), format="7.3")
    for name in ("a.mat", "b.mat"):
        rec = nnm.read_measured(tmp_path / name)
        assert rec.labels == ("node 14 uz", "node 20 uz") and rec.file_units == ("g", "mm/s^2")
        np.testing.assert_allclose(rec.channel(1), 2e-3 * A, rtol=1e-12)
    scipy.io.savemat(tmp_path / "c.mat", dict(fs=1000.0, acc_wing=A, acc_tank=2 * A, units="g"))
    rec = nnm.read_measured(tmp_path / "c.mat")
    assert rec.labels == ("acc_wing", "acc_tank") and rec.sampling == pytest.approx(1000.0)
    np.testing.assert_allclose(rec.channel("acc_tank"), 2 * G0 * A, rtol=1e-12)


def test_rfs_takes_a_record_and_its_units(tmp_path):
    """The same accelerations in g (CSV) and in m/s^2 (arrays) give the same surface."""
    from test_rfs import simulate

    t, a1, a2, _ = simulate(T=2.0)[:4]
    path = tmp_path / "conn.csv"
    np.savetxt(path, np.column_stack([t, a1 / G0, a2 / G0]), delimiter=",", header="t (s), 1 z (g), 2 z (g)",
               fmt="%.17g")
    rec = nnm.read_measured(path)
    s_rec = nnm.rfs(rec, "node 1 uz", (2, "uz"), mass=1.0)
    s_arr = nnm.rfs(t, a1, a2, mass=1.0)
    np.testing.assert_allclose(s_rec.force, s_arr.force, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(s_rec.displacement, s_arr.displacement, rtol=1e-9, atol=1e-15)
    with pytest.raises(NNMInputError, match="no channel 'node 3 uz'"):
        nnm.rfs(rec, "node 3 uz", 1, mass=1.0)


def test_fit_backbone_takes_a_measured_backbone(tmp_path):
    from test_fit_backbone import CUBIC, measured

    a, f = measured(CUBIC.scaled(1.7), 1, 12)
    path = tmp_path / "backbone.csv"
    np.savetxt(path, np.column_stack([f, 1e3 * a]), delimiter=",", header="frequency (Hz), amplitude (mm)",
               fmt="%.17g")
    fit = nnm.fit_backbone(CUBIC, 1, 1, nnm.read_measured(path))
    assert fit.k3_factor == pytest.approx(nnm.fit_backbone(CUBIC, 1, 1, a, f).k3_factor, rel=1e-9)
    assert fit.k3_factor == pytest.approx(1.7, rel=1e-4)


@pytest.mark.parametrize("name, text, message", [
    ("a.csv", "time (s), x (g)\n0, 1\n", "at least 2 data rows"),
    ("a.csv", "time (s), x (g)\n0, 1\n0.001, abc\n0.002, 1\n", "line 3: 'abc' in column 'x (g)' is not a number"),
    ("a.csv", "time (s), x (furlong)\n0, 1\n0.001, 1\n0.002, 1\n", "unit 'furlong' is not known"),
    ("a.csv", "speed (m/s), x (g)\n0, 1\n0.001, 1\n0.002, 1\n", "name it time (s) or frequency (Hz)"),
    ("a.csv", "time (s), x (g)\n0, 1\n0.001, 1\n0.001, 1\n", "time axis is not strictly increasing (sample 3)"),
    ("a.csv", "time (s), x (g), y (Hz)\n0, 1, 1\n0.001, 1, 1\n0.002, 1, 1\n", "only the first column is the axis"),
    ("a.csv", "time (s), x (g)\n0, 1\n0.001, 1, 2\n0.002, 1\n", "line 3: 3 values for 2 columns"),
    ("a.csv", "time (s), x (g)\n0, 1\n0.001, nan\n0.002, 1\n", "NaN or infinite value at sample 2"),
    ("a.uff", "this is not\na universal file\n", "no UFF data set 58"),
    ("a.mat", "not a mat file", "not a readable MATLAB"),
    ("a.xyz", "", "measured data is read from"),
])
def test_bad_files_give_one_line(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(NNMFileError, match=re.escape(message)) as err:
        nnm.read_measured(path)
    assert "\n" not in str(err.value)


def test_bad_uff_and_mat_contents(tmp_path):
    mixed = write(tmp_path / "mixed.uff", [set58(A, T), set58(A[:200], T[:200], rsp_node=20)])
    with pytest.raises(NNMFileError, match="differ from data set 1"):
        nnm.read_measured(mixed)
    assert nnm.read_measured(mixed, sets=[1]).labels == ("node 20 uz",)
    wrong = write(tmp_path / "wrong.uff", [set58(A, T, ordinate_spec_data_type=8, ordinate_axis_units_lab="g")])
    with pytest.raises(NNMFileError, match="unit label 'g' is a unit of acceleration, the data type says displacement"):
        nnm.read_measured(wrong)
    scipy.io.savemat(tmp_path / "noaxis.mat", dict(data=np.column_stack([A, A])))
    with pytest.raises(NNMFileError, match="no axis"):
        nnm.read_measured(tmp_path / "noaxis.mat")
    with pytest.raises(NNMFileError, match="no such file"):
        nnm.read_measured(tmp_path / "missing.uff")


def test_a_bad_record_writes_nothing(tmp_path):
    target = tmp_path / "out.uff"
    with pytest.raises(NNMInputError, match="needs an nnm Measurement"):
        nnm.write_uff58(target, {"t": T})
    assert not target.exists()
