"""von Karman beams as nnm Models: the PolynomialStiffness elements against the FE energy, and NNM 1 of the hinged
beam against its closed-form backbone (ROM and full model)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

import nnm_solver as nnm
from nnm_fem import (GeometricStructure, beam_structure, condensed_rom, internal_force, tangent_stiffness,
                     von_karman_beam)
from nnm_fem.vk_beam import hinged_backbone

L, H, B, E, RHO = 1.0, 0.01, 0.02, 70e9, 2700.0


def exact_frequency(a):
    """a'' + w0^2 (a + a^3 / (4 r^2)) = 0, written out again (not through nnm_fem.vk_beam)."""
    w0 = (np.pi / L) ** 2 * np.sqrt(E * H ** 2 / 12 / RHO)
    kap = 3 * (np.asarray(a) / H) ** 2                     # a^2 / (4 r^2), r^2 = h^2 / 12
    return w0 * np.sqrt(1 + kap) / (4 * ellipk(kap / (2 * (1 + kap))))     # 1 / period (Hz)


def test_closed_form_against_direct_integration():
    w0 = (np.pi / L) ** 2 * np.sqrt(E * H ** 2 / 12 / RHO)
    for a in (0.5 * H, 2 * H):
        rhs = lambda t, y: [y[1], -w0 ** 2 * (y[0] + y[0] ** 3 / (4 * H ** 2 / 12))]  # noqa: E731
        hit = lambda t, y: y[1]                                                       # noqa: E731
        hit.direction = 1.0
        hit.terminal = True
        sol = solve_ivp(rhs, (0, 1.0), [a, 0.0], events=hit, rtol=1e-12, atol=1e-14 * a)
        period = sol.t_events[0][0]                        # from the top to the bottom and back: v crosses 0 upwards
        period = 2 * period                                # half a period from a to -a
        f, _ = hinged_backbone(a, L, H, E, RHO)
        assert f == pytest.approx(1 / period, rel=1e-8)
        assert exact_frequency(a) == pytest.approx(f, rel=1e-12)


def test_model_elements_are_the_fe_energy():
    s = beam_structure(L, H, B, E, RHO, 6, "clamped")
    model = von_karman_beam(L, H, B, E, RHO, 6, ends="clamped")
    assert len(model.springs) == 12 and all(isinstance(e, nnm.PolynomialStiffness) for e in model.springs)
    assert model.dof_labels == s.labels and model.mesh.displacement_map.shape[1] == model.n
    x = np.random.default_rng(3).standard_normal(model.n) * H
    f = s.energy.force(x)
    assert np.max(np.abs(model.nonlinear_force(x) - f)) < 1e-12 * np.max(np.abs(f))
    assert model.energy(x, 0 * x) == pytest.approx(s.strain_energy(x), rel=1e-12)
    back = GeometricStructure.from_model(model)              # the law read back from the elements
    assert np.allclose(internal_force(model, x), s.internal_force(x), rtol=0, atol=1e-12 * np.max(np.abs(f)))
    assert abs(tangent_stiffness(model, x) - s.tangent(x)).max() < 1e-12 * abs(s.tangent(x)).max()
    assert back.n == s.n


def test_rom_backbone_follows_the_closed_form_to_two_thicknesses():
    rom = condensed_rom(beam_structure(L, H, B, E, RHO, 8, "hinged"), [1], H)
    e_max = float(hinged_backbone(2 * H, L, H, E, RHO)[1]) * B
    branch = nnm.continue_nnm(rom.model, 1, energy_max=e_max)
    assert branch.status == "done"
    mid = beam_structure(L, H, B, E, RHO, 8, "hinged").dof("node 9 uz")
    a = np.abs(rom.expand(branch.x0)[:, mid])
    assert a[-1] == pytest.approx(2 * H, rel=1e-3)
    err = branch.frequency_hz / hinged_backbone(a, L, H, E, RHO)[0] - 1
    assert np.max(np.abs(err)) < 1e-4                       # measured 5.7e-5 (8 elements; the linear part 1.6e-5)
