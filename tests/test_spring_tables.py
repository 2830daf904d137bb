"""Spring tables of imported models (issue 18): polynomial and piecewise-linear springs in MATLAB .mat files
(spring-table version 2, v5 and v7.3) and in TOML descriptions, unit conversion, old tables, bad input."""
import numpy as np
import pytest
import scipy.io

import nnm_solver as nnm
from nnm_solver import NNMFileError, NNMInputError

from test_importers import write_v73_sparse

NAN = np.nan
K3 = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])

TABLES = {
    "springs": np.array([[1, 0, 1e9]]),                                     # version 1: [dof other k3]
    "polynomial_springs": np.array([[2, 1, 2, 5e5], [3, 0, 3, 1e8], [2, 1, 3, -2e7]]),   # [dof other p c_p]
    # [dof other k0 d1 k1 d2 k2 ...]: odd, padded with NaN; asymmetric (a negative d: compression side)
    "piecewise_springs": np.array([[3, 0, 1e4, 1e-3, 5e3, 3e-3, 2e4],
                                   [1, 2, 2e4, 2e-3, 1e4, -1e-3, 8e4],
                                   [2, 0, 0.0, 5e-4, 3e4, NAN, NAN]]),
    "piecewise_eps": 2e-3,
}
EXPECTED = [
    nnm.CubicSpring(dof=0, k3=1e9),
    nnm.PolynomialSpring(dof=1, other=0, coefficients={2: 5e5, 3: -2e7}),
    nnm.PolynomialSpring(dof=2, coefficients={3: 1e8}),
    nnm.PiecewiseLinearSpring(dof=2, stiffnesses=[1e4, 5e3, 2e4], breakpoints=[1e-3, 3e-3], eps=2e-3),
    nnm.PiecewiseLinearSpring(dof=0, other=1, stiffnesses=[2e4, 1e4], breakpoints=[2e-3], eps=2e-3,
                              stiffnesses_negative=[2e4, 8e4], breakpoints_negative=[1e-3]),
    nnm.PiecewiseLinearSpring(dof=1, stiffnesses=[0.0, 3e4], breakpoints=[5e-4], eps=2e-3),
]


def _mat(path, **tables):
    scipy.io.savemat(path, {"M": np.eye(3), "K": 1e4 * K3, **tables})
    return path


def test_mat_version_2_tables_v5_and_v73(tmp_path):
    m = nnm.load_model(_mat(tmp_path / "m.mat", **TABLES))
    assert m.springs == EXPECTED
    assert not m.elements.odd                                  # the quadratic term and the asymmetric spring
    np.testing.assert_allclose(m.K_linear, 1e4 * K3 + np.diag([0.0, 0.0, 1e4])
                               + 2e4 * np.array([[1, -1, 0], [-1, 1, 0], [0, 0, 0]]))
    write_v73_sparse(tmp_path / "v73.mat", {"M": np.eye(3), "K": 1e4 * K3, **TABLES})
    assert nnm.load_model(tmp_path / "v73.mat").springs == EXPECTED
    # the HDF5 file keeps them (nnm-solve import)
    nnm.save_model(tmp_path / "m.h5", m)                     # a pure-cubic polynomial comes back as a CubicSpring
    back = nnm.load_model(tmp_path / "m.h5").elements
    for key in ("B", "powers", "coefficients", "kinks", "k0"):
        np.testing.assert_array_equal(getattr(back, key), getattr(m.elements, key))


def test_mat_old_tables_still_load_and_versions_are_checked(tmp_path):
    old = nnm.load_model(_mat(tmp_path / "old.mat", springs=np.array([[1, 0, 1e9], [2, 3, -5.0]])))
    assert old.springs == [nnm.CubicSpring(dof=0, k3=1e9), nnm.CubicSpring(dof=1, other=2, k3=-5.0)]
    assert nnm.load_model(_mat(tmp_path / "v1.mat", springs=np.array([[1, 0, 1e9]]), springs_version=1)).springs \
        == [nnm.CubicSpring(dof=0, k3=1e9)]
    with pytest.raises(NNMFileError, match="springs_version = 1 but the file has version-2 tables"):
        nnm.load_model(_mat(tmp_path / "v1b.mat", polynomial_springs=np.array([[1, 0, 2, 1.0]]), springs_version=1))
    with pytest.raises(NNMFileError, match=r"springs_version = \[3.0\] is not a spring-table version .* update nnm"):
        nnm.load_model(_mat(tmp_path / "v3.mat", springs_version=3))


@pytest.mark.parametrize("tables, match", [
    (dict(polynomial_springs=np.array([[1, 0, 1, 5.0]])), "polynomial_springs row 1: power 1 is not an integer >= 2"),
    (dict(polynomial_springs=np.array([[1, 0, 2.5, 5.0]])), "power 2.5 is not an integer"),
    (dict(polynomial_springs=np.array([[1, 0, 3, 1.0], [1, 0, 3, NAN]])), "row 2: coefficient nan is not finite"),
    (dict(polynomial_springs=np.array([[1, 0, 3, 1.0], [1, 0, 3, 2.0]])), "a second d\\^3 term"),
    (dict(polynomial_springs=np.array([[1, 0, 3]])), "'polynomial_springs' must have 4 columns"),
    (dict(piecewise_springs=np.array([[1, 0, 1.0, 0.2, 2.0, 0.1, 3.0]])),
     "piecewise_springs row 1: PiecewiseLinearSpring breakpoints \\[0.2, 0.1\\] are not strictly increasing"),
    (dict(piecewise_springs=np.array([[1, 0, 1.0, 0.0, 2.0]])), "row 1: PiecewiseLinearSpring breakpoint 0.0 is not pos"),
    (dict(piecewise_springs=np.array([[1, 0, 1.0, 0.1, NAN, 0.2, 3.0]])), "NaN only as trailing padding"),
    (dict(piecewise_springs=np.array([[1, 0, 1.0, 0.1, 2.0, 0.3, NAN]])), "expected k0 followed by pairs"),
    (dict(piecewise_springs=np.array([[4, 0, 1.0, 0.1, 2.0]])), "piecewise_springs row 1: dof 4 is not a DOF"),
    (dict(piecewise_springs=np.array([[1, 0.5, 1.0, 0.1, 2.0]])), "dof and other must be whole numbers"),
    (dict(springs=np.array([[1.5, 0, 0.5]])), "springs row 1: dof and other must be whole numbers"),  # (was DOF 2)
    (dict(springs="abc"), "'springs' must be a numeric table"),                           # (a traceback before)
    (dict(piecewise_springs=np.array([[1, 0, 1.0, 0.1, 2.0]]), piecewise_eps="x"), "'piecewise_eps' must be a numeric"),
    (dict(piecewise_springs=np.array([[1, 0, 1.0, 0.1, 2.0]]), piecewise_eps=0.7), "eps=0.7 must be in"),
])
def test_mat_bad_spring_tables_one_line(tmp_path, tables, match):
    with pytest.raises(NNMFileError, match=match) as exc:
        nnm.load_model(_mat(tmp_path / "bad.mat", **tables))
    assert "\n" not in str(exc.value) and "bad.mat" in str(exc.value)


def _toml(folder, springs, units=None, mat_tables=None):
    _mat(folder / "m.mat", **(mat_tables or {}))
    head = f'units = "{units}"\n' if units else ""
    p = folder / "model.toml"
    p.write_text(head + '[matrices]\nfile = "m.mat"\n' + springs)
    return p


def test_toml_piecewise_and_polynomial_springs_with_units(tmp_path):
    text = ('[[springs]]\ntype = "piecewise_linear"\ndof = 2\nstiffnesses = [1e4, 5e3, 2e4]\n'
            'breakpoints = [1e-3, 3e-3]\neps = 2e-3\n'
            '[[springs]]\ntype = "piecewise_linear"\ndof = 0\nother = 1\nstiffnesses = [2e4, 1e4]\nbreakpoints = [2e-3]\n'
            'stiffnesses_negative = [2e4, 8e4]\nbreakpoints_negative = [1e-3]\neps = 2e-3\n'
            '[[springs]]\ntype = "piecewise_linear"\ndof = 1\nstiffnesses = [0, 3e4]\nbreakpoints = [5e-4]\neps = 2e-3\n')
    m = nnm.load_model(_toml(tmp_path, text))
    assert m.springs == EXPECTED[3:]
    # mm-t-s: stiffnesses in N/mm (x 1e3 in SI), breakpoints in mm (x 1e-3); the .mat tables convert alike
    mm = ('[[springs]]\ntype = "piecewise_linear"\ndof = 2\nstiffnesses = [10.0, 5.0, 20.0]\nbreakpoints = [1.0, 3.0]\n'
          'eps = 2e-3\n')
    m = nnm.load_model(_toml(tmp_path, mm, units="mm-t-s",
                             mat_tables=dict(piecewise_springs=np.array([[3, 0, 10.0, 1.0, 5.0, 3.0, 20.0]]),
                                             polynomial_springs=np.array([[3, 0, 2, 1.0]]), piecewise_eps=2e-3)))
    pw = nnm.PiecewiseLinearSpring(dof=2, stiffnesses=[1e4, 5e3, 2e4], breakpoints=[1e-3, 3e-3], eps=2e-3)
    assert len(m.springs) == 3 and m.springs[0].coefficients[2] == pytest.approx(1e6, rel=1e-14)
    for s in m.springs[1:]:
        np.testing.assert_allclose(s.stiffnesses, pw.stiffnesses, rtol=1e-14)
        np.testing.assert_allclose(s.breakpoints, pw.breakpoints, rtol=1e-14)
        assert s.eps == pw.eps and s.dof == 2
    b = nnm.continue_nnm(m, 1, 1e-3, max_points=5)                           # and it computes
    assert len(b) >= 2


@pytest.mark.parametrize("text, match", [
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = [1.0, 2.0, 3.0]\nbreakpoints = [0.2, 0.1]\n',
     "\\[\\[springs\\]\\] #1: PiecewiseLinearSpring breakpoints \\[0.2, 0.1\\] are not strictly increasing"),
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = [1.0, 2.0]\nbreakpoints = [-0.1]\n',
     "#1: PiecewiseLinearSpring breakpoint -0.1 is not positive"),
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = 1.0\nbreakpoints = [0.1]\n', "stiffnesses must be a list"),
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = [1.0, "x"]\nbreakpoints = [0.1]\n', "stiffnesses\\[1\\]"),
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = [1.0, 2.0]\n', "missing breakpoints"),
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = [1.0, 2.0]\nbreakpoints = [0.1]\ngap = 0.1\n',
     "unknown key\\(s\\) gap"),
    ('type = "piecewise_linear"\ndof = 0\nstiffnesses = [1.0, 2.0]\nbreakpoints = [0.1]\nstiffnesses_negative = [1.0]\n',
     "give both stiffnesses_negative and breakpoints_negative"),
    ('type = "polynomial"\ndof = 0\ncoefficients = {3 = nan}\n', "coefficients.3 = nan is not"),
])
def test_toml_bad_springs_one_line(tmp_path, text, match):
    with pytest.raises(NNMInputError, match=match) as exc:
        nnm.load_model(_toml(tmp_path, "[[springs]]\n" + text))
    assert "\n" not in str(exc.value) and "model.toml" in str(exc.value)


def test_a_mat_files_dof_labels_are_its_dof_map_in_a_description(tmp_path):
    """A .mat named in a description keeps its dof_labels as the DOF map, as when it is loaded alone (they were
    dropped: springs by node refused with 'these matrix files have none')."""
    labels = np.array(["node 1 ux", "node 2 ux", "node 3 ux"], dtype=object)
    p = _toml(tmp_path, '\n[[springs]]\nnode = 2\ndirection = "ux"\nk3 = 5.0\n', mat_tables=dict(dof_labels=labels))
    m = nnm.load_model(p)
    assert m.dof_labels == list(labels) == nnm.load_model(tmp_path / "m.mat").dof_labels
    assert len(m.springs) == 1 and m.springs[0].dof == 1 and m.springs[0].k3 == 5.0
