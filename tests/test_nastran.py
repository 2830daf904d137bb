"""Nastran matrices in: OUTPUT4 files written by pyNastran's writer (ASCII), by a binary writer here following
the OUTPUT4 record layout, and by hand; the a-set DOF map from ASET1 cards; bad files give one line."""
import struct

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.cli import main as solve_main
from nnm_solver.errors import NNMFileError, NNMInputError

op4 = pytest.importorskip("pyNastran.op4.op4")

K = np.array([[4.0, -2.0, 0.0], [-2.0, 4.0, -2.0], [0.0, -2.0, 2.0]]) * 1e4
M = np.diag([1.0, 2.0, 0.5])


def write_binary_op4(path, matrices):
    """Dense real double OUTPUT4 (UNFORMATTED), little-endian Fortran records: header (ncols, nrows, form, type 2,
    name), one record per column (icol, first row, words, values), and the closing record (ncols + 1, 1, 2, 1.0)."""
    def record(payload):
        return struct.pack("<i", len(payload)) + payload + struct.pack("<i", len(payload))

    out = b""
    for name, A in matrices.items():
        nrows, ncols = A.shape
        out += record(struct.pack("<4i8s", ncols, nrows, 6, 2, f"{name:<8}".encode()))
        for j in range(ncols):
            out += record(struct.pack(f"<3i{nrows}d", j + 1, 1, 2 * nrows, *A[:, j]))
        out += record(struct.pack("<3id", ncols + 1, 1, 2, 1.0))
    path.write_bytes(out)


def write_text_op4(path, matrices):
    """Dense FORMATTED OUTPUT4 by hand: header line, per column 'icol irow nwords' and 3E23.16 lines."""
    lines = []
    for name, A in matrices.items():
        n = A.shape[0]
        lines.append(f"{n:8d}{n:8d}{6:8d}{2:8d}{name:<8}1P,3E23.16")
        for j in range(n):
            lines.append(f"{j + 1:8d}{1:8d}{n:8d}")
            vals = [f"{v:23.16E}" for v in A[:, j]]
            lines += ["".join(vals[i:i + 3]) for i in range(0, n, 3)]
        lines.append(f"{n + 1:8d}{1:8d}{1:8d}")
        lines.append(f"{1.0:23.16E}")
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("writer", ["pynastran_ascii", "binary", "by_hand"])
def test_op4_matrices_by_file_type(tmp_path, writer):
    p = tmp_path / "model.op4"
    if writer == "pynastran_ascii":
        op4.OP4().write_op4(str(p), {"KAA": (6, K), "MAA": (6, M)}, is_binary=False, precision="double")
    elif writer == "binary":
        write_binary_op4(p, {"KAA": K, "MAA": M})
    else:
        write_text_op4(p, {"KAA": K, "MAA": M})
    model = nnm.load_model(p)
    np.testing.assert_allclose(np.asarray(model.K.todense() if hasattr(model.K, "todense") else model.K), K)
    np.testing.assert_allclose(np.asarray(model.M.todense() if hasattr(model.M, "todense") else model.M), M)
    assert model.info["format"] == "nastran"


def test_a_description_names_the_matrices_and_places_springs_by_grid(tmp_path):
    op4.OP4().write_op4(str(tmp_path / "gset.op4"), {"KGG": (6, K), "MGG": (6, M), "PHG": (2, np.ones((3, 1)))},
                        is_binary=False, precision="double")
    (tmp_path / "model.bdf").write_text("$ a-set of the connection\nASET1   3       30      10\n"
                                        "ASET1,3,20\n")
    (tmp_path / "model.toml").write_text(
        '[matrices]\nformat = "nastran"\nfile = "gset.op4"\nstiffness = "KGG"\nmass = "MGG"\ndof_map = "model.bdf"\n'
        '[[springs]]\nnode = 30\ndirection = 3\nother_node = 20\nk3 = -1e9\n')
    model = nnm.load_model(tmp_path / "model.toml")
    assert model.dof_labels == ["node 10 uz", "node 20 uz", "node 30 uz"]
    assert (model.springs[0].dof, model.springs[0].other, model.springs[0].k3) == (2, 1, -1e9)
    w = np.sqrt(np.linalg.eigvalsh(np.linalg.solve(np.linalg.cholesky(M), np.linalg.solve(np.linalg.cholesky(M), K).T)))
    np.testing.assert_allclose(model.linear_modes()[0], np.sort(w) / (2 * np.pi), rtol=1e-12)


def test_the_aircraft_through_op4_has_the_same_frequencies_and_springs(tmp_path):
    ref = nnm.load_model("assets/paris.h5")
    write_binary_op4(tmp_path / "paris.op4", {"KAA": np.asarray(ref.K), "MAA": np.asarray(ref.M)})
    (tmp_path / "dofs.txt").write_text("".join(f"{i // 6 + 1} {i % 6 + 1}\n" for i in range(ref.n)))
    springs = "".join(f"[[springs]]\ndof = {s.dof}\nother = {s.other}\nk3 = {s.k3!r}\n" for s in ref.springs)
    (tmp_path / "paris.toml").write_text(f'[matrices]\nfile = "paris.op4"\ndof_map = "dofs.txt"\n{springs}')
    model = nnm.load_model(tmp_path / "paris.toml")
    np.testing.assert_allclose(model.linear_modes()[0][:20], ref.linear_modes()[0][:20], rtol=1e-10)
    assert [(s.dof, s.other, s.k3) for s in model.springs] == [(s.dof, s.other, s.k3) for s in ref.springs]


@pytest.mark.parametrize("content, message", [
    (b"this is not an OUTPUT4 file\n", "not a readable Nastran OUTPUT4"),
    ("missing", "no matrix MAA \\(the file holds KAA\\)"),
])
def test_bad_nastran_files_give_one_line_and_exit_2(tmp_path, capsys, content, message):
    p = tmp_path / "bad.op4"
    if content == "missing":
        op4.OP4().write_op4(str(p), {"KAA": (6, K)}, is_binary=False, precision="double")
    else:
        p.write_bytes(content)
    with pytest.raises(NNMFileError, match=message) as err:
        nnm.load_model(p)
    assert "\n" not in str(err.value)
    out = tmp_path / "out.h5"
    assert solve_main(["import", str(p), "--out", str(out)]) == 2
    msg = capsys.readouterr().err
    assert message.replace("\\", "") in msg and msg.count("\n") == 1 and not out.exists()


def test_bad_descriptions_and_maps_give_one_line(tmp_path):
    write_text_op4(tmp_path / "m.op4", {"KAA": K, "MAA": M})
    (tmp_path / "short.bdf").write_text("ASET1,3,10\n")
    cases = [('file = "m.op4"\nformat = "nastran"\ndof_map = "short.bdf"\n', "1 DOFs listed, the matrices have 3"),
             ('format = "nastran"\nmass = "MAA"\n', "need file"),
             ('file = "m.op4"\nformat = "nastran"\nrecovery = 1\n', "unknown key"),
             ('file = "m.op4"\nstiffness = "KGG"\n', "no matrix KGG")]
    for body, message in cases:
        (tmp_path / "d.toml").write_text("[matrices]\n" + body)
        with pytest.raises(NNMInputError, match=message) as err:
            nnm.load_model(tmp_path / "d.toml")
        assert "\n" not in str(err.value)
