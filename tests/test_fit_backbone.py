"""fit_backbone: the factor on a model's nonlinear coefficients recovered from backbones computed on the model
with known factors (a branch of its own for each, not the scaling law the fit uses for cubic models)."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.errors import NNMInputError
from nnm_solver.identification import scale_nonlinear

M = np.diag([1.0, 1.0])
K = np.array([[2.0, -1.0], [-1.0, 2.0]])
CUBIC = nnm.Model(M, K, [nnm.CubicSpring(dof=0, k3=0.5), nnm.CubicSpring(dof=1, other=0, k3=0.2)])


def measured(model, dof, points, noise=0.0, seed=0, energy=3.0, **kw):
    """(amplitude, frequency) of ``points`` points spread along the computed backbone, amplitudes times 1 + noise N(0,1)."""
    b = nnm.continue_nnm(model, 1, energy, **kw)
    bb = nnm.amplitude_backbone(b, dof)
    idx = np.linspace(3, len(b) - 1, points).astype(int)
    rng = np.random.default_rng(seed)
    return bb.amplitude[idx] * (1 + noise * rng.standard_normal(points)), bb.frequency_hz[idx]


@pytest.mark.parametrize("factor", [1.7, 0.3])
def test_exact_backbones_give_the_factor_of_a_cubic_model(factor):
    a, f = measured(CUBIC.scaled(factor), 1, 15)
    fit = nnm.fit_backbone(CUBIC, 1, 1, a, f)
    assert fit.exact_scaling and fit.covered and fit.branches == 1
    assert fit.k3_factor == pytest.approx(factor, rel=1e-4)
    assert fit.model.springs[0].k3 == pytest.approx(0.5 * factor, rel=1e-4)
    assert fit.residual < 0.01


def test_one_percent_noise_gives_the_factor_within_one_percent():
    a, f = measured(CUBIC.scaled(1.7), 1, 40, noise=0.01, seed=3)
    fit = nnm.fit_backbone(CUBIC, 1, 1, a, f)
    assert fit.k3_factor == pytest.approx(1.7, rel=1e-2)
    low, high = fit.confidence
    assert low < 1.7 < high and fit.stderr < 0.01 * 1.7
    assert 0.1 < fit.residual < 3                      # the misfit is the noise, in units of amplitude_rtol


def test_a_model_without_the_scaling_law_is_recomputed_per_factor():
    pwl = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[0.0, 1.0], breakpoints=[0.3])
    model = nnm.Model(M, K, [pwl])
    truth = model.with_springs([scale_nonlinear(pwl, 2.0)])
    assert truth.springs[0].stiffnesses == (0.0, 2.0)              # slope k0 kept, the kink's slope change scaled
    a, f = measured(truth, 0, 12, method="hb", energy=2.0)
    fit = nnm.fit_backbone(model, 1, 0, a, f, method="hb")
    assert not fit.exact_scaling and fit.branches > 5
    assert fit.k3_factor == pytest.approx(2.0, rel=2e-3)


@pytest.mark.parametrize("args, message", [
    ((1, 5, [1e-2, 2e-2], [0.16, 0.17]), "dof 5 is not a DOF"),
    ((1, 0, [1e-2, 2e-2], [0.16]), "2 amplitudes for 1 frequencies"),
    ((1, 0, [1e-2, -2e-2], [0.16, 0.17]), "finite and positive"),
    ((1, 0, [1e-2], [0.16]), "at least 2"),
    ((3, 0, [1e-2, 2e-2], [0.16, 0.17]), "mode 3 is out of range"),
])
def test_bad_data_give_one_line(args, message):
    with pytest.raises(NNMInputError, match=message) as err:
        nnm.fit_backbone(CUBIC, *args)
    assert "\n" not in str(err.value)
    with pytest.raises(NNMInputError, match="no nonlinear element"):
        nnm.fit_backbone(nnm.Model(M, K), 1, 0, [1e-2, 2e-2], [0.16, 0.17])
