"""HDF5 files: round trips, appending keeps everything, atomic writes, and one-line errors for bad files."""
import os

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import nnm_solver as nnm
from nnm_solver import NNMFileError, NNMInputError

from conftest import two_dof_model


def _mesh():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2]])
    D = np.zeros((9, 2))
    D[2, 0] = D[5, 1] = 1.0
    return nnm.DisplayMesh(V, F, D, part_ids=[0], part_names=["plate"])


def test_model_round_trip(tmp_path):
    m = nnm.Model(np.eye(2), np.array([[2.0, -1], [-1, 2]]),
                  [nnm.CubicSpring(dof=0, k3=0.5), nnm.CubicSpring(dof=0, other=1, k3=-2.0)],
                  dof_labels=["a", "b"], mode_labels=["in phase", "out of phase"], mesh=_mesh(),
                  name="two", info={"source": "test", "version": 3})
    p = tmp_path / "m.h5"
    nnm.save_model(p, m, extra={"reference": {"table2_hz": np.arange(3.0), "source": "paper"}})
    r = nnm.load_model(p)
    assert np.array_equal(r.M, m.M) and np.array_equal(r.K, m.K)
    assert r.springs == m.springs
    assert r.dof_labels == ["a", "b"] and r.mode_labels == ["in phase", "out of phase"]
    assert r.name == "two" and r.info["version"] == 3
    assert np.allclose(r.mesh.displacements(np.array([1.0, 2.0])), [[0, 0, 1], [0, 0, 2], [0, 0, 0]])
    ref = nnm.load_extra(p, "reference")
    assert np.array_equal(ref["table2_hz"], np.arange(3.0)) and ref["source"] == "paper"


def test_sparse_matrices_round_trip(tmp_path):
    M = sp.identity(3, format="csr")
    K = sp.diags([2.0, 3.0, 4.0]).tocsr()
    p = tmp_path / "s.h5"
    nnm.save_model(p, nnm.Model(M, K))
    r = nnm.load_model(p)
    assert sp.issparse(r.K) and np.allclose(r.K.toarray(), K.toarray())


def test_sparse_display_map_round_trip_stays_sparse(tmp_path):
    """A large FE model's display map is sparse (examples/build_paris_full.py: 3V x 64,446): it is written as CSR
    (/mesh/displacement_map a group, attribute sparse="csr"), read back sparse, and moves the mesh as the dense one."""
    dense = _mesh()
    mesh = nnm.DisplayMesh(dense.vertices, dense.faces, sp.csr_matrix(dense.displacement_map, dtype=np.float32),
                           part_ids=[0], part_names=["plate"])
    assert sp.issparse(mesh.displacement_map)
    x = np.array([[1.0, 2.0], [-0.5, 3.0]])
    assert np.array_equal(mesh.displacements(x), dense.displacements(x))
    assert np.array_equal(mesh.displacements(x[0]), dense.displacements(x[0]))
    assert np.array_equal(mesh.map_rows([2, 5]), dense.map_rows([2, 5]))
    m = nnm.Model(np.eye(2), np.array([[2.0, -1], [-1, 2]]), mesh=mesh)
    p = tmp_path / "sparse_mesh.h5"
    nnm.save_model(p, m)
    with h5py.File(p, "r") as f:
        g = f["mesh/displacement_map"]
        assert isinstance(g, h5py.Group) and g.attrs["sparse"] == "csr" and g["data"].dtype == np.float32
    r = nnm.load_model(p)
    assert sp.issparse(r.mesh.displacement_map) and r.mesh.displacement_map.shape == (9, 2)
    assert np.array_equal(r.mesh.displacements(x), dense.displacements(x))
    # the viewer's mapper keeps it sparse and gives the same displacements
    from nnm_viewer.animation import MeshMapper
    assert np.allclose(MeshMapper(r.mesh)(x), MeshMapper(dense)(x))
    assert MeshMapper(r.mesh).sparse and not MeshMapper(dense).sparse
    # a dense map is still a dataset
    nnm.save_model(p, nnm.Model(np.eye(2), np.array([[2.0, -1], [-1, 2]]), mesh=dense))
    with h5py.File(p, "r") as f:
        assert isinstance(f["mesh/displacement_map"], h5py.Dataset)
    assert isinstance(nnm.load_model(p).mesh.displacement_map, np.ndarray)


def test_stored_ritz_basis_is_used_and_belongs_to_its_model(tmp_path, monkeypatch):
    """store_ritz_basis writes /ritz_basis; a model read from the file (or a k3-scaled one) takes it instead of
    computing one; another model's basis is refused, and a file whose basis is not its model's does not use it."""
    import weakref

    from nnm_solver.model import ritz
    N = 300
    T = (1e4 * sp.diags([-np.ones(N - 1), 2 * np.ones(N), -np.ones(N - 1)], [-1, 0, 1])).tocsr()
    model = nnm.Model(0.5 * sp.identity(N, format="csr"), T, [nnm.CubicSpring(dof=10, other=11, k3=1e9)])
    p = tmp_path / "chain.h5"
    nnm.save_model(p, model)
    hb = dict(method="hb", harmonics=5, condensed=True, floquet=False, modal_basis="ritz")
    computed = nnm.continue_nnm(model, 2, 1e-3, **hb)
    info = nnm.store_ritz_basis(p, model, 2, 5)
    assert info["exact_modes"] >= 2 and info["columns"] == info["exact_modes"] + 2
    monkeypatch.setattr(ritz, "_stored", {})
    monkeypatch.setattr(ritz, "_cache", weakref.WeakKeyDictionary())
    read = nnm.load_model(p)

    def refuse(*args, **kwargs):
        raise AssertionError("the basis was computed, not read")
    monkeypatch.setattr(ritz, "ritz_basis", refuse)
    branch = nnm.continue_nnm(read, 2, 1e-3, **hb)
    assert np.array_equal(branch.frequency_hz, computed.frequency_hz)
    assert ritz.ritz_system(read, 2, 5).stored == str(p.resolve())
    nnm.continue_nnm(read.scaled(2.0), 2, 1e-3, **hb)            # the same linear part: the same basis
    other = nnm.Model(0.6 * sp.identity(N, format="csr"), T, [nnm.CubicSpring(dof=10, other=11, k3=1e9)])
    with pytest.raises(NNMInputError, match="another model"):
        nnm.store_ritz_basis(p, other, 2, 5)
    # a file whose model was replaced under a stored basis: the basis is not used
    with h5py.File(p, "r+") as f:
        f["ritz_basis"].attrs["fingerprint"] = "0" * 64
    monkeypatch.setattr(ritz, "_stored", {})
    with pytest.warns(UserWarning, match="another model"):
        nnm.load_model(p)
    assert ritz._stored == {}


def test_branch_round_trip_and_append_keeps_everything(tmp_path, two_dof_nnm1):
    p = tmp_path / "b.h5"
    nnm.save_model(p, two_dof_nnm1.model)
    n1 = nnm.save_branch(p, two_dof_nnm1)
    n2 = nnm.save_branch(p, two_dof_nnm1.scaled(2.0))
    assert n1 != n2
    bs = nnm.load_branches(p)
    assert len(bs) == 2
    a = bs[0]
    for key in ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable"):
        assert np.array_equal(getattr(a, key), getattr(two_dof_nnm1, key))
    assert a.events == two_dof_nnm1.events
    assert a.status == two_dof_nnm1.status and a.mode == 1
    assert bs[1].model.k3[0] == pytest.approx(1.0)     # the scaled branch keeps its own k3
    # the loaded branch is usable
    t, x = a.motion(3, samples=64)
    assert x.shape == (64, 2)


def test_save_branch_creates_file_with_model(tmp_path, two_dof_nnm1):
    p = tmp_path / "new.h5"
    nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 5)))
    assert nnm.load_model(p).n == 2
    assert len(nnm.load_branches(p)[0]) == 5


def test_interrupted_write_leaves_file_intact(tmp_path, two_dof_nnm1, monkeypatch):
    p = tmp_path / "b.h5"
    nnm.save_branch(p, two_dof_nnm1)
    before = p.read_bytes()

    def fail(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(nnm.files.branch_io, "_jsonable", fail)   # dies in the middle of writing the new group
    with pytest.raises(KeyboardInterrupt):
        nnm.save_branch(p, two_dof_nnm1)
    assert p.read_bytes() == before
    assert [f for f in os.listdir(tmp_path) if f.endswith(".tmp")] == []
    assert len(nnm.load_branches(p)) == 1


def test_branch_of_other_model_is_refused(tmp_path, two_dof_nnm1):
    p = tmp_path / "one.h5"
    nnm.save_model(p, nnm.Model(np.eye(1), np.eye(1)))
    with pytest.raises(NNMInputError, match="1 DOFs but the branch has 2"):
        nnm.save_branch(p, two_dof_nnm1)


def test_bad_files(tmp_path):
    with pytest.raises(NNMFileError, match="no such file"):
        nnm.load_model(tmp_path / "missing.h5")
    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"this is not hdf5")
    with pytest.raises(NNMFileError, match="not a readable HDF5 file"):
        nnm.load_model(junk)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = 1
    with pytest.raises(NNMFileError, match="not an nnm file"):
        nnm.load_model(other)
    good = tmp_path / "good.h5"
    nnm.save_model(good, two_dof_model())
    with h5py.File(good, "r+") as f:
        del f["model/K"]
    with pytest.raises(NNMFileError, match="missing dataset /model/K"):
        nnm.load_model(good)
    nnm.save_model(good, two_dof_model())
    with h5py.File(good, "r+") as f:
        del f["model/K"]
        f["model/K"] = np.eye(3)
    with pytest.raises(NNMFileError, match="shape"):
        nnm.load_model(good)
    nnm.save_model(good, two_dof_model())
    with h5py.File(good, "r+") as f:
        f["model/springs/dof"][0] = 7
    with pytest.raises(NNMFileError, match="dof=7 is not a DOF"):
        nnm.load_model(good)
    truncated = tmp_path / "trunc.h5"
    truncated.write_bytes(good.read_bytes()[:800])
    with pytest.raises(NNMFileError):
        nnm.load_model(truncated)


def test_mat_import(tmp_path):
    p = tmp_path / "m.mat"
    scipy.io.savemat(p, {"M": np.eye(2), "K": np.array([[2.0, -1], [-1, 2]]),
                         "springs": np.array([[1, 0, 0.5], [1, 2, -3.0]])})
    m = nnm.load_mat_model(p)
    assert m.springs == [nnm.CubicSpring(dof=0, k3=0.5), nnm.CubicSpring(dof=0, other=1, k3=-3.0)]
    scipy.io.savemat(p, {"M": np.eye(2)})
    with pytest.raises(NNMFileError, match="no variable 'K'"):
        nnm.load_mat_model(p)
    scipy.io.savemat(p, {"M": np.eye(2), "K": np.eye(2), "springs": np.array([[3, 0, 1.0]])})
    with pytest.raises(NNMFileError, match="not a DOF"):
        nnm.load_mat_model(p)
    bad = tmp_path / "bad.mat"
    bad.write_bytes(b"garbage")
    with pytest.raises(NNMFileError, match="not a readable MATLAB"):
        nnm.load_mat_model(bad)


def test_written_files_have_normal_permissions(tmp_path):
    p = tmp_path / "perm.h5"
    nnm.save_model(p, two_dof_model())
    umask = os.umask(0)
    os.umask(umask)
    assert p.stat().st_mode & 0o777 == 0o666 & ~umask
    os.chmod(p, 0o640)
    nnm.save_model(p, two_dof_model())
    assert p.stat().st_mode & 0o777 == 0o640


# ---------------------------------------------------------------------- a branch of another model (issue 32, item 2)
K2 = np.array([[2.0, -1.0], [-1.0, 2.0]])
OTHER_MODELS = {
    "other K": (nnm.Model(np.eye(2), 3 * K2, [nnm.CubicSpring(dof=0, k3=0.5)]), "K differs by up to 66.7 % of its largest entry"),
    "other M": (nnm.Model(2 * np.eye(2), K2, [nnm.CubicSpring(dof=0, k3=0.5)]), "M differs"),
    "other spring position": (nnm.Model(np.eye(2), K2, [nnm.CubicSpring(dof=1, k3=0.5)]),
                              "spring 0 joins DOFs 1-ground in the file, 0-ground in the branch's model"),
    "relative spring": (nnm.Model(np.eye(2), K2, [nnm.CubicSpring(dof=0, other=1, k3=0.5)]),
                        "spring 0 joins DOFs 0-1 in the file, 0-ground"),
    "other spring count": (nnm.Model(np.eye(2), K2, [nnm.CubicSpring(dof=0, k3=0.5),
                                                     nnm.CubicSpring(dof=1, k3=1.0)]),
                           "the file's model has 2 springs, the branch's 1"),
    "other spring law": (nnm.Model(np.eye(2), K2, [nnm.PolynomialSpring(dof=0, coefficients={3: 0.5, 5: 1.0})]),
                         "spring 0 is a PolynomialSpring in the file, a CubicSpring"),
    "other DOF count": (nnm.Model(np.eye(3), np.diag([2.0, 2.0, 2.0]), [nnm.CubicSpring(dof=0, k3=0.5)]),
                        "the file's model has 3 DOFs but the branch has 2"),
    "sparse K": (nnm.Model(sp.identity(2, format="csr"), sp.csr_matrix(3 * K2), [nnm.CubicSpring(dof=0, k3=0.5)]),
                 "K differs"),
}


@pytest.mark.parametrize("case", list(OTHER_MODELS))
def test_branch_of_another_model_is_refused_and_file_untouched(tmp_path, two_dof_nnm1, case):
    other, what = OTHER_MODELS[case]
    p = tmp_path / "chain.h5"
    nnm.save_model(p, other)
    before = p.read_bytes()
    with pytest.raises(NNMInputError) as err:
        nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 5)))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{p} holds another model than this branch's (")
    assert what in msg
    assert "the file was left unchanged: save the branch to another file name, e.g. " in msg
    assert p.read_bytes() == before
    assert [f for f in os.listdir(tmp_path) if f != "chain.h5"] == []      # no temporary file left either
    assert nnm.load_branches(p) == []


def test_file_with_branches_refuses_a_branch_of_another_model(tmp_path, two_dof_nnm1):
    """The issue's case: chain.h5 made from one description, then a branch of another model saved there."""
    p = tmp_path / "chain.h5"
    nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 5)))
    before = p.read_bytes()
    b = two_dof_nnm1.subset(slice(0, 5))
    b.model = nnm.Model(2 * np.eye(2), 3 * K2, [nnm.CubicSpring(dof=1, k3=1.5)])
    with pytest.raises(NNMInputError, match=r"spring 0 joins DOFs 0-ground in the file, 1-ground in the branch's "
                                            r"model; M differs by up to 50 % of its largest entry; K differs by up to "
                                            r"66\.7 % of its largest entry\); the file was left unchanged"):
        nnm.save_branch(p, b)
    assert p.read_bytes() == before
    assert [x.name for x in nnm.load_branches(p)] == ["mode1"]


def test_refusal_names_a_free_file_name(tmp_path, two_dof_nnm1):
    p = tmp_path / "chain.h5"
    nnm.save_model(p, OTHER_MODELS["other K"][0])
    with pytest.raises(NNMInputError,
                       match=r"another file name, e\.g\. .*chain_2\.h5 \(nnm-solve: --out .*chain_2\.h5\)$"):
        nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 3)))
    (tmp_path / "chain_2.h5").write_bytes(b"taken")
    with pytest.raises(NNMInputError, match=r"e\.g\. .*chain_3\.h5"):
        nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 3)))
    # the remedy works: the named file takes the branch
    nnm.save_branch(tmp_path / "chain_3.h5", two_dof_nnm1.subset(slice(0, 3)))
    assert len(nnm.load_branches(tmp_path / "chain_3.h5")) == 1


def test_branch_of_the_same_model_with_another_k3_is_appended(tmp_path, two_dof_nnm1):
    """The viewer's stiffness slider and scaled branches: only the cubic springs' k3 differ, and each branch
    is read back with its own k3."""
    p = tmp_path / "b.h5"
    nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 5)))
    scaled = two_dof_nnm1.subset(slice(0, 5)).scaled(3.0)
    own = two_dof_nnm1.subset(slice(0, 5))
    own.model = two_dof_model(k3=-2.0)                  # rebuilt with another k3 (equal matrices, another object)
    nnm.save_branch(p, scaled)
    nnm.save_branch(p, own, name="softened")
    bs = nnm.load_branches(p)
    assert [b.model.k3[0] for b in bs] == [pytest.approx(0.5), pytest.approx(1.5), pytest.approx(-2.0)]
    assert bs[2].name == "softened"
    assert nnm.load_model(p).k3[0] == pytest.approx(0.5)      # the file's model is unchanged


def test_same_model_read_back_from_the_file_is_accepted(tmp_path, two_dof_nnm1):
    """A branch computed on the model loaded from the file (sparse or dense matrices) is appended."""
    p = tmp_path / "s.h5"
    m = nnm.Model(sp.identity(2, format="csr"), sp.csr_matrix(K2), [nnm.CubicSpring(dof=0, k3=0.5)])
    nnm.save_model(p, m)
    b = two_dof_nnm1.subset(slice(0, 4))
    b.model = nnm.load_model(p)
    nnm.save_branch(p, b)
    b.model = two_dof_model()                           # the same numbers as dense matrices
    nnm.save_branch(p, b)
    assert len(nnm.load_branches(p)) == 2


def test_sweep_branch_of_a_recorded_variant_is_accepted(tmp_path, two_dof_nnm1):
    """A sweep branch ``<variant>:mode<N>`` carries its variant's model (other K, M, springs) and is read back
    with it; the same name with a model that is not the variant's is refused."""
    from nnm_solver.sweeps import prepare_file

    base = two_dof_model()
    v = nnm.Variant(name="stiff", spring_factor=2.0, added_stiffness=[(1, 0.3)], mass_factor=1.5)
    p = tmp_path / "sweep.h5"
    prepare_file(p, base, [v], 1.0, {"stiff:mode1"})
    b = two_dof_nnm1.subset(slice(0, 4))
    b.model = v.apply(base)
    b.name = "stiff:mode1"
    nnm.save_branch(p, b)
    back = nnm.load_branches(p)[0]
    assert back.name == "stiff:mode1" and np.allclose(back.model.K, v.apply(base).K)
    before = p.read_bytes()
    wrong = two_dof_nnm1.subset(slice(0, 4))
    wrong.name = "stiff:mode1"                          # the base model under the variant's name
    with pytest.raises(NNMInputError, match="with sweep variant 'stiff'"):
        nnm.save_branch(p, wrong)
    assert p.read_bytes() == before
    # a branch of the base model under another name is fine
    nnm.save_branch(p, two_dof_nnm1.subset(slice(0, 4)))
    assert len(nnm.load_branches(p)) == 2


def test_subset_and_save_keep_the_located_events(two_dof_nnm1, tmp_path):
    """A subset in order (the file's thinning, a save under another name) keeps the branch's located events between
    its first and last rows, with their energies and orbits, and renumbers them to the first kept row after each;
    rows out of order bracket them again from the rows."""
    b = two_dof_nnm1
    located = [e for e in b.events if e.get("located") and "x0" in e]
    assert located
    e = located[0]
    rows = np.unique(np.r_[0, np.arange(1, len(b), 3), e["index"] - 1, len(b) - 1])    # thinned around it
    c = b.subset(rows)
    kept = [x for x in c.events if x["kind"] == e["kind"] and x["energy"] == e["energy"]]
    assert len(kept) == 1 and kept[0]["x0"] == e["x0"]
    assert rows[kept[0]["index"]] >= e["index"] > rows[kept[0]["index"] - 1]
    assert all(x["energy"] != e["energy"] for x in b.subset(slice(0, e["index"] - 1)).events)   # before it: gone
    p = tmp_path / "b.h5"
    nnm.save_branch(p, b, name="renamed")
    assert [x["energy"] for x in nnm.load_branches(p)[0].events] == [x["energy"] for x in b.events]
