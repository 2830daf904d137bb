"""The general Gauss kernel's band path (integrators/general_band.py, band.py) against independent references: numpy's
dense solve, the modal kernel with its dense stage LU (general.py), central differences of the state, the energy."""
import numpy as np
import pytest

import nnm_fem
import nnm_solver as nnm
from nnm_solver.integrators import general, general_band
from nnm_solver.integrators.band import band_lu, band_solve, to_band
from nnm_solver.integrators.settings import KERNELS
from nnm_solver.model.modal import ModalSystem, modal_system

L, H, B, E, RHO = 1.0, 0.01, 0.02, 210e9, 7800.0


def _beam(elements=8, springs=()):
    model = nnm_fem.von_karman_beam(L, H, B, E, RHO, elements=elements, ends="hinged")
    if springs:
        model = model.with_springs(list(model.springs) + list(springs))
    return model


def _start(system, model, elements, amplitude=H):
    """A modal start at midspan amplitude ``amplitude`` (mode 1's shape) with some velocity in mode 3."""
    mid = model.dof_labels.index(f"node {elements + 1} uz")
    x = system.Phi[:, 0] / abs(system.Phi[mid, 0]) * amplitude
    v0 = np.zeros(system.n)
    v0[2] = 2.0
    return system.to_modal(x), v0, 2 * np.pi / np.sqrt(system.omega2[0])


@pytest.mark.parametrize("kl, ku", [(0, 0), (1, 2), (3, 3), (5, 1)])
def test_band_lu_solves_like_numpy(kl, ku):
    rng = np.random.default_rng(kl * 10 + ku)
    N = 23
    A = rng.standard_normal((N, N))
    i, j = np.indices((N, N))
    A[(j < i - kl) | (j > i + ku)] = 0.0
    A[np.arange(N), np.arange(N)] *= 1e-3 if kl else 1.0          # small pivots: the row interchanges matter
    W = np.zeros((N, 2 * kl + ku + 1))
    W[i[A != 0], (j - i + kl)[A != 0]] = A[A != 0]
    piv, ok = band_lu(W, kl, ku)
    assert ok
    X = rng.standard_normal((N, 4))
    Y = X.copy()
    band_solve(W, piv, kl, ku, Y)
    assert np.allclose(Y, np.linalg.solve(A, X), rtol=0, atol=1e-10 * np.abs(np.linalg.solve(A, X)).max())
    w = max(kl, ku)
    Sb = to_band(A + A.T, w)                                         # the layout's band arrays: Sb[i, j - i + w]
    assert all(Sb[r, c - r + w] == (A + A.T)[r, c] for r in range(N) for c in range(max(0, r - w), min(N, r + w + 1)))


def test_band_lu_reports_a_singular_matrix():
    W = np.zeros((4, 4))                       # kl = 1, ku = 1: an all-zero matrix
    _, ok = band_lu(W, 1, 1)
    assert not ok


def test_stage_solver_choice():
    beam = modal_system(_beam(16))
    assert general.stage_solver(beam, 3) == "band" and general.stage_solver(beam, 2) == "band"
    assert general.stage_solver(beam, 1) == "dense"                      # Newmark keeps its modal kernel
    lay = general_band.layout(beam)
    assert lay.w <= KERNELS.band_max_fraction * beam.n                  # the beam's tangent is banded
    small = modal_system(nnm.Model(np.eye(2), np.diag([1.0, 4.0]),
                                   [nnm.PolynomialStiffness([[3, 0], [0, 3]], [[1.0, 0.0], [0.0, 1.0]])]))
    assert general.stage_solver(small, 3) == "dense" and general_band.layout(small) is None    # no band built
    lam, Phi = beam.model.eigensolution                                  # a basis of fewer modes: no physical form
    ritz = ModalSystem(beam.model, eigensolution=(lam[:10], Phi[:, :10]))
    assert general_band.layout(ritz) is None and general.stage_solver(ritz, 3) == "dense"


@pytest.mark.parametrize("stages", [2, 3])
def test_band_path_is_the_dense_path(stages):
    """Same orbit to round-off; the sensitivity (monodromy) to the round-off of solving in physical coordinates."""
    model = _beam(8, springs=[nnm.CubicSpring(dof=5, k3=1e9)])         # coupled elements and a spring
    system = modal_system(model)
    q0, v0, T = _start(system, model, 8)
    h = 0.9 * T / 100
    dense = general.sweep(system, stages, q0, v0, h, 100, ncols=2 * system.n, solver="dense")
    band = general.sweep(system, stages, q0, v0, h, 100, ncols=2 * system.n, solver="band")
    assert dense[-1] and band[-1] and dense[-2] == band[-2] == 100
    for i in (0, 1):                                                     # q, v
        assert np.abs(band[i] - dense[i]).max() <= 1e-10 * np.abs(dense[i]).max()
    for i in (4, 5):                                                     # dq/d[q0, v0, h], dv/d[...]
        assert np.abs(band[i] - dense[i]).max() <= 1e-7 * np.abs(dense[i]).max()
    Qd, _, okd = general.record(system, stages, q0, v0, h, 50)
    rec = general.sweep(system, stages, q0, v0, h, 50, record=True, solver="band")
    assert okd and rec[-1] and np.abs(rec[2] - Qd).max() <= 1e-10 * np.abs(Qd).max()


def test_band_sensitivity_against_central_differences():
    model = _beam(8)
    system = modal_system(model)
    q0, v0, T = _start(system, model, 8, amplitude=1.5 * H)
    n, h, N = system.n, T / 100, 100
    q, v, _, _, SQ, SV, _, ok = general.sweep(system, 3, q0, v0, h, N, ncols=2 * n, solver="band")
    assert ok

    def end(dq=0.0, dv=0.0, dh=0.0):
        out = general.sweep(system, 3, q0 + dq, v0 + dv, h + dh, N, solver="band")
        return np.concatenate([out[0], out[1]])

    w1 = np.sqrt(system.omega2[0])
    for col in (0, 2, 5, n, n + 2):                                      # q0 and v0 entries (steps: round-off of
        e = np.zeros(n)                                                  # the stiff sweep against truncation)
        e[col % n] = 1e-5 * abs(q0[0]) if col < n else 1e-4 * abs(q0[0]) * w1
        delta = (end(dq=e) - end(dq=-e)) if col < n else (end(dv=e) - end(dv=-e))
        fd = delta / (2 * e[col % n])
        exact = np.concatenate([SQ[:, col], SV[:, col]])
        assert np.abs(fd - exact).max() <= 5e-6 * np.abs(exact).max(), col
    dh = 1e-5 * h
    fd = (end(dh=dh) - end(dh=-dh)) / (2 * dh)
    exact = np.concatenate([SQ[:, 2 * n], SV[:, 2 * n]])
    assert np.abs(fd - exact).max() <= 5e-6 * np.abs(exact).max()


def test_band_path_conserves_energy():
    """The energy along a recorded orbit (a = 1.5 h, mode 3 kicked, 16 elements, 3 periods) is conserved to the
    scheme's error, which falls with the step (the beam's axial modes, h w_max = 270 at 100 steps a period, are not
    resolved: measured 2.7e-4, 9.4e-5, 1.1e-5 at 100, 200, 400 steps a period), and is the modal kernel's."""
    model = _beam(16)
    system = modal_system(model)
    q0, v0, T = _start(system, model, 16, amplitude=1.5 * H)
    err = {}
    for steps, solver in ((100, "band"), (400, "band"), (100, "dense")):   # steps per period, over 3 periods
        out = general.sweep(system, 3, q0, v0, T / steps, 3 * steps, record=True, solver=solver)
        assert out[-1]
        energy = np.array([system.energy(q, v) for q, v in zip(out[2], out[3])])
        err[steps, solver] = energy / energy[0] - 1
    worst = {k: np.abs(e).max() for k, e in err.items()}
    assert worst[100, "band"] <= 5e-4 and worst[400, "band"] <= 0.1 * worst[100, "band"], worst
    assert np.abs(err[100, "band"] - err[100, "dense"]).max() <= 1e-9


def test_band_path_fails_a_nan_start_cleanly():
    model = _beam(8)
    system = modal_system(model)
    q0, v0, T = _start(system, model, 8)
    q0[1] = np.nan
    out = general.sweep(system, 3, q0, v0, T / 100, 100, ncols=2 * system.n, solver="band")
    assert not out[-1] and out[-2] == 0
