"""ROMs from another FE code's nonlinear static solutions (nnm_fem/rom_static.py, issue 55): the load cases to run,
the displacements solved here by a different static solver (scipy's hybrid Powell on the FE force, standing in for
the other code), and the ROM against the exact condensed energy (nnm_fem.constrained_static, Lagrange multipliers)
at points that are not samples, and its backbone against the hinged beam's closed form."""
import numpy as np
import pytest
import scipy.optimize as so

import nnm_fem
import nnm_solver as nnm
from nnm_fem.rom import constrained_static, linear_modes
from nnm_fem.vk_beam import hinged_backbone

L, H, B, E, RHO = 1.0, 0.01, 0.02, 210e9, 7800.0


def other_code(structure, loads):
    """The 'other FE code': each load's nonlinear equilibrium by scipy's root finder from the linear solution."""
    K = structure.K.toarray()
    out = []
    for F in loads:
        sol = so.root(lambda x: nnm_fem.internal_force(structure, x) - F, np.linalg.solve(K, F),
                      jac=lambda x: nnm_fem.tangent_stiffness(structure, x).toarray(), method="hybr", tol=1e-13)
        assert sol.success, sol.message
        out.append(sol.x)
    return np.array(out)


@pytest.fixture(scope="module")
def beam():
    return nnm_fem.beam_structure(L, H, B, E, RHO, 8, "hinged")


def test_the_rom_equals_the_condensed_energy_between_its_samples(beam):
    """Modes 1 and 3 (the symmetric ones), loads scaled to two thicknesses: 12 static solutions.  Measured: the
    modal force within 1.2e-5 of the exact condensed gradient at 0.3, 0.7 and 1 of the scale (off the samples), the
    expansion within 1.3e-4 of the exact equilibrium."""
    omega2, Phi = linear_modes(beam, [1, 3])
    loads = nnm_fem.static_load_cases(beam.M, Phi, omega2, 2 * H)
    assert loads.shape == (12, beam.n)
    rom = nnm_fem.rom_from_static_solutions(beam.M, Phi, omega2, loads, other_code(beam, loads), modes=[1, 3])
    assert rom.samples == 12 and rom.fit_residual < 1e-5 and rom.model.n == 2
    q0 = 2 * H / np.max(np.abs(Phi), axis=0)
    for frac in (0.3, 0.7, 1.0):
        q = q0 * np.array([frac, 0.37 * frac])
        x, mu, ok = constrained_static(beam, Phi, q, steps=6)
        assert ok
        f_nl = mu - omega2 * q
        assert np.abs(rom.force(q) - f_nl).max() < 1e-4 * np.abs(f_nl).max()
        assert np.abs(rom.expand(q) - x).max() < 1e-3 * np.abs(x).max()


def test_a_one_mode_rom_from_static_solutions_follows_the_closed_form(beam):
    """The hinged beam on mode 1 from 4 static solutions: NNM 1 to two thicknesses within 2e-4 of the closed form
    (measured 5.7e-5; the 8-element mesh's own linear error is 1.6e-5)."""
    omega2, Phi = linear_modes(beam, [1])
    loads = nnm_fem.static_load_cases(beam.M, Phi, omega2, 2 * H)
    rom = nnm_fem.rom_from_static_solutions(beam.M, Phi, omega2, loads, other_code(beam, loads))
    branch = nnm.continue_nnm(rom.model, 1, float(hinged_backbone(2 * H, L, H, E, RHO)[1]) * B)
    assert branch.status == "done"
    mid = beam.labels.index("node 9 uz")
    a = np.array([abs(rom.expand(q)[mid]) for q in branch.x0]) / H
    assert a.max() > 1.99
    err = branch.frequency_hz / hinged_backbone(a * H, L, H, E, RHO)[0] - 1
    assert np.abs(err).max() < 2e-4


def test_bad_static_solutions_get_one_clear_line(beam):
    omega2, Phi = linear_modes(beam, [1, 3])
    loads = nnm_fem.static_load_cases(beam.M, Phi, omega2, H)
    X = other_code(beam, loads[:2])
    with pytest.raises(nnm.NNMInputError, match="do not determine"):
        nnm_fem.rom_from_static_solutions(beam.M, Phi, omega2, loads[:2], X)
    pressure = np.ones((2, beam.n))
    with pytest.raises(nnm.NNMInputError, match="not a modal load"):
        nnm_fem.rom_from_static_solutions(beam.M, Phi, omega2, pressure, X)
    with pytest.raises(nnm.NNMInputError, match="mass-normalised"):
        nnm_fem.rom_from_static_solutions(beam.M, 2 * Phi, omega2, loads[:2], X)
    with pytest.raises(nnm.NNMInputError, match="finite"):
        nnm_fem.rom_from_static_solutions(beam.M, Phi, omega2, loads[:2], X * np.nan)
    with pytest.raises(nnm.NNMInputError, match="cases"):
        nnm_fem.rom_from_static_solutions(beam.M, Phi, omega2, loads[:2], X[:1])
