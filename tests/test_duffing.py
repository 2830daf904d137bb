"""Duffing backbone vs the exact period from the complete elliptic integral (reference benchmark 1)."""
import numpy as np
import pytest
from scipy.special import ellipk

import nnm_solver as nnm

from conftest import duffing_model


def exact_period(A, k):
    m = k * A ** 2 / (2 * (1 + k * A ** 2))
    return 4 * ellipk(m) / np.sqrt(1 + k * A ** 2)


def amplitude_from_energy(E, k):
    """A with A^2/2 + k A^4/4 = E (the turning-point amplitude of the orbit of energy E)."""
    if k == 0:
        return np.sqrt(2 * E)
    return np.sqrt((-1 + np.sqrt(1 + 4 * k * E)) / k)


def _rel_errors(branch, k):
    A = np.abs(branch.x0[:, 0])
    assert np.all(np.abs(branch.v0[:, 0]) < 1e-5 * A)   # t=0 at the turning point (phase condition)
    return branch.period / exact_period(amplitude_from_energy(branch.energy, k), k) - 1


@pytest.mark.parametrize("k", [1.0, -0.2])
def test_backbone_matches_elliptic_period(k):
    b = nnm.continue_nnm(duffing_model(k), mode=1, energy_max=2.0 if k > 0 else 0.6, steps_per_period=200)
    assert b.status == "done"
    err = _rel_errors(b, k)
    # Newmark (average acceleration) period error: (w h)^2 / 12 = (2 pi / 200)^2 / 12 = 8.2e-5
    assert np.max(np.abs(err)) < 1.2e-4
    assert b.frequency_hz[-1] > b.frequency_hz[0] if k > 0 else b.frequency_hz[-1] < b.frequency_hz[0]
    # energy of the first point agrees with A^2/2 + k A^4/4
    A, v = b.x0[:, 0], b.v0[:, 0]
    assert np.allclose(b.energy, v ** 2 / 2 + A ** 2 / 2 + k * A ** 4 / 4, rtol=1e-12)


def test_second_order_convergence_in_steps_per_period():
    m = duffing_model(1.0)
    errs = {}
    for spp in (100, 200, 1000):
        b = nnm.continue_nnm(m, mode=1, energy_max=1.0, steps_per_period=spp, tol=1e-9, integrator="newmark",
                             freq_tol=None)                      # the fixed step whose order is measured
        errs[spp] = np.max(np.abs(_rel_errors(b, 1.0)))
    assert errs[100] / errs[200] == pytest.approx(4.0, rel=0.05)
    assert errs[200] / errs[1000] == pytest.approx(25.0, rel=0.05)
    assert errs[1000] < 5e-6


def test_full_period_and_half_period_shooting_agree():
    m = duffing_model(1.0)
    bh = nnm.continue_nnm(m, mode=1, energy_max=1.0, symmetric=True, tol=1e-9)
    bf = nnm.continue_nnm(m, mode=1, energy_max=1.0, symmetric=False, tol=1e-9)
    f_full = np.interp(bh.energy, bf.energy, bf.frequency_hz)
    inside = (bh.energy >= bf.energy[0]) & (bh.energy <= bf.energy[-1])
    assert np.allclose(bh.frequency_hz[inside], f_full[inside], rtol=1e-7)
