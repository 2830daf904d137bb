"""integrators/gauss: the step's constants reused for the same system and h (a shooting iterate's residual, its
Jacobian and its point's stability maps share h; issue 52): the same object, and sweeps with it equal to sweeps with
freshly built constants bit for bit."""
import dataclasses

import numpy as np

import nnm_solver as nnm
from nnm_solver.integrators import gauss, gauss_constants
from nnm_solver.model.modal import modal_system


def chain():
    n = 6
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return modal_system(nnm.Model(np.eye(n), K, springs=[nnm.CubicSpring(dof=0, k3=0.5),
                                                         nnm.CubicSpring(dof=3, k3=0.2)]))


def test_the_same_system_and_step_reuse_one_object_and_another_step_does_not():
    sys_ = chain()
    h = 0.0123
    k = gauss.constants(sys_, h, 3)
    assert gauss.constants(sys_, h, 3) is k
    assert gauss.constants(sys_, h * (1 + 1e-15), 3) is not k and gauss.constants(sys_, h, 2) is not k
    assert gauss.constants(chain(), h, 3) is not k            # another system (equal arrays, other objects)
    fresh = gauss.GaussConstants(sys_.omega2, sys_.Bq, h, 3)
    for name in ("C1", "Cc", "F", "G", "Minv", "A_lin", "E"):
        assert np.array_equal(getattr(k, name), getattr(fresh, name))


def test_sweeps_with_reused_constants_equal_fresh_ones_bit_for_bit(monkeypatch):
    sys_ = chain()
    rng = np.random.default_rng(3)
    q0, v0, h, N = 0.5 * rng.standard_normal(6), np.zeros(6), 0.05, 40
    gauss_constants._recent.clear()
    first = gauss.sweep_sensitivity(q0, v0, h, N, sys_.kernel, 3)
    again = gauss.sweep_sensitivity(q0, v0, h, N, sys_.kernel, 3)        # the cached constants
    monkeypatch.setattr(gauss_constants, "KERNELS", dataclasses.replace(gauss_constants.KERNELS, gauss_constants_kept=0))  # no reuse
    gauss_constants._recent.clear()
    fresh = gauss.sweep_sensitivity(q0, v0, h, N, sys_.kernel, 3)
    assert not gauss_constants._recent
    for a, b, c in zip(first, again, fresh):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    assert first[-1] and np.max(np.abs(first[2])) > 0
