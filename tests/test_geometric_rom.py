"""Condensed ROMs (nnm_fem.rom) of von Karman beams and plates against their full models (static parts)."""
import numpy as np
import pytest

from nnm_fem import beam_structure, condensed_rom, constrained_static, plate_structure
from nnm_solver import NNMInputError

L, H, B, E, RHO = 1.0, 0.01, 0.02, 70e9, 2700.0
A, I = B * H, B * H ** 3 / 12


@pytest.mark.parametrize("scale", [H, 2 * H])
def test_hinged_one_mode_rom_is_the_closed_form_duffing(scale):
    """Continuum: a'' + w0^2 (a + a^3 / (4 r^2)); for the mass-normalised q = a sqrt(rho A L / 2), k3 = w0^2 / (2 r^2 rho A L)."""
    s = beam_structure(L, H, B, E, RHO, 16, "hinged")
    rom = condensed_rom(s, [1], scale)
    assert rom.exponents.tolist() == [[3]]                  # even potential: no quadratic term
    w0 = np.sqrt(rom.omega2[0])
    assert w0 == pytest.approx(np.pi ** 2 * np.sqrt(E * I / (RHO * A * L ** 4)), rel=2e-6)
    assert rom.coefficients[0, 0] == pytest.approx(w0 ** 2 / (2 * H ** 2 / 12 * RHO * A * L), rel=2e-5)
    assert rom.fit_residual < 1e-7


def test_clamped_rom_against_condensed_full_model_off_the_samples():
    s = beam_structure(L, H, B, E, RHO, 12, "clamped")
    rom = condensed_rom(s, [1, 3], H)
    uz = [k for k, lab in enumerate(s.labels) if lab.endswith("uz")]
    q = np.array([0.7, -0.4]) * H / np.max(np.abs(rom.Phi[uz]), axis=0)
    x, mu, ok = constrained_static(s, rom.Phi, q)
    assert ok
    g = mu - rom.omega2 * q
    # U_c is quartic up to the relaxation of the other modes (order q^6): the fit at scale h absorbs it
    assert np.linalg.norm(rom.force(q) - g) < 5e-3 * np.linalg.norm(g)
    assert np.linalg.norm(rom.expand(q) - x) < 2e-3 * np.linalg.norm(x)    # membrane expansion, quadratic in q
    eps = 1e-6 * np.abs(q)
    grad = [(rom.potential(q + e) - rom.potential(q - e)) / (2 * e[k]) for k, e in enumerate(np.diag(eps))]
    assert np.allclose(grad, rom.force(q), rtol=1e-6)      # a conservative ROM


def test_clamped_rom_converges_in_modes_and_scale():
    s = beam_structure(L, H, B, E, RHO, 12, "clamped")
    k3 = {}
    for modes in ([1], [1, 3], [1, 3, 5]):
        for scale in (H, 2 * H):
            rom = condensed_rom(s, modes, scale)
            k3[len(modes), scale] = rom.coefficients[rom.exponents.tolist().index([3] + [0] * (len(modes) - 1)), 0]
    d1, d2 = abs(k3[2, H] / k3[1, H] - 1), abs(k3[3, H] / k3[2, H] - 1)
    assert d2 < d1 / 5 and d2 < 1e-3                         # measured 4.7e-3 then 5.8e-4
    assert abs(k3[3, 2 * H] / k3[3, H] - 1) < 1e-3


def test_plate_rom_is_fitted_and_even():
    s = plate_structure(0.3, 0.3, 0.002, E, 0.3, RHO, 4, "clamped")
    rom = condensed_rom(s, [1], 0.002)
    assert rom.exponents.tolist() == [[3]]
    assert rom.coefficients[0, 0] > 0 and rom.fit_residual < 1e-2


def test_rom_bad_input():
    s = beam_structure(L, H, B, E, RHO, 4, "hinged")
    for modes, scale in (([0], H), ([1, 1], H), ([1], -H), ([1], float("nan"))):
        with pytest.raises(NNMInputError):
            condensed_rom(s, modes, scale)
