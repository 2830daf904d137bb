"""von Karman beam with immovable ends (nnm_fem.vk_beam): linear modes, force and tangent, static large deflection."""
import numpy as np
import pytest
import scipy.linalg as sla

from nnm_fem import beam_structure, static_solve
from nnm_fem.vk_beam import beam_mesh
from nnm_solver import NNMInputError

L, H, B, E, RHO = 1.0, 0.01, 0.02, 70e9, 2700.0          # aluminium strip, L / h = 100
A, I = B * H, B * H ** 3 / 12


def _frequencies(s, k):
    lam = sla.eigh(s.K.toarray(), s.M.toarray(), eigvals_only=True)
    return np.sqrt(lam[:k]) / (2 * np.pi)


@pytest.mark.parametrize("ends, beta", [("hinged", np.pi * np.arange(1, 4)),
                                        ("clamped", np.array([4.730040745, 7.853204624, 10.99560784]))])
def test_linear_frequencies_converge_to_euler_bernoulli(ends, beta):
    exact = beta ** 2 / (2 * np.pi) * np.sqrt(E * I / (RHO * A * L ** 4))
    err = [np.abs(_frequencies(beam_structure(L, H, B, E, RHO, n, ends), 3) / exact - 1) for n in (8, 16)]
    assert np.all(err[1] < 5e-4)
    assert np.all(err[0] / err[1] > 12)                 # cubic Hermite, consistent mass: h^4


def test_axial_modes_and_total_mass():
    s = beam_structure(L, H, B, E, RHO, 8, "hinged")
    ux = [i for i, lab in enumerate(s.labels) if lab.endswith("ux")]
    lam = sla.eigh(s.K.toarray()[np.ix_(ux, ux)], s.M.toarray()[np.ix_(ux, ux)], eigvals_only=True)
    f_axial = np.sqrt(lam[0]) / (2 * np.pi)
    assert f_axial == pytest.approx(np.sqrt(E / RHO) / (2 * L), rel=1e-4)
    one = np.zeros(s.n)
    one[[i for i, lab in enumerate(s.labels) if lab.endswith("uz")]] = 1.0    # rigid heave of the interior
    assert one @ s.M @ one < RHO * A * L


@pytest.mark.parametrize("ends", ["hinged", "clamped"])
def test_force_and_tangent_against_finite_differences(ends):
    s = beam_structure(L, H, B, E, RHO, 6, ends)
    x = np.random.default_rng(1).standard_normal(s.n) * H
    eps = 1e-6 * H
    Kfd = np.array([(s.internal_force(x + eps * e) - s.internal_force(x - eps * e)) / (2 * eps)
                    for e in np.eye(s.n)]).T
    Kt = s.tangent(x).toarray()
    assert np.max(np.abs(Kt - Kfd)) < 1e-7 * np.max(np.abs(Kt))
    grad = np.array([(s.strain_energy(x + eps * e) - s.strain_energy(x - eps * e)) / (2 * eps) for e in np.eye(s.n)])
    f = s.internal_force(x)
    assert np.max(np.abs(grad - f)) < 1e-7 * np.max(np.abs(f))


@pytest.mark.parametrize("amplitude", [1.0, 2.0])
def test_static_sine_load_matches_closed_form(amplitude):
    """q = q0 sin(pi x / L) on the hinged beam: w = a sin(pi x / L) exactly, EI (pi/L)^4 a + EA (pi/L)^4 a^3 / 4 = q0."""
    a = amplitude * H
    q0 = E * I * (np.pi / L) ** 4 * a + E * A * (np.pi / L) ** 4 * a ** 3 / 4
    errs = []
    for n in (8, 16):
        bm = beam_mesh(L, H, B, E, RHO, n, "hinged")
        s = beam_structure(L, H, B, E, RHO, n, "hinged")
        sol = static_solve(s, bm.load_vector(lambda x: q0 * np.sin(np.pi * x / L))[bm.free()], steps=4)
        assert sol.converged and sol.residual < 1e-10
        errs.append(abs(sol.x[s.dof(f"node {n + 1} uz")] / a - 1))
    assert errs[1] < 1e-5
    assert errs[0] / errs[1] > 12                        # quadratic axial field: no membrane locking, N^-4


def test_clamped_static_deflection_converges():
    w = []
    for n in (4, 8, 32):
        bm = beam_mesh(L, H, B, E, RHO, n, "clamped")
        s = beam_structure(L, H, B, E, RHO, n, "clamped")
        sol = static_solve(s, bm.load_vector(lambda x: 2e3 + 0 * x)[bm.free()], steps=5)
        assert sol.converged
        w.append(sol.x[s.dof(f"node {n + 1} uz")])
    assert w[2] > 1.5 * H                                 # large deflection (linear theory: 5.4 h)
    assert abs(w[1] / w[2] - 1) < 3e-4
    assert abs(w[0] / w[2] - 1) > 4 * abs(w[1] / w[2] - 1)


def test_bad_input_is_one_clear_line():
    for kw in ({"elements": 1}, {"elements": 2.5}, {"ends": "free"}, {"length": -1.0}, {"E": float("nan")}):
        args = dict(length=L, thickness=H, width=B, E=E, rho=RHO, elements=4, ends="hinged")
        args.update(kw)
        with pytest.raises(NNMInputError) as exc:
            beam_structure(**args)
        assert "\n" not in str(exc.value)
