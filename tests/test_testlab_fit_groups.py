"""fit_backbone(groups=...): one factor per group of elements, recovered from backbones computed on a model with
known factors (issue 54); bad groups give one line."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.errors import NNMInputError

M = np.diag([1.0, 1.0])
K = np.array([[2.0, -1.0], [-1.0, 2.0]])
CUBIC = nnm.Model(M, K, [nnm.CubicSpring(dof=0, k3=0.5), nnm.CubicSpring(dof=1, other=0, k3=0.2)])
HB = dict(method="hb", harmonics=3, max_rel_step=0.5)


def measured(model, mode, dof, points=10, energy=2.0):
    b = nnm.continue_nnm(model, mode, energy, **HB)
    bb = nnm.amplitude_backbone(b, dof)
    idx = np.linspace(3, len(b) - 1, points).astype(int)
    return bb.amplitude[idx], bb.frequency_hz[idx]


@pytest.mark.slow
def test_two_groups_from_two_modes():
    """The grounded spring x 1.5, the coupling spring x 0.6: the backbones of modes 1 and 2 at DOF 1 give both."""
    truth = CUBIC.with_springs([CUBIC.springs[0].scaled(1.5), CUBIC.springs[1].scaled(0.6)])
    a1, f1 = measured(truth, 1, 1)
    a2, f2 = measured(truth, 2, 1)
    fit = nnm.fit_backbone(CUBIC, 1, 1, a1, f1, groups=[[0], [1]], also=[(2, 1, a2, f2)], **HB)
    np.testing.assert_allclose(fit.factors, [1.5, 0.6], rtol=2e-3)
    assert np.isnan(fit.k3_factor) and not fit.exact_scaling
    assert fit.model.springs[0].k3 == pytest.approx(0.75, rel=2e-3)
    assert fit.group_fit.correlation.shape == (2, 2) and all(lo < s < hi for s, (lo, hi) in
                                                              zip(fit.factors, fit.group_fit.confidence))
    assert fit.branches > 4


@pytest.mark.parametrize("kw, message", [
    (dict(groups=[[0], [0, 1]]), "element 0 is in two groups"),
    (dict(groups=[[0], [2]]), "element 2 is not an element of the model"),
    (dict(groups=[[]]), "a group is empty"),
    (dict(groups=["a"]), "groups must be lists of 0-based element indices"),
    (dict(also=[(2, 1, [1e-2, 2e-2], [0.2, 0.21])]), "with groups=[...] only"),
    (dict(groups=[[0]], also=[(2, 1, [1e-2], [0.2, 0.21])]), "1 amplitudes for 2 frequencies"),
])
def test_bad_groups_give_one_line(kw, message):
    with pytest.raises(NNMInputError, match=message.replace("[", r"\[").replace("]", r"\]").replace(".", r"\.")):
        nnm.fit_backbone(CUBIC, 1, 1, [1e-2, 2e-2], [0.16, 0.17], **kw)
