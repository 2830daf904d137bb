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


def test_geometric_beams_example_fast(tmp_path):
    """examples/geometric_beams.py --fast: the hinged ROM on the closed form; the clamped ROM (modes 1, 3) hardens
    past its 5:1 resonance with mode 3 (a tongue where 5 f meets mode 3: the default jumps tongues above 3:1 and
    lists it) to 40 J."""
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "examples" / "geometric_beams.py"
    spec = importlib.util.spec_from_file_location("geometric_beams_example", path)
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    hinged_runs, clamped_runs = ex.main(["--fast", "--out-dir", str(tmp_path)])
    _, rows = hinged_runs["rom"]
    assert rows[-1, 0] == pytest.approx(2.0, rel=1e-3) and np.max(np.abs(rows[:, 3])) < 1e-4
    rom, branch = clamped_runs[(1, 3)]
    assert branch.status == "done" and branch.energy[-1] == pytest.approx(ex.CLAMPED_ENERGY_MAX, rel=1e-6)
    f3 = np.sqrt(rom.omega2[1]) / (2 * np.pi)
    five = [t for t in branch.tongues if t.order == 5]           # the tongue, jumped and listed
    assert five and five[0].partner_mode == 2 and five[0].skipped
    assert abs(5 * five[0].entry_frequency_hz / f3 - 1) < 0.06
    assert set(map(str, branch.labels)) == {"backbone"}
    assert branch.frequency_hz[-1] > 2 * branch.frequency_hz[0]
    assert (tmp_path / "geometric_beams_fep.png").exists()
