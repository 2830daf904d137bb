"""von Karman plate with immovable edges (nnm_fem.vk_plate): linear modes, force and tangent, strip = beam."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from nnm_fem import beam_structure, plate_structure, static_solve
from nnm_solver import NNMInputError

A_, H, E, NU, RHO = 0.5, 0.002, 70e9, 0.3, 2700.0
D = E * H ** 3 / (12 * (1 - NU ** 2))


def _lambdas(s, k=2):
    lam = np.sort(spla.eigsh(s.K.tocsc(), k=k + 1, M=s.M.tocsc(), sigma=0, which="LM")[0])
    return np.sqrt(lam[:k]) * A_ ** 2 * np.sqrt(RHO * H / D)


@pytest.mark.parametrize("edges, exact, tol", [("hinged", [2 * np.pi ** 2, 5 * np.pi ** 2], 6e-4),
                                               ("clamped", [35.9855, 73.3947], 2e-3)])   # Leissa (1969), CCCC
def test_square_plate_frequencies(edges, exact, tol):
    err = [np.abs(_lambdas(plate_structure(A_, A_, H, E, NU, RHO, n, edges)) / exact - 1) for n in (4, 6)]
    assert np.all(err[1] < tol)
    assert np.all(err[0] > 2 * err[1])


def test_force_and_tangent_against_finite_differences():
    s = plate_structure(A_, 0.7 * A_, H, E, NU, RHO, (3, 2), "clamped")
    x = np.random.default_rng(2).standard_normal(s.n) * H
    eps = 1e-6 * H
    Kfd = np.array([(s.internal_force(x + eps * e) - s.internal_force(x - eps * e)) / (2 * eps)
                    for e in np.eye(s.n)]).T
    Kt = s.tangent(x).toarray()
    assert np.max(np.abs(Kt - Kfd)) < 1e-7 * np.max(np.abs(Kt))
    grad = np.array([(s.strain_energy(x + eps * e) - s.strain_energy(x - eps * e)) / (2 * eps) for e in np.eye(s.n)])
    assert np.max(np.abs(grad - s.internal_force(x))) < 1e-7 * np.max(np.abs(grad))


def test_strip_in_cylindrical_bending_is_the_beam():
    """nu = 0, clamped at x = 0 and a, planes of symmetry at y = 0 and b: the plate deforms like the beam."""
    L, width, q = 0.5, 0.1, 2e3
    wp, wb = [], []
    for n in (4, 8):
        s = plate_structure(L, width, H, E, 0.0, RHO, (n, 2), ("clamped", "clamped", "symmetric", "symmetric"))
        sol = static_solve(s, q * s.unit_loads["pressure"], steps=5)
        assert sol.converged
        centre = sol.x[s.dof(f"node {n + 1} uz")]
        assert np.allclose(sol.x[[s.dof(f"node {n + 1 + k * (2 * n + 1)} uz") for k in (2, 4)]], centre,
                           rtol=1e-9)                        # independent of y
        wp.append(centre)
        b = beam_structure(L, H, width, E, RHO, n, "clamped")
        wb.append(static_solve(b, q * width * b.unit_loads["uniform"], steps=5).x[b.dof(f"node {n + 1} uz")])
    assert wb[1] > 1.2 * H                                   # large deflection
    assert abs(wp[1] / wb[1] - 1) < 2e-3                     # measured 1.2e-3 (8 elements), 1.6e-2 (4)
    assert abs(wp[1] / wb[1] - 1) < abs(wp[0] / wb[0] - 1) / 8


def test_bad_plate_input():
    for kw in ({"nu": 0.5}, {"elements": 1}, {"edges": "free"}, {"edges": ("clamped",) * 3}, {"a": 0.0}):
        args = dict(a=A_, b=A_, thickness=H, E=E, nu=NU, rho=RHO, elements=2, edges="clamped")
        args.update(kw)
        with pytest.raises(NNMInputError) as exc:
            plate_structure(**args)
        assert "\n" not in str(exc.value)
