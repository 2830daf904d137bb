"""Importers: the same beam (nnm_fem cantilever + tip cubic spring) written in every format by
examples/bring_your_own_model.py and imported back gives the HDF5 original's linear frequencies and
NNM backbone; MATLAB v7.3 (dense and sparse), units, display meshes, DOF maps, ANSYS .full; bad
input gives one line naming the file (and line / table), exit code 2 and writes nothing."""
import importlib.util
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.linalg
import scipy.sparse as sp

import nnm_solver as nnm
from nnm_solver import NNMFileError, NNMInputError
from nnm_solver.cli.solve import main as solve_main
from nnm_solver.files.importers.ansys import reader_available

ROOT = Path(__file__).resolve().parents[1]
MAX_POINTS = 15
ENERGY_MAX = 1.0


def _example():
    spec = importlib.util.spec_from_file_location("byom", ROOT / "examples" / "bring_your_own_model.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _dense(A):
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def write_v73_sparse(path, variables):
    """A MATLAB v7.3 file laid out as MATLAB writes it (512-byte header block; arrays transposed;
    sparse matrices as groups data / ir / jc with attribute MATLAB_sparse = rows)."""
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, A in variables.items():
            if sp.issparse(A):
                A = sp.csc_matrix(A)
                A.sort_indices()
                g = f.create_group(name)
                g.attrs["MATLAB_class"] = np.bytes_("double")
                g.attrs["MATLAB_sparse"] = np.uint64(A.shape[0])
                g.create_dataset("data", data=A.data)
                g.create_dataset("ir", data=A.indices.astype(np.uint64))
                g.create_dataset("jc", data=A.indptr.astype(np.uint64))
            else:
                d = f.create_dataset(name, data=np.asarray(A, dtype=float).T)
                d.attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as fh:
        head = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 ."
        fh.write(head.ljust(116) + b"\x00" * 8 + b"\x00\x02" + b"IM")


@pytest.fixture(scope="module")
def beam_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("byom")
    files = _example().write_all(folder)
    ref = nnm.load_model(files["h5"])
    tip = ref.springs[0].dof
    # MATLAB v7.3: sparse matrices laid out as MATLAB does; dense through hdf5storage (an independent writer)
    files["matlab_v73_sparse"] = folder / "beam_v73_sparse.mat"
    write_v73_sparse(files["matlab_v73_sparse"], {"M": ref.M, "K": ref.K, "springs": np.array([[tip + 1, 0, 1e9]])})
    try:
        import hdf5storage
    except ImportError:
        hdf5storage = None
    if hdf5storage is not None:
        files["matlab_v73_dense"] = folder / "beam_v73_dense.mat"
        hdf5storage.savemat(str(files["matlab_v73_dense"]),
                            {"M": _dense(ref.M), "K": _dense(ref.K), "springs": np.array([[tip + 1.0, 0.0, 1e9]]),
                             "dof_labels": np.array(ref.dof_labels, dtype=object)},
                            format="7.3", matlab_compatible=True)
    return files


@pytest.fixture(scope="module")
def reference(beam_files):
    model = nnm.load_model(beam_files["h5"])
    return model, nnm.continue_nnm(model, mode=1, energy_max=ENERGY_MAX, max_points=MAX_POINTS)


ROUTES = ["matrixmarket", "abaqus", "matlab", "matlab_v73_sparse", "matlab_v73_dense"]


@pytest.mark.parametrize("route", ROUTES)
def test_route_gives_the_same_frequencies_and_backbone(route, beam_files, reference):
    if route not in beam_files:
        pytest.skip("hdf5storage (the independent MATLAB v7.3 writer, in the test extra) is not installed")
    ref, ref_branch = reference
    model = nnm.load_model(beam_files[route])
    assert model.n == ref.n and len(model.springs) == 1
    assert model.springs[0].dof == ref.springs[0].dof and model.springs[0].k3 == pytest.approx(1e9, rel=1e-15)
    f_ref, _ = ref.linear_modes()
    f, _ = model.linear_modes()
    assert np.max(np.abs(f / f_ref - 1)) <= 1e-10
    branch = nnm.continue_nnm(model, mode=1, energy_max=ENERGY_MAX, max_points=MAX_POINTS)
    assert len(branch) == len(ref_branch) == MAX_POINTS
    np.testing.assert_allclose(branch.frequency_hz, ref_branch.frequency_hz, rtol=1e-9)
    np.testing.assert_allclose(branch.energy, ref_branch.energy, rtol=1e-8)
    assert branch.frequency_hz[-1] > branch.frequency_hz[0] * 1.02          # the spring hardens the mode


def test_description_routes_keep_dof_map_and_display_mesh(beam_files, reference):
    ref, _ = reference
    for route in ("matrixmarket", "abaqus"):
        model = nnm.load_model(beam_files[route])
        assert model.dof_labels == ref.dof_labels                           # 'node 2 ux' ... 'node 7 rz'
        assert model.mesh is not None and model.info["format"] == route
        np.testing.assert_allclose(model.mesh.vertices, ref.mesh.vertices, atol=1e-7)   # h5 keeps float32
        np.testing.assert_array_equal(model.mesh.displacement_map, ref.mesh.displacement_map)
        # the clamped node 1 (two ribbon points) stays still; the tip follows node 7
        x = np.zeros(ref.n)
        x[nnm.DofMap.from_labels(model.dof_labels).index(7, "uz")] = 1e-3
        u = model.mesh.displacements(x)
        assert np.all(u[:2] == 0) and np.allclose(u[-2:, 2], 1e-3)
    dm = nnm.DofMap.from_labels(ref.dof_labels)
    assert dm.index(7, "uz") == ref.springs[0].dof and len(dm.nodes) == 6


def test_units_mm_t_s_convert_to_si(beam_files, reference):
    ref, ref_branch = reference
    model = nnm.load_model(beam_files["abaqus_mm"])
    assert model.info["units"] == "mm-t-s"
    for A, B in ((model.M, ref.M), (model.K, ref.K)):
        assert np.max(np.abs(_dense(A) - _dense(B))) <= 1e-14 * np.max(np.abs(_dense(B)))
    assert model.springs[0].k3 == pytest.approx(1e9, rel=1e-14)
    np.testing.assert_allclose(model.mesh.vertices, ref.mesh.vertices, atol=1e-7)
    np.testing.assert_allclose(model.mesh.displacement_map, ref.mesh.displacement_map, rtol=1e-14, atol=1e-14)
    # 1e-16 perturbations of the entries move this beam's lowest eigenvalue by ~1e-10 relative
    # (dense eigh, lambda_max / lambda_1 ~ 2e6), so the frequencies agree to 1e-9 here
    f_ref, _ = ref.linear_modes()
    f, _ = model.linear_modes()
    assert np.max(np.abs(f / f_ref - 1)) <= 1e-9
    branch = nnm.continue_nnm(model, mode=1, energy_max=ENERGY_MAX, max_points=MAX_POINTS)
    np.testing.assert_allclose(branch.frequency_hz, ref_branch.frequency_hz, rtol=1e-8)


def test_import_command_writes_a_complete_file(beam_files, tmp_path, reference, capsys):
    ref, _ = reference
    out = tmp_path / "imported.h5"
    assert solve_main(["import", str(beam_files["matrixmarket"]), "--out", str(out)]) == 0
    assert "36 DOFs, 1 spring(s), a display mesh of 14 points" in capsys.readouterr().out
    m = nnm.load_model(out)
    assert m.dof_labels == ref.dof_labels and m.springs == ref.springs and m.mesh is not None
    assert nnm.load_branches(beam_files["matrixmarket"]) == []              # descriptions hold no branches
    assert nnm.load_extra(out, "provenance")["format"] == "matrixmarket"
    # solving an imported model saves next to it in HDF5, never into the description
    with pytest.raises(NNMInputError, match="not an nnm HDF5 file"):
        nnm.save_branch(beam_files["matrixmarket"], nnm.continue_nnm(m, 1, 1e-6, max_points=2))


def test_viewer_loads_and_animates_a_matrixmarket_model_with_a_gmsh_mesh(beam_files, reference):
    """nnm-view FILE.toml: the viewer's loader takes the description (no branches yet) and the orbit
    animation moves the Gmsh ribbon (the browser check of docs/byom.md is manual)."""
    pytest.importorskip("viser", reason="the viewer's dependencies are not installed")
    from nnm_viewer.animation import orbit_animation
    from nnm_viewer.app import load
    from nnm_viewer.glb import read_glb_json

    model, branches = load(str(beam_files["matrixmarket"]))
    assert branches == [] and model.mesh is not None and len(model.mesh.faces) == 12
    _, ref_branch = reference
    t, x = ref_branch.motion(MAX_POINTS - 1, 64)
    anim = orbit_animation(model.mesh.vertices, model.mesh.faces, model.mesh.displacements, t, x,
                           ref_branch.period[-1])
    tip_peak = np.max(np.abs(x[:, ref_branch.model.springs[0].dof]))
    assert anim.peak_max == pytest.approx(tip_peak, rel=1e-2)      # the tip ribbon points move the most
    assert anim.peak[0] == anim.peak[1] == 0.0                       # the clamped end does not move
    assert "animations" in read_glb_json(anim.glb(10.0, display_period=2.0))


def _description(folder, text, files=("beam_M.mtx", "beam_K.mtx", "beam_dofs.txt", "beam.msh"), src=None):
    for f in files:
        if src is not None:
            shutil.copy(src / f, folder / f)
    p = folder / "model.toml"
    p.write_text(text)
    return p


MTX = '[matrices]\nmass = "beam_M.mtx"\nstiffness = "beam_K.mtx"\n'


def test_springs_by_index_by_node_relative_and_typed(beam_files, tmp_path, reference):
    ref, _ = reference
    src = beam_files["h5"].parent
    p = _description(tmp_path, MTX + 'dof_map = "beam_dofs.txt"\n'
                     '[[springs]]\ndof = 32\nk3 = 2.0\n'
                     '[[springs]]\ntype = "cubic"\nnode = 7\ndirection = "UZ"\nother_node = 6\nk3 = -3.0\n'
                     '[[springs]]\nnode = 7\ndirection = "ry"\nother = 5\nk3 = 4.0\n'
                     '[[springs]]\ntype = "polynomial"\ndof = 30\ncoefficients = {2 = 5.0, 3 = 6.0}\n', src=src)
    m = nnm.load_model(p)
    dm = nnm.DofMap.from_labels(m.dof_labels)
    assert m.springs == [nnm.CubicSpring(dof=32, k3=2.0),
                         nnm.CubicSpring(dof=dm.index(7, "uz"), other=dm.index(6, "uz"), k3=-3.0),
                         nnm.CubicSpring(dof=dm.index(7, "ry"), other=5, k3=4.0),
                         nnm.PolynomialSpring(dof=30, coefficients={2: 5.0, 3: 6.0})]
    # in mm-t-s a coefficient of d^p is in N/mm^p: x 1e3^p in SI
    (tmp_path / "mm.toml").write_text('units = "mm-t-s"\n' + MTX + '[[springs]]\ntype = "polynomial"\ndof = 30\n'
                                      'coefficients = {2 = 1.0, 3 = 1.0}\n')
    law = nnm.load_model(tmp_path / "mm.toml").springs[0].law()
    assert law[2] == pytest.approx(1e6, rel=1e-14) and law[3] == pytest.approx(1e9, rel=1e-14)


BAD_DESCRIPTIONS = [
    # (description text, files copied, fragments of the one-line message)
    ('[matrices]\nmass = "missing_M.mtx"\nstiffness = "beam_K.mtx"\n', ["missing_M.mtx", "no such file", "mass"]),
    (MTX + '[[springs]]\nnode = 7\ndirection = "uz"\nk3 = 1.0\n', ["[[springs]] #1", "need a DOF map"]),
    (MTX + 'dof_map = "beam_dofs.txt"\n[[springs]]\nnode = 99\ndirection = "uz"\nk3 = 1.0\n',
     ["[[springs]] #1", "node 99 is not a node"]),
    (MTX + '[[springs]]\ndof = 36\nk3 = 1.0\n', ["[[springs]] #1", "dof = 36 is not a DOF", "0..35"]),
    (MTX + 'dof_map = "beam_dofs.txt"\n[[springs]]\nnode = 1\ndirection = "uz"\nk3 = 1.0\n',
     ["node 1 is not a node"]),
    (MTX + '[[springs]]\ndof = 3\ntype = "quintic"\nk5 = 1.0\n', ["unknown type 'quintic'", "known: cubic, polynomial"]),
    (MTX + '[[springs]]\ndof = 3\ntype = "polynomial"\ncoefficients = {1 = 2.0}\n', ["power '1' is not an integer >= 2"]),
    (MTX + '[[springs]]\ndof = 3\nk3 = "stiff"\n', ["k3 = 'stiff' is not a number"]),
    (MTX + '[[springs]]\ndof = 3\nk3 = 1.0\nk4 = 2.0\n', ["unknown key(s) k4"]),
    ('units = "furlong-firkin-fortnight"\n' + MTX, ["unknown units", "mm-t-s"]),
    ('units = {length = "furlong"}\n' + MTX, ["unknown length unit 'furlong'"]),
    (MTX + '[mesh]\nfile = "beam.msh"\n', ["cannot tell which DOFs move the 14 points"]),
    ('name = "x"\n[matrix]\nmass = "a"\n', ["unknown key(s) matrix"]),
    ('[matrices\nmass = 1\n', ["not valid TOML"]),
]


@pytest.mark.parametrize("text,fragments", BAD_DESCRIPTIONS)
def test_bad_descriptions_give_one_line_naming_the_file(text, fragments, beam_files, tmp_path):
    p = _description(tmp_path, text, src=beam_files["h5"].parent)
    with pytest.raises(NNMInputError) as exc:
        nnm.load_model(p)
    msg = str(exc.value)
    assert "\n" not in msg and str(p) in msg or "missing_M.mtx" in msg, msg
    for frag in fragments:
        assert frag in msg, msg


def _mtx(path, A):
    scipy.io.mmwrite(path, sp.coo_matrix(A), precision=17)


@pytest.mark.parametrize("case", ["size", "nonsymmetric", "indefinite", "abaqus_line", "not_mtx"])
def test_bad_matrices_exit_2_and_write_nothing(case, tmp_path, capsys):
    M, K = np.eye(3), np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    fmt = 'format = "matrixmarket"\n'
    if case == "size":
        _mtx(tmp_path / "M.mtx", np.eye(4))
        expect = "M.mtx is 4x4 but"
    elif case == "nonsymmetric":
        M = M.copy()
        M[0, 1] = 0.5
        _mtx(tmp_path / "M.mtx", M)
        expect = "M is not symmetric"
    elif case == "indefinite":
        _mtx(tmp_path / "M.mtx", np.diag([1.0, -1.0, 1.0]))
        expect = "M is not positive definite"
    elif case == "abaqus_line":
        (tmp_path / "M.mtx").write_text("** abaqus\n1,1, 1,1, 1.0\n1,2, 1,2\n")
        fmt = 'format = "abaqus"\n'
        expect = "M.mtx line 3: expected"
    else:
        (tmp_path / "M.mtx").write_text("%%MatrixMarket matrix coordinate real general\n3 3 1\n1 1 x\n")
        expect = "M.mtx: not a readable MatrixMarket file"
    if not (tmp_path / "M.mtx").exists():
        _mtx(tmp_path / "M.mtx", M)
    if case == "abaqus_line":
        (tmp_path / "K.mtx").write_text("1,1, 1,1, 2.0\n")
    else:
        _mtx(tmp_path / "K.mtx", K)
    p = tmp_path / "m.toml"
    p.write_text(f'[matrices]\n{fmt}mass = "M.mtx"\nstiffness = "K.mtx"\n')
    out = tmp_path / "out.h5"
    assert solve_main(["import", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert expect in err and err.count("\n") == 1, err
    assert not out.exists() and not list(tmp_path.glob(".out.h5*"))
    capsys.readouterr()
    assert solve_main([str(p), "--mode", "1", "--energy-max", "1"]) == 2
    assert expect in capsys.readouterr().err and not (tmp_path / "m.h5").exists()


def test_matlab_errors_name_row_and_variable(tmp_path):
    p = tmp_path / "m.mat"
    scipy.io.savemat(p, {"M": np.eye(2), "K": np.eye(2), "springs": np.array([[1, 0, 0.5], [3, 0, 1.0]])})
    with pytest.raises(NNMFileError, match=r"m\.mat: springs row 2: dof 3 is not a DOF of the model \(1\.\.2"):
        nnm.load_model(p)
    write_v73_sparse(tmp_path / "v73.mat", {"M": sp.identity(2, format="csc"), "K": np.eye(3)})
    with pytest.raises(NNMFileError, match=r"v73\.mat: M is 2x2 but K is 3x3"):
        nnm.load_model(tmp_path / "v73.mat")
    assert nnm.load_mat_model is nnm.importers.matlab.load_mat_model
    from nnm_solver.matio import load_mat_model                      # the old import path still works
    assert load_mat_model is nnm.load_mat_model


def test_abaqus_coordinate_format_and_triangles(tmp_path):
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    (tmp_path / "K.mtx").write_text("".join(f"{i + 1},{j + 1}, {float(K[i, j])!r}\n" for i in range(3) for j in range(i + 1)))
    (tmp_path / "M.mtx").write_text("".join(f"{i + 1} {i + 1} 1.0D+00\n" for i in range(3)))   # Fortran exponent
    p = tmp_path / "m.toml"
    p.write_text('[matrices]\nformat = "abaqus"\nmass = "M.mtx"\nstiffness = "K.mtx"\n[[springs]]\ndof = 0\nk3 = 1.0\n')
    m = nnm.load_model(p)
    assert np.array_equal(_dense(m.K), K) and np.array_equal(_dense(m.M), np.eye(3)) and m.dof_labels is None


# ---------------------------------------------------------------------- ANSYS
ANSYS_OK, ANSYS_WHY = reader_available()
needs_ansys = pytest.mark.skipif(not ANSYS_OK, reason=f"ansys-mapdl-reader cannot be imported ({ANSYS_WHY}); "
                                 f'install it with pip install "nnm[ansys]"')


def test_ansys_beam_route_needs_a_full_file_writer():
    pytest.skip("ansys-mapdl-reader reads .full files but cannot write them, so the beam cannot be exported "
                "to ANSYS here; the .full route is tested on the file MAPDL wrote that the reader ships "
                "(test_ansys_full_file_shipped_with_the_reader)")


@needs_ansys
def test_ansys_full_file_shipped_with_the_reader(tmp_path):
    from ansys.mapdl.reader import Archive, examples, read_binary
    model = nnm.load_model(examples.fullfile)
    full = read_binary(examples.fullfile)
    # independent assembly of the free-DOF matrices from the reader's sorted upper triangles
    free = np.array([tuple(r) not in {tuple(c) for c in full.const} for r in full.dof_ref])
    k, m = full.k.toarray(), full.m.toarray()
    k, m = (A + A.T - np.diag(np.diag(A)) for A in (k, m))
    assert model.n == free.sum() == 900 and len(full.const) == 63
    np.testing.assert_array_equal(_dense(model.K), k[np.ix_(free, free)])
    np.testing.assert_array_equal(_dense(model.M), m[np.ix_(free, free)])
    dm = nnm.DofMap.from_labels(model.dof_labels)
    assert dm.entries[0] == (int(full.dof_ref[free][0][0]), "ux") and all(d in ("ux", "uy", "uz") for _, d in dm.entries)
    # the description: a spring by node and direction at the free end, a display mesh from the archive
    import meshio
    import pyvista as pv
    grid = Archive(examples.hexarchivefile).grid.copy()
    grid.clear_data()
    meshio.write(tmp_path / "hexbeam.vtu", pv.to_meshio(grid))
    shutil.copy(examples.fullfile, tmp_path / "file.full")
    p = tmp_path / "beam.toml"
    p.write_text('[matrices]\nfile = "file.full"\n[[springs]]\nnode = 33\ndirection = "uy"\nk3 = 1e15\n'
                 '[mesh]\nfile = "hexbeam.vtu"\n')
    desc = nnm.load_model(p)
    assert desc.springs == [nnm.CubicSpring(dof=dm.index(33, "uy"), k3=1e15)]
    assert len(desc.mesh.vertices) == 321 and len(desc.mesh.faces) > 0
    clamped = np.flatnonzero(~desc.mesh.displacement_map.any(axis=1)) // 3
    assert set(clamped + 1) == set(int(n) for n in full.const[:, 0])          # clamped nodes stay still
    out = tmp_path / "beam.h5"
    assert solve_main(["import", str(p), "--out", str(out)]) == 0
    back = nnm.load_model(out)

    def lowest_hz(m):     # the 10 lowest frequencies (a subset: 900 DOFs)
        lam = scipy.linalg.eigh(_dense(m.K), _dense(m.M), eigvals_only=True, subset_by_index=[0, 9])
        return np.sqrt(lam) / (2 * np.pi)

    f0, f1 = lowest_hz(desc), lowest_hz(back)
    assert np.max(np.abs(f1 / f0 - 1)) <= 1e-10 and back.springs == desc.springs
    assert f0[0] == pytest.approx(1283.2, rel=1e-4)


def test_full_without_reader_says_how_to_install(tmp_path, monkeypatch):
    import nnm_solver.files.importers.ansys as ansys
    monkeypatch.setattr(ansys, "reader_available", lambda: (False, "ImportError: no module"))
    (tmp_path / "x.full").write_bytes(b"\0" * 64)
    with pytest.raises(NNMInputError, match=r'x\.full: reading ANSYS \.full files needs .*pip install "nnm\[ansys\]"'):
        nnm.load_model(tmp_path / "x.full")
