"""The backbone against an exact one (issue 51): a symmetric 2-DOF chain with equal softening springs at both masses,
whose NNMs 1 (x1 = x2) and 2 (x1 = -x2) are invariant lines carrying a single Duffing oscillator,
x'' + w^2 x + g x^3 = 0 (g < 0), with the elliptic-integral period and a saddle at E_s = w^4 / (-2 g) (the two
masses together).  The default call and harmonic balance (default, and condensed with 9 harmonics) give every point
on the family within 1e-4 of the exact frequency, and end `escape` below the saddle."""
import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipk

import nnm_solver as nnm

G = -0.5


def chain():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]),
                     springs=[nnm.CubicSpring(dof=0, k3=G), nnm.CubicSpring(dof=1, k3=G)])


def exact_frequency(E, w2):
    """Hz of the Duffing orbit of total energy E (J) on the invariant line (each mass: x'' + w2 x + G x^3 = 0)."""
    A = brentq(lambda A: 2 * (w2 * A * A / 2 + G * A ** 4 / 4) - E, 1e-12, np.sqrt(w2 / -G) * (1 - 1e-12))
    m = G * A * A / (2 * (w2 + G * A * A))
    return np.sqrt(w2 + G * A * A) / (4 * ellipk(m))


@pytest.mark.parametrize("mode, w2", [(1, 1.0), (2, 3.0)])
@pytest.mark.parametrize("method", ["default", "hb", "hb9-condensed"])
def test_the_skip_backbone_is_the_exact_one_up_to_its_saddle(mode, w2, method):
    E_saddle = w2 ** 2 / (-2 * G)
    m = chain()
    how = {"default": nnm.Shooting(), "hb": nnm.HarmonicBalance(),
           "hb9-condensed": nnm.HarmonicBalance(harmonics=9, condensed=True)}[method]
    b = nnm.continue_nnm(m, mode, 10 * E_saddle, how, tongues=nnm.Skip(), floquet=False)
    assert b.status == "escape", b.message
    assert b.energy.max() < E_saddle
    on = np.flatnonzero(b.labels == "backbone")
    assert len(on) > 0.9 * len(b) and b.energy[on].max() > 0.95 * E_saddle     # it ends next to the saddle
    dev = np.array([abs(b.frequency_hz[i] / exact_frequency(b.energy[i], w2) - 1) for i in on])
    assert dev.max() < 1e-4, (dev.max(), b.energy[on][np.argmax(dev)])
    # each point's estimate bounds its error where the error is above the corrector's tolerance
    big = dev > 1e-7
    assert np.all(dev[big] < 3 * b.freq_error[on][big] + 1e-7)
