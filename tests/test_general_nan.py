"""A NaN or an escaping orbit in the general (PolynomialStiffness) sweeps (integrators/general.py) gives a failed
orbit (ok = False) that the shooting problem turns into a non-finite residual and the Newton corrector refuses
(NOT_FINITE), not a LinAlgError from the linear solve (issue 55)."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.continuation.newton import NOT_FINITE, NewtonSettings, newton_solve
from nnm_solver.integrators import general
from nnm_solver.model.modal import ModalSystem
from nnm_solver.orbits.shooting import ShootingProblem

# a softening quadratic-cubic force in two coordinates, g = grad V, V = -d1^4 / 4 + d1^2 d2 / 2 - d2^4 / 4:
# g = (-d1^3 + d1 d2, d1^2 / 2 - d2^3); large states escape
EX = [[3, 0], [1, 1], [2, 0], [0, 3]]
CO = [[-1.0, 0.0], [1.0, 0.0], [0.0, 0.5], [0.0, -1.0]]


@pytest.fixture(scope="module")
def system():
    model = nnm.Model(np.eye(2), np.diag([1.0, 4.0]), springs=[nnm.PolynomialStiffness(EX, CO)])
    return ModalSystem(model)


@pytest.mark.parametrize("stages", [1, 2, 3])
@pytest.mark.parametrize("q0", [[np.nan, 0.0], [1e60, 0.0], [30.0, 30.0]])
def test_the_sweeps_report_a_failed_orbit_instead_of_raising(system, stages, q0):
    q0, v0 = np.array(q0), np.zeros(2)
    _, _, ok = general.state(system, stages, q0, v0, 0.3, 40)
    assert not ok
    *_, ok_s = general.sensitivity(system, stages, q0, v0, 0.3, 40)
    assert not ok_s
    Q, V, ok_r = general.record(system, stages, q0, v0, 0.3, 40)
    assert not ok_r and len(Q) <= 41


@pytest.mark.parametrize("stages", [1, 2])
def test_a_finite_start_still_integrates_as_before(system, stages):
    """The guard changes nothing on a regular orbit: energy conserved to the scheme's accuracy."""
    q0, v0 = np.array([0.2, -0.1]), np.zeros(2)
    Q, V, ok = general.record(system, stages, q0, v0, 0.01, 600)
    assert ok
    x = Q @ system.Phi.T
    d1, d2 = x[:, 0], x[:, 1]
    energy = (0.5 * np.sum((V @ system.Phi.T) ** 2, axis=1) + 0.5 * (d1 ** 2 + 4 * d2 ** 2)
              - d1 ** 4 / 4 + d1 ** 2 * d2 / 2 - d2 ** 4 / 4)
    assert np.ptp(energy) < 1e-4 * energy[0]


@pytest.mark.parametrize("integrator", ["newmark", "gauss4"])
def test_the_corrector_refuses_the_failed_orbit(system, integrator):
    problem = ShootingProblem(system, 0, steps_per_period=40, integrator=integrator)
    u = problem.pack(np.array([1e60, 0.0]), np.zeros(2), 2 * np.pi)
    assert not np.all(np.isfinite(problem.residual(u)))
    r, J = problem.jacobian(u)
    assert not np.all(np.isfinite(r))
    result = newton_solve(problem, u, NewtonSettings(1e-10, 10, True))
    assert not result.converged and result.reason == NOT_FINITE
