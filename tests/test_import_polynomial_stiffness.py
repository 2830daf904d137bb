"""PolynomialStiffness in the TOML model description (issue 55): ``type = "polynomial_stiffness"``, NLvib's exponents
and coefficients, by dofs or by node and direction, in the description's units; the same element as one built in
Python (force and potential at random points, SI from mm-t-s by hand), round trip through the nnm HDF5 file and
``nnm-solve import``; bad input one line, exit 2, nothing written."""
import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import nnm_solver as nnm
from nnm_solver.cli import main as solve_main
from nnm_solver.errors import NNMInputError
from nnm_solver.files.coupled_io import same_element

# NLvib example 06's quadratic and cubic terms in two coordinates (a potential), a = 1, b = 4 (file units)
EX = [[2, 0], [1, 1], [0, 2], [3, 0], [2, 1], [1, 2], [0, 3]]
CO = [[1.5, 2.0], [4.0, 1.0], [0.5, 6.0], [2.5, 0.0], [0.0, 2.5], [2.5, 0.0], [0.0, 2.5]]
K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]) * 1e3
M = np.diag([1.0, 2.0, 3.0])


@pytest.fixture
def folder(tmp_path):
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.coo_matrix(M))
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.coo_matrix(K))
    (tmp_path / "dofs.txt").write_text("7 uz\n8 uz\n9 uz\n")
    return tmp_path


def describe(folder, element, units="SI", dof_map=True):
    text = (f'units = "{units}"\n[matrices]\nmass = "M.mtx"\nstiffness = "K.mtx"\n'
            + ('dof_map = "dofs.txt"\n' if dof_map else "")
            + f'[[springs]]\ntype = "cubic"\ndof = 1\nk3 = 2.0\n'
            + f'[[springs]]\ntype = "polynomial_stiffness"\nexponents = {EX}\ncoefficients = {CO}\n{element}')
    p = folder / "model.toml"
    p.write_text(text)
    return p


def test_by_dofs_and_by_nodes_give_the_element_built_in_python(folder):
    ref = nnm.PolynomialStiffness(EX, CO, dofs=[0, 2])
    for placement in ("dofs = [0, 2]\n", 'nodes = [7, 9]\ndirection = "uz"\n', 'nodes = [7, 9]\ndirection = ["z", 3]\n'):
        model = nnm.load_model(describe(folder, placement))
        assert [type(e).__name__ for e in model.springs] == ["CubicSpring", "PolynomialStiffness"]
        assert same_element(model.springs[1], ref, rtol=0)
    rng = np.random.default_rng(3)
    built = nnm.Model(M, K, [nnm.CubicSpring(dof=1, k3=2.0), ref])
    for x in rng.normal(scale=0.3, size=(4, 3)):
        np.testing.assert_allclose(model.nonlinear_force(x), built.nonlinear_force(x), rtol=1e-14)


def test_units_scale_each_monomial_by_its_degree(folder):
    """mm-t-s: N / mm^p -> N / m^p is 1e3^p (1e6 for the quadratic rows, 1e9 for the cubic ones); the model's
    force in N at x in m equals the file's force in N at x in mm."""
    model = nnm.load_model(describe(folder, "dofs = [0, 2]\n", units="mm-t-s"))
    e = model.springs[1]
    np.testing.assert_allclose(e.coefficients, np.array(CO) * np.array([1e6] * 3 + [1e9] * 4)[:, None], rtol=1e-14)
    file_units = nnm.PolynomialStiffness(EX, CO)
    d_mm = np.array([0.7, -1.3])
    np.testing.assert_allclose(e.force(d_mm * 1e-3), file_units.force(d_mm), rtol=1e-13)
    # the potential in J = the file's in N mm x 1e-3
    assert e.potential(d_mm * 1e-3) == pytest.approx(file_units.potential(d_mm) * 1e-3, rel=1e-13)


def test_round_trip_through_the_nnm_file_and_nnm_solve_import(folder):
    src = describe(folder, "dofs = [0, 2]\ndirections = [[1.0, 0.0], [0.5, 1.0]]\n")
    out = folder / "model.h5"
    assert solve_main(["import", str(src), "--out", str(out)]) == 0
    back = nnm.load_model(out)
    model = nnm.load_model(src)
    assert same_element(back.springs[1], model.springs[1], rtol=0)
    assert back.dof_labels == ["node 7 uz", "node 8 uz", "node 9 uz"]
    x = np.array([0.2, -0.1, 0.4])
    np.testing.assert_allclose(back.nonlinear_force(x), model.nonlinear_force(x), rtol=0, atol=0)
    path = folder / "again.h5"
    nnm.save_model(path, back)
    assert same_element(nnm.load_model(path).springs[1], model.springs[1], rtol=0)


@pytest.mark.parametrize("element, message", [
    ("dofs = [0, 2]\nexponents_typo = 1\n", "unknown key\\(s\\) exponents_typo"),
    ("dofs = [0, 5]\n", "dofs = \\[0, 5\\] must list 0-based DOF indices of the model \\(0..2\\)"),
    ("dofs = [0, 2]\nnodes = [7, 9]\n", "give dofs or nodes, not both"),
    ("nodes = [7, 9]\n", "nodes need direction"),
    ("nodes = [7, 99]\ndirection = \"uz\"\n", "node 99 is not a node of the model"),
    ("nodes = [7, 9]\ndirection = [\"uz\"]\n", "1 directions for 2 nodes"),
    ("dofs = [0, 2]\ndirections = [[1.0, 0.0, 2.0], [0.5, 1.0]]\n", "directions rows have different lengths"),
    ("dofs = [0]\n", "1 dofs for 2 coordinates"),
    ("", "2 coordinates and no dofs, the model 3 DOFs"),
])
def test_bad_tables_give_one_line_naming_the_table(folder, element, message):
    p = describe(folder, element)
    with pytest.raises(NNMInputError, match=message) as err:
        nnm.load_model(p)
    assert "\n" not in str(err.value) and "[[springs]] #2" in str(err.value)


@pytest.mark.parametrize("exponents, coefficients, message", [
    ("[[2, 0], [1.5, 1]]", "[[1, 0], [0, 1]]", "exponents row 2: 1.5 is not an integer >= 0"),
    ("[[2, 0], [1, 1]]", "[[1, 0]]", "coefficients have shape \\(1, 2\\), exponents \\(2, 2\\)"),
    ("[[2, 0], [1, 1]]", "[[1, 0], [0, 1]]", "not conservative"),
    ("[[1, 0], [0, 3]]", "[[1, 0], [0, 1]]", "degree 1 < 2"),
    ("[2, 0]", "[[1, 0]]", "exponents must be a list of rows"),
    ("[[2, 0], [1, 1]]", "[[1, 0], [0, \"a\"]]", "coefficients row 2: 'a' is not a finite number"),
])
def test_bad_exponents_and_coefficients_give_one_line_and_exit_2(folder, capsys, exponents, coefficients, message):
    p = folder / "bad.toml"
    p.write_text(f'[matrices]\nmass = "M.mtx"\nstiffness = "K.mtx"\n[[springs]]\ntype = "polynomial_stiffness"\n'
                 f'dofs = [0, 1]\nexponents = {exponents}\ncoefficients = {coefficients}\n')
    with pytest.raises(NNMInputError, match=message):
        nnm.load_model(p)
    out = folder / "bad.h5"
    assert solve_main(["import", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bad.toml [[springs]] #1" in err
    assert not out.exists()


def test_nodes_need_a_dof_map_and_mixed_units_are_refused(folder):
    with pytest.raises(NNMInputError, match="nodes need a DOF map"):
        nnm.load_model(describe(folder, 'nodes = [7, 9]\ndirection = "uz"\n', dof_map=False))
    (folder / "dofs.txt").write_text("7 uz\n7 rx\n9 uz\n")
    with pytest.raises(NNMInputError, match="translations and rotations at once"):
        nnm.load_model(describe(folder, "dofs = [0, 1]\n", units="mm-t-s"))
