"""Branch.reference_motion (orbits/reference.py): the stored state of a converged point integrated by scipy's
DOP853 over its stored period agrees with the solver's own orbit (Branch.motion) to that integrator's
discretisation error, with no compiled kernel (issue 32, item 4: the viewer animates it while numba compiles)."""
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.errors import NNMInputError
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.reference import reference_orbit, reference_steps

ROOT = Path(__file__).resolve().parents[1]


def accurate_points(branches, count=2):
    """(branch, i) of stable points of gauss6 shooting branches whose estimated relative frequency error is
    below 1e-6: where the discrete orbit is the exact flow to ~1e-6 (picked from the file, which may be
    rebuilt)."""
    out = []
    for b in branches:
        if getattr(b.settings, "integrator", None) != "gauss6" or b.freq_error is None:
            continue
        ok = np.flatnonzero(np.asarray(b.stable) & (np.nan_to_num(np.asarray(b.freq_error), nan=1.0) < 1e-6))
        out += [(b, int(i)) for i in ok[[0, -1]]] if len(ok) else []
        if len(out) >= count:
            return out[:count]
    return out


def test_reference_orbit_agrees_with_the_integrators_on_the_shipped_aircraft():
    branches = nnm.load_branches(ROOT / "assets" / "paris.h5")
    points = accurate_points(branches)
    assert points, "no stable gauss6 point with a small frequency error in assets/paris.h5"
    for b, i in points:
        t_ref, x_ref = b.reference_motion(i, samples=200)
        t, x = b.motion(i, samples=200)
        np.testing.assert_allclose(t_ref, t)
        # the shipped branches are gauss6 at 100 steps (the default): the discrete orbit is the exact flow to 6.3e-6 of
        # the peak at mode 10's point 14 (at 200 steps, as shipped before: 1e-9 to 1.2e-7)
        assert np.abs(x_ref - x).max() < 2e-5 * np.abs(x).max(), (b.name, i)
        # the half-period symmetry the shooting used holds for the exact flow too: the whole period agrees,
        # less closely (the error has twice the time to grow)
        xs, _ = reference_orbit(modal_system(b.model), b.x0[i], b.v0[i], b.period[i], 200, symmetric=False)
        assert np.abs(xs - x).max() < 1e-4 * np.abs(x).max(), (b.name, i)


def test_reference_orbit_is_the_exact_flow_of_a_linear_mode():
    """Linear model: x(t) = a phi_k cos(2 pi f_k t) exactly; the reference reproduces it to ~rtol."""
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    model = nnm.Model(np.eye(2), K, springs=[])
    freqs, shapes = model.linear_modes()
    system = modal_system(model)
    a, f = 0.3, freqs[1]
    x, v = reference_orbit(system, a * shapes[:, 1], np.zeros(2), 1 / f, 64, symmetric=True, rtol=1e-10)
    t = np.arange(64) / (64 * f)
    np.testing.assert_allclose(x, a * np.cos(2 * np.pi * f * t)[:, None] * shapes[:, 1][None], atol=1e-8 * a)
    np.testing.assert_allclose(v, -a * 2 * np.pi * f * np.sin(2 * np.pi * f * t)[:, None] * shapes[:, 1][None],
                               atol=1e-8 * a * 2 * np.pi * f)


def test_reference_orbit_rejects_bad_input():
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    system = modal_system(model)
    with pytest.raises(NNMInputError, match="samples"):
        reference_orbit(system, [0.1, 0.1], [0.0, 0.0], 6.0, 1)
    with pytest.raises(NNMInputError, match="period"):
        reference_orbit(system, [0.1, 0.1], [0.0, 0.0], -1.0, 16)


def test_reference_orbit_refuses_to_take_more_steps_than_allowed():
    """An explicit method needs steps below ~3 / omega_max: the estimate, and max_steps refusing before it
    integrates (the viewer then waits for the compiled integrator instead)."""
    b = nnm.load_branches(ROOT / "assets" / "two_dof.h5")[0]
    system = modal_system(b.model)
    T = b.period[0]
    assert reference_steps(system, T) == int(np.ceil(T * np.sqrt(system.omega2.max()) / 3)) + 1
    half = reference_steps(system, T * 127 / 256)             # symmetric: half a period (the last sample's time)
    with pytest.raises(RuntimeError, match="max_steps"):
        b.reference_motion(0, samples=256, max_steps=half - 1)
    _, x = b.reference_motion(0, samples=256, max_steps=half)
    assert np.all(np.isfinite(x))
