"""Condensed ROMs (nnm_fem.rom) of von Karman beams and plates against their full models (static parts)."""
import numpy as np
import pytest

from nnm_fem import beam_structure, condensed_rom, constrained_static, plate_structure
from nnm_fem.rom import linear_modes, membrane_static
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


def test_clamped_rom_is_the_membrane_condensed_full_model():
    """relax='membrane': the condensed energy of a flat von Karman beam is exactly quartic; the fit reproduces the
    full model's static modal forces and in-plane displacements off the samples, independent of scale and modes."""
    s = beam_structure(L, H, B, E, RHO, 12, "clamped")
    rom = condensed_rom(s, [1, 3], H)
    uz = [k for k, lab in enumerate(s.labels) if lab.endswith("uz")]
    ux = [k for k, lab in enumerate(s.labels) if lab.endswith("ux")]
    q = np.array([0.7, -0.4]) * H / np.max(np.abs(rom.Phi[uz]), axis=0)
    x, mu, ok = membrane_static(s, rom.Phi, q, ux)
    assert ok
    g = mu - rom.omega2 * q
    assert np.linalg.norm(rom.force(q) - g) < 1e-8 * np.linalg.norm(g)
    assert np.linalg.norm(rom.expand(q) - x) < 1e-8 * np.linalg.norm(x)     # in-plane motion quadratic in q
    eps = 1e-6 * np.abs(q)
    grad = [(rom.potential(q + e) - rom.potential(q - e)) / (2 * e[k]) for k, e in enumerate(np.diag(eps))]
    assert np.allclose(grad, rom.force(q), rtol=1e-6)                        # a conservative ROM
    k1111 = rom.coefficients[rom.exponents.tolist().index([3, 0]), 0]
    for modes, scale in (([1], H), ([1, 3], 2 * H), ([1, 3, 5], H / 2)):
        other = condensed_rom(s, modes, scale)
        assert other.coefficients[other.exponents.tolist().index([3] + [0] * (len(modes) - 1)), 0] == \
            pytest.approx(k1111, rel=1e-7)


def test_implicit_condensation_depends_on_scale_and_tends_to_membrane():
    """relax='all' lets the other modes relax too: its quartic fit depends on the scale (a convergence check) and
    tends to the membrane-only value as the scale goes to zero (the relaxation is of higher order)."""
    s = beam_structure(L, H, B, E, RHO, 12, "clamped")
    k_mem = condensed_rom(s, [1], H).coefficients[0, 0]
    d = [abs(condensed_rom(s, [1], sc, relax="all").coefficients[0, 0] / k_mem - 1) for sc in (H, H / 2, H / 4)]
    assert d[0] > 1e-2 and d[1] < d[0] / 3 and d[2] < d[1] / 3           # measured 4.1e-2, 1.2e-2, 3.2e-3
    x, mu, ok = constrained_static(s, linear_modes(s, [1])[1], np.array([1e-3]))
    assert ok


def test_plate_rom_is_fitted_and_even():
    s = plate_structure(0.3, 0.3, 0.002, E, 0.3, RHO, 4, "clamped")
    rom = condensed_rom(s, [1], 0.002)
    assert rom.exponents.tolist() == [[3]]
    assert rom.coefficients[0, 0] > 0 and rom.fit_residual < 1e-8


def test_rom_bad_input():
    s = beam_structure(L, H, B, E, RHO, 4, "hinged")
    for modes, scale, relax in (([0], H, "all"), ([1, 1], H, "all"), ([1], -H, "all"), ([1], float("nan"), "all"),
                                ([1], H, "some")):
        with pytest.raises(NNMInputError):
            condensed_rom(s, modes, scale, relax=relax)


def test_geometric_plate_example_fast(tmp_path):
    """examples/geometric_plate.py --fast: one- and three-mode ROMs of the clamped plate agree at small amplitude
    and part as the coupled modes 5, 6 take energy (the convergence check in the number of modes)."""
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "examples" / "geometric_plate.py"
    spec = importlib.util.spec_from_file_location("geometric_plate_example", path)
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    runs, table = ex.main(["--fast", "--out-dir", str(tmp_path)])
    one, three = table[(1,)], table[(1, 5, 6)]
    assert all(runs[m][0].fit_residual < 1e-10 for m in runs)
    assert abs(one[0] / three[0] - 1) < 1e-3                  # a = h/2: measured 4.7e-4
    assert 1e-3 < abs(one[1] / three[1] - 1) < 2e-2           # a = h: measured 7.8e-3
    assert one[1] > runs[(1,)][1].frequency_hz[0] * 1.1       # hardening
    assert (tmp_path / "geometric_plate_backbone.png").exists()
