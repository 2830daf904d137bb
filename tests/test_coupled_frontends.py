"""Front ends on a model with an element in several coordinates (PolynomialStiffness, which has no single ``dof``):
the viewer's element text and default plot DOFs, the sweeps' file check, name its coordinates instead of failing."""
import numpy as np

import nnm_solver as nnm


def _model():
    return nnm.Model(np.eye(3), np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]]),
                     springs=[nnm.PolynomialStiffness(np.array([[1, 2], [2, 1]]), np.array([[1.0, 0.0], [0.0, 1.0]]),
                                                      dofs=[1, 2]),
                              nnm.CubicSpring(dof=0, k3=1.0)])


def test_viewer_texts_and_default_dofs():
    from nnm_viewer.info import auto_dofs
    from nnm_viewer.model_info import element_dofs
    m = _model()
    assert element_dofs(m, m.springs[0]).count("x[") == 2 and element_dofs(m, m.springs[1]).startswith("x[")
    x = np.zeros((10, 3))
    x[:, 0] = np.linspace(0, 1, 10)
    assert auto_dofs(m, x, count=1) == [0]


def test_the_sweeps_file_check_compares_coupled_elements():
    from nnm_solver.sweeps.sweep_files import _same_model
    a, b = _model(), _model()
    assert _same_model(a, b)
    c = a.with_springs([nnm.PolynomialStiffness(np.array([[1, 2], [2, 1]]), np.array([[1.0, 0.0], [0.0, 1.0]]),
                                                dofs=[0, 2]), a.springs[1]])
    assert not _same_model(a, c)
