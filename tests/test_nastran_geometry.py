"""Nastran bulk data by hand: the a-set's DOF map with a superelement's modal (QSET) scalar points, the GRID/CQUAD4/
CTRIA3/CBAR geometry as the display mesh (pyNastran's BDF reader; CP and CD systems, bars as ribbons moving with the
grid's rotations, checked against small rigid rotations), FORMATTED .op4 values with three-digit exponents, bad
files one line."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.cli import main as solve_main
from nnm_solver.errors import NNMFileError, NNMInputError
from nnm_solver.files.importers.nastran import read_aset_map, read_nastran
from nnm_solver.files.importers.nastran_mesh import RIBBON_WIDTH, read_bdf_mesh

op4 = pytest.importorskip("pyNastran.op4.op4")

# fixed-field, free-field and a continuation; CORD2R 5 is the basic system shifted by 10 in x, CORD2R 7 turns
# x -> y (local x = basic y, local y = -basic x); grid 3 is placed in 5, grid 5 has its displacements in 7
BULK = """$ hand-made bulk data
CORD2R  5       0       10.     0.      0.      10.     0.      1.
        11.     0.      0.
CORD2R  7       0       0.      0.      0.      0.      0.      1.
        0.      1.      0.
GRID    1               0.      0.      0.
GRID    2               1.      0.      0.
GRID    3       5       1.      1.      0.
GRID,4,,0.,1.,0.
GRID    5               2.      0.      0.      7
CQUAD4  10      1       1       2       3       4
CTRIA3  11      1       2       5       3
CBAR    20      2       2       5       0.      0.      1.
CONM2   30      4       0       1.0
SPOINT  101     THRU    103
ASET1   123456  1       THRU    2
ASET1   123456  4       5
ASET    3       123
QSET1   0       101     THRU    103
"""


@pytest.fixture
def bulk(tmp_path):
    p = tmp_path / "model.bdf"
    p.write_text(BULK)
    return p


def test_the_aset_map_labels_grid_components_and_modal_scalar_points(bulk):
    dm = read_aset_map(bulk)
    assert len(dm) == 4 * 6 + 3 + 3
    labels = dm.labels()
    assert labels[:7] == ["node 1 ux", "node 1 uy", "node 1 uz", "node 1 rx", "node 1 ry", "node 1 rz", "node 2 ux"]
    assert labels[12:15] == ["node 3 ux", "node 3 uy", "node 3 uz"]                 # ASET 3 123: translations only
    assert labels[-3:] == ["spoint 101 modal", "spoint 102 modal", "spoint 103 modal"]
    assert dm.modal().sum() == 3 and dm.index(102, "modal") == len(dm) - 2
    again = nnm.DofMap.from_labels(labels)
    assert again.entries == dm.entries


def test_a_scalar_point_in_the_aset_only_is_scalar_and_ids_are_sorted_together(tmp_path):
    p = tmp_path / "m.bdf"
    p.write_text("ASET1,0,50\nASET1,3,60\nASET1,3,40\nQSET1,,70\n")
    assert read_aset_map(p).labels() == ["node 40 uz", "spoint 50 scalar", "node 60 uz", "spoint 70 modal"]


def test_a_blank_component_with_several_scalar_points(tmp_path):
    """QSET1 with a blank component and several IDs (docs/import.md: '0 or blank'): the first ID was read as the
    components ('not ASET1, components, grid, ...'; small field: 'ID 1002 ... as a scalar point and as a grid')."""
    p = tmp_path / "se.bdf"
    want = ["node 7 ux", "node 7 uy", "node 7 uz", "node 7 rx", "node 7 ry", "node 7 rz",
            "spoint 1001 modal", "spoint 1002 modal", "spoint 1003 modal"]
    for text in ("ASET1,123456,7\nQSET1,,1001,THRU,1003\n", "ASET1   123456  7\nQSET1           1001    1002    1003\n",
                 "ASET1,123456,7\nQSET1,0,1001,THRU,1003\n"):
        p.write_text(text)
        assert read_aset_map(p).labels() == want, text


def test_the_geometry_is_the_display_mesh(bulk):
    dm = read_aset_map(bulk)
    mesh = read_bdf_mesh(bulk, len(dm), dm)
    shells = mesh.vertices[:5]
    np.testing.assert_allclose(shells, [[0, 0, 0], [1, 0, 0], [11, 1, 0], [0, 1, 0], [2, 0, 0]])   # CP 5 applied
    assert mesh.part_names == ["model shells", "model bars"]
    assert mesh.faces.shape == (2 + 1 + 2, 3) and list(mesh.part_ids) == [0, 0, 0, 1, 1]
    width = RIBBON_WIDTH * np.linalg.norm(np.ptp(np.vstack([shells, shells[[1, 4]]]), axis=0))
    ribbon = mesh.vertices[5:]
    np.testing.assert_allclose(ribbon[:, 2], [width / 2, -width / 2, -width / 2, width / 2])   # CBAR x = (0, 0, 1)
    # a translation of grid 2 moves its shell vertex and its two ribbon vertices
    x = np.zeros(len(dm))
    x[dm.index(2, "uy")] = 1e-3
    u = mesh.displacements(x)
    np.testing.assert_allclose(u[[1, 5, 6]], [[0, 1e-3, 0]] * 3)
    assert np.count_nonzero(u) == 3


@pytest.mark.parametrize("direction", ["rx", "ry", "rz"])
def test_ribbon_vertices_follow_small_rotations_of_their_grid(bulk, direction):
    """Vertex displacement of a grid rotation theta: R(theta) r - r for a rigid rotation (Rodrigues) to O(theta^2);
    grid 5's rotations are in its CD system 7 (local x = basic y, local y = -basic x)."""
    dm = read_aset_map(bulk)
    mesh = read_bdf_mesh(bulk, len(dm), dm)
    theta = 1e-6
    local = {"rx": [1, 0, 0], "ry": [0, 1, 0], "rz": [0, 0, 1]}[direction]
    to_basic = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])      # columns: local axes in basic
    axis = to_basic @ np.array(local, dtype=float)
    x = np.zeros(len(dm))
    x[dm.index(5, direction)] = theta
    u = mesh.displacements(x)
    grid5 = np.array([2.0, 0.0, 0.0])
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K
    for v in (7, 8):                                        # the ribbon's vertices at grid 5
        r = mesh.vertices[v] - grid5
        np.testing.assert_allclose(u[v], R @ r - r, rtol=1e-5, atol=theta ** 2 * np.linalg.norm(r))
        assert np.linalg.norm(u[v]) >= 0.5 * theta * np.linalg.norm(np.cross(axis, r))
    assert np.allclose(u[4], 0)                             # the grid's own (shell) vertex does not move


def test_a_description_with_the_bulk_data_as_dof_map_and_mesh(bulk, tmp_path):
    n = 30
    rng = np.random.default_rng(0)
    A = rng.normal(size=(n, n))
    K = A @ A.T + n * np.eye(n)
    M = np.diag(rng.uniform(1.0, 2.0, n))
    M[0, 1] = M[1, 0] = 1e-305                              # round-off entries: three-digit exponents in the file
    M[0, 2] = M[2, 0] = -3e-306
    op4.OP4().write_op4(str(tmp_path / "model.op4"), {"KAA": (6, K), "MAA": (6, M)}, is_binary=False,
                        precision="double")
    (tmp_path / "model.toml").write_text('[matrices]\nfile = "model.op4"\ndof_map = "model.bdf"\n[mesh]\n'
                                         'file = "model.bdf"\n[[springs]]\nnode = 5\ndirection = 1\nother_node = 2\n'
                                         'other_direction = 1\nk3 = 1e6\n')
    model = nnm.load_model(tmp_path / "model.toml")
    import scipy.linalg
    w2 = scipy.linalg.eigh(K, np.where(np.abs(M) < 1e-99, 0, M), eigvals_only=True)
    np.testing.assert_allclose(model.linear_modes()[0][:6], np.sqrt(w2[:6]) / (2 * np.pi), rtol=1e-9)
    assert model.dof_labels[-1] == "spoint 103 modal"
    assert model.mesh is not None and model.mesh.vertices.shape == (9, 3)
    s = model.springs[0]
    assert (model.dof_labels[s.dof], model.dof_labels[s.other]) == ("node 5 ux", "node 2 ux")
    out = tmp_path / "model.h5"
    assert solve_main(["import", str(tmp_path / "model.toml"), "--out", str(out)]) == 0
    back = nnm.load_model(out)
    assert back.dof_labels == model.dof_labels
    np.testing.assert_allclose(back.mesh.vertices, model.mesh.vertices)
    Mr, Kr = read_nastran(tmp_path / "model.op4")
    assert Mr[0, 1] == Mr[0, 2] == 0.0 and np.allclose(Mr, np.where(np.abs(M) < 1e-99, 0, M), rtol=1e-15)


def test_fortran_three_digit_exponents_without_the_e(tmp_path):
    """Nastran's 1P,3E23.16 writes 1.0e-305 as '1.0000000000000000-305' (no E); such values are round-off zeros."""
    lines = [f"{2:8d}{2:8d}{6:8d}{2:8d}{'KAA':<8}1P,3E23.16", f"{1:8d}{1:8d}{4:8d}",
             f"{2.0:23.16E}" + " 1.0000000000000000-305", f"{2:8d}{1:8d}{4:8d}",
             " 1.0000000000000000-305" + f"{3.0:23.16E}", f"{3:8d}{1:8d}{1:8d}", f"{1.0:23.16E}"]
    text = "\n".join(lines) + "\n"
    (tmp_path / "k.op4").write_text(text + text.replace("KAA", "MAA"))
    M, K = read_nastran(tmp_path / "k.op4")
    np.testing.assert_array_equal(np.asarray(K), [[2.0, 0.0], [0.0, 3.0]])
    (tmp_path / "big.op4").write_text(text.replace("-305", "+305"))
    with pytest.raises(NNMFileError, match="beyond the range of a FORMATTED OUTPUT4 field; write the matrices "
                                           "UNFORMATTED") as err:
        read_nastran(tmp_path / "big.op4")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("text, message", [
    ("GRID    1               0.      0.      0.\nCQUAD4  10      1       1       2       3       4\n",
     "element 10 uses grid 2, which has no GRID card"),
    ("GRID    1               0.      0.      0.\nGRID    2               1.      0.      0.\n",
     "no elements to draw"),
    ("CORD2C  9       0       0.      0.      0.      0.      0.      1.\n        1.      0.      0.\n"
     "GRID    1               0.      0.      0.      9\nGRID    2               1.      0.      0.\n"
     "CROD    5       1       1       2\n", "only rectangular CD systems"),
    ("GRID    1               0.      0.      0.\nGRID    2               1.      0.      0.\n"
     "CROD    5       1       1       2\n", "no grid of .* matches a DOF of the model"),
    ("GRID    1      x        0.      0.      0.\n", "not a readable Nastran bulk data file"),
])
def test_bad_bulk_data_meshes_give_one_line(tmp_path, text, message):
    p = tmp_path / "bad.bdf"
    p.write_text(text)
    dm = nnm.DofMap([(99, "ux")])
    with pytest.raises((NNMFileError, NNMInputError), match=message) as err:
        read_bdf_mesh(p, 1, dm)
    assert "\n" not in str(err.value)


def test_bad_descriptions_exit_2_and_write_nothing(bulk, tmp_path, capsys):
    K = np.eye(30) * 1e4
    op4.OP4().write_op4(str(tmp_path / "model.op4"), {"KAA": (6, K), "MAA": (6, np.eye(30))}, is_binary=False,
                        precision="double")
    cases = [('units = "mm-t-s"\n[matrices]\nfile = "model.op4"\ndof_map = "model.bdf"\n', "modal coordinates"),
             ('[matrices]\nfile = "model.op4"\ndof_map = "model.bdf"\n[mesh]\nfile = "model.bdf"\nnodes = [1]\n',
              "placed by grid ID"),
             ('[matrices]\nfile = "model.op4"\n[mesh]\nfile = "model.bdf"\n', "give \\[matrices\\] dof_map")]
    for text, message in cases:
        p = tmp_path / "bad.toml"
        p.write_text(text)
        with pytest.raises(NNMInputError, match=message):
            nnm.load_model(p)
        out = tmp_path / "bad.h5"
        assert solve_main(["import", str(p), "--out", str(out)]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1 and not out.exists()


def test_uff_shapes_leave_the_modal_scalar_points_out(tmp_path):
    """A model with grids and modal scalar points: UFF 55 nodes are the grids only."""
    labels = ["node 1 uz", "node 2 uz", "spoint 101 modal"]
    model = nnm.Model(np.eye(3), np.diag([1.0, 2.0, 3.0]) * 1e4, [nnm.CubicSpring(dof=0, k3=1e9)], dof_labels=labels)
    from nnm_solver.files.exports import uff_nodes

    nums, k, values = uff_nodes(model)
    assert list(nums) == [1, 2] and k == 3
    np.testing.assert_array_equal(values(np.array([1.0, 2.0, 3.0])), [[0, 0, 1.0], [0, 0, 2.0]])
