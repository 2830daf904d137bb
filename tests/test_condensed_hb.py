"""Harmonic balance condensed onto the nonlinear elements (orbits/condensed_hb.py) against the
uncondensed harmonic balance (a second implementation of the same equations), finite differences,
Hill's multipliers and independent reference models."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.condensed_hb import CondensedHBProblem
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from reference_models import beam_matrices, tip_dof


def two_dof(k3=0.5):
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=k3)])


def ecl_beam(n_el=20):
    """The ECL benchmark (../shared/reference): steel cantilever 0.7 m, 14 mm square, tip cubic spring 8e9 N/m^3."""
    a = 0.014
    M, K = beam_matrices(n_el, 0.7, 205e9 * a ** 4 / 12, 7800.0 * a * a)
    return nnm.Model(M, K, [nnm.CubicSpring(dof=tip_dof(n_el), k3=8e9)])


def two_springs_chain(n=6):
    """A chain of n unit masses with a cubic spring to ground at DOF 0 and one between DOFs 2 and 4."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.diag(1.0 + 0.1 * np.arange(n)), K,
                     [nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=4, k3=-0.3)])


def _at_energy_max(model, mode, energy_max, **kw):
    a = nnm.continue_nnm(model, mode, energy_max, method="hb", floquet=False, **kw)
    b = nnm.continue_nnm(model, mode, energy_max, method="hb", condensed=True, floquet=False, **kw)
    assert a.status == b.status == "done", (a.message, b.message)
    return a, b


@pytest.mark.parametrize("basis", ["odd", "full"])
def test_jacobian_matches_finite_differences(basis):
    model = two_springs_chain()
    system = modal_system(model)
    hb = HBBasis(5, basis)
    p = CondensedHBProblem(system, 1, hb)
    rng = np.random.default_rng(3)
    u, _ = p.start(0.7)
    u = u + 0.05 * rng.standard_normal(len(u)) * np.abs(u).max()
    u[-1] = 1.03
    r, J = p.jacobian(u)
    assert np.allclose(r, p.residual(u))
    Jfd = np.zeros_like(J)
    for i in range(len(u)):
        e = np.zeros(len(u))
        e[i] = 1e-6 * max(1.0, abs(u[i]))
        Jfd[:, i] = (p.residual(u + e) - p.residual(u - e)) / (2 * e[i])
    assert np.max(np.abs(J - Jfd)) < 1e-7 * max(1.0, np.max(np.abs(J)))


def test_two_dof_condensed_equals_uncondensed():
    """NNM 1 of the 2-DOF benchmark to 57 J (H = 7): the same frequency at energy_max to 1e-10, every point's
    reconstructed orbit solves the uncondensed HB equations, and the same energies as the model's."""
    model = two_dof()
    a, b = _at_energy_max(model, 1, 57.0, harmonics=7, tol=1e-12)
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-10
    system = modal_system(model)
    full = HBProblem(system, 0, HBBasis(7, "odd"))
    for i in range(0, len(b), 7):
        A = system.to_modal(b.coefficients_at(i))
        u = full.pack(A, 2 * np.pi * b.frequency_hz[i])
        assert full.error(u, full.residual(u)) < 1e-11
        assert np.isclose(full.energy(u), b.energy[i], rtol=1e-10)
    assert b.settings.condensed and not a.settings.condensed


@pytest.mark.parametrize("make, mode, energy_max, H", [(ecl_beam, 1, 0.5, 5), (two_springs_chain, 2, 0.3, 7)])
def test_condensed_equals_uncondensed_on_other_structures(make, mode, energy_max, H):
    model = make()
    a, b = _at_energy_max(model, mode, energy_max, harmonics=H)
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-10
    assert abs(b.frequency_hz[-1] / b.frequency_hz[0] - 1) > 1e-4            # a nonlinear stretch of the branch
    assert np.allclose(b.x0[-1], a.x0[-1], rtol=0, atol=1e-8 * np.abs(a.x0[-1]).max())


def test_full_basis_condensed_equals_uncondensed():
    model = two_springs_chain()
    a, b = _at_energy_max(model, 1, 0.4, harmonics=5, basis="full")
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-9


def test_multipliers_and_events_are_those_of_the_uncondensed_orbits():
    """Hill's multipliers of the reconstructed orbit equal the uncondensed ones, so the located events do."""
    model = two_dof()
    a = nnm.continue_nnm(model, 1, 45.0, method="hb", harmonics=5, floquet=True)
    b = nnm.continue_nnm(model, 1, 45.0, method="hb", harmonics=5, condensed=True, floquet=True)
    assert a.status == b.status == "done"
    ka = [(e["kind"], e["energy"]) for e in a.events]
    kb = [(e["kind"], e["energy"]) for e in b.events]
    assert [k for k, _ in ka] == [k for k, _ in kb] and len(kb) >= 1
    for (_, ea), (_, eb) in zip(ka, kb):
        assert abs(eb / ea - 1) < 1e-6
    assert np.array_equal(a.stable[[0, -1]], b.stable[[0, -1]])
    system = modal_system(model)
    p = CondensedHBProblem(system, 0, HBBasis(5, "odd"))
    full = HBProblem(system, 0, HBBasis(5, "odd"))
    A = system.to_modal(b.coefficients_at(len(b) - 1))
    u_full = full.pack(A, 2 * np.pi * b.frequency_hz[-1])
    D = HBBasis(5, "odd")
    u = p.pack(A @ system.Bq.T, A[0, 0], 2 * np.pi * b.frequency_hz[-1])
    assert D.harmonics == 5
    mu_c = np.sort_complex(p.multipliers(u))
    mu_f = np.sort_complex(full.multipliers(u_full))
    assert np.allclose(mu_c, mu_f, atol=1e-8)


def test_bad_condensed_option_is_one_clear_error():
    with pytest.raises(nnm.NNMInputError, match="condensed"):
        nnm.continue_nnm(two_dof(), 1, 1.0, method="hb", condensed="yes")
    with pytest.raises(nnm.NNMInputError, match="condensed"):
        nnm.continue_nnm(two_dof(), 1, 1.0, condensed=True)          # shooting has no condensed form


def sparse_cantilever(n_el, length=1.0, EI=43.75, rhoA=0.78, k3=1e7):
    """A clamped-free Euler-Bernoulli beam of n_el Hermite elements as sparse matrices (2 n_el DOFs), with a
    grounded cubic spring at the tip deflection (the strip of reference_models, defaults)."""
    import scipy.sparse as sp
    h = length / n_el
    ke = EI / h ** 3 * np.array([[12.0, 6 * h, -12.0, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                                 [-12.0, -6 * h, 12.0, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    me = rhoA * h / 420.0 * np.array([[156.0, 22 * h, 54.0, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                      [54.0, 13 * h, 156.0, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    idx = 2 * np.arange(n_el)[:, None] + np.arange(4)[None, :]
    rows = np.repeat(idx, 4, axis=1).ravel()
    cols = np.tile(idx, (1, 4)).ravel()
    N = 2 * (n_el + 1)
    K = sp.csr_matrix((np.tile(ke.ravel(), n_el), (rows, cols)), shape=(N, N))[2:, 2:]
    M = sp.csr_matrix((np.tile(me.ravel(), n_el), (rows, cols)), shape=(N, N))[2:, 2:]
    return nnm.Model(M.tocsr(), K.tocsr(), [nnm.CubicSpring(dof=2 * n_el - 2, k3=k3)])


def test_ritz_basis_equals_the_full_basis_on_a_model_where_both_run():
    """A 60-element cantilever (120 DOFs): the Ritz basis (modes below 2 H f + residual flexibility) gives the
    full basis's frequencies to 1e-9 beyond the two bases' linear frequency difference (their eigen-solvers' round-off)
    and its orbits to 1e-6 at the tip; the basis holds the exact low modes."""
    from nnm_solver.model.ritz import ritz_system
    model = sparse_cantilever(60)
    a = nnm.continue_nnm(model, 1, 5e-3, method="hb", harmonics=5, condensed=True, floquet=False, modal_basis="full",
                         freq_tol=None)         # the same truncation as the Ritz branch's (a Ritz basis is not refined)
    b = nnm.continue_nnm(model, 1, 5e-3, method="hb", harmonics=5, condensed=True, floquet=False, modal_basis="ritz")
    assert a.status == b.status == "done"
    assert b.settings.modal_basis == "ritz" and b.settings.cutoff_hz > 9 * a.frequency_hz[0]
    system = ritz_system(model, 1, 5)
    lam, _ = model.eigensolution
    # the two bases' linear frequency of mode 1 differ by their eigen-solvers' round-off (1.7e-8 in lam on one
    # machine): the nonlinear frequencies agree to that, plus 1e-9
    linear = 0.5 * abs(system.omega2[0] / lam[0] - 1)
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-9 + linear
    assert abs(a.frequency_hz[-1] / a.frequency_hz[0] - 1) > 1e-3                # nonlinear enough to matter
    tip = 2 * 60 - 2
    assert abs(b.x0[-1, tip] / a.x0[-1, tip] - 1) < 1e-6
    m = system.exact_modes
    # the dense eigensolution's own round-off on this pencil (eigenvalues spanning 1e10) is ~1e-8
    assert np.allclose(system.omega2[:m], lam[:m], rtol=1e-7)
    assert system.n == m + 2 * len(model.springs) and np.all(system.omega2[m:] >= lam[m] * (1 - 1e-9))


def test_a_300_element_beam_is_accepted_and_condensed_equals_uncondensed():
    """The 300-element cantilever (600 DOFs, eigenvalues spanning 1e12): mode 1 is an elastic mode (issue 28's
    report: it was refused as rigid-body), and its condensed branch equals the uncondensed one."""
    model = sparse_cantilever(300)
    a, b = _at_energy_max(model, 1, 5e-3, harmonics=3, modal_basis="full")
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-10


def lattice(N=100, k=1e4, m=0.5, k3=1e9):
    """N x N unit cells of masses m (kg) moving out of plane, springs k (N/m) to the four neighbours and to the
    fixed frame, a grounded cubic spring k3 (N/m^3) at a node near the centre: N^2 DOFs, sparse.  Linear
    eigenvalues in closed form: (k / m) (4 sin^2(p pi / (2 (N + 1))) + 4 sin^2(q pi / (2 (N + 1))))."""
    import scipy.sparse as sp
    T = sp.diags([-np.ones(N - 1), 2 * np.ones(N), -np.ones(N - 1)], [-1, 0, 1])
    I = sp.identity(N)
    K = (k * (sp.kron(T, I) + sp.kron(I, T))).tocsr()
    return nnm.Model(m * sp.identity(N * N, format="csr"), K, [nnm.CubicSpring(dof=(N // 2) * N + N // 2, k3=k3)])


def test_block_lanczos_finds_every_mode_below_the_cutoff_with_the_exact_eigenvalues():
    """model/ritz.py's block Lanczos (modes_below) on a 40 x 40 lattice (1,600 DOFs, double eigenvalues from its
    symmetry), two cutoffs: every mode below the cutoff and past it, none missed (the count is the closed form's),
    eigenvalues equal to the closed form to 1e-10, M-orthonormal shapes with small residuals (CHOLMOD or SuperLU,
    whichever SparseSolver uses)."""
    import scipy.sparse as sp
    from nnm_solver.model.ritz import modes_below
    from nnm_solver.model.sparse import SparseSolver
    N, k, m = 40, 1e4, 0.5
    model = lattice(N, k, m)
    p, q = np.meshgrid(np.arange(1, N + 1), np.arange(1, N + 1))
    s2 = lambda j: np.sin(j * np.pi / (2 * (N + 1))) ** 2                                          # noqa: E731
    exact = np.sort((k / m * 4 * (s2(p) + s2(q))).ravel())
    K, M = sp.csc_matrix(model.K), sp.csc_matrix(model.M)
    for f_cut in (20.0, 30.0):
        w2 = (2 * np.pi * f_cut) ** 2
        lam, Phi = modes_below(K, M, SparseSolver(K), 10, lambda found: w2)
        below = int(np.sum(exact <= w2))
        assert below > 90 and len(lam) > below and lam[below] > w2 and np.all(lam[:below] <= w2)
        assert np.allclose(lam, exact[:len(lam)], rtol=1e-10)
        assert np.allclose(Phi.T @ (M @ Phi), np.eye(len(lam)), atol=1e-9)
        r = K @ Phi - (M @ Phi) * lam
        assert np.max(np.linalg.norm(r, axis=0) / (lam * np.linalg.norm(M @ Phi, axis=0))) < 1e-8


def test_ritz_basis_falls_back_to_arpack_where_the_block_lanczos_cannot_converge(monkeypatch):
    """The 300-element cantilever (eigenvalues spanning 1e12) through the sparse path: the block Lanczos stalls at
    the round-off of K^-1 (LanczosStall) and ritz_basis takes ARPACK's modes instead, equal to the dense ones."""
    import dataclasses

    import scipy.sparse as sp
    from nnm_solver.model import ritz
    from nnm_solver.model.sparse import SparseSolver
    model = sparse_cantilever(300)
    K, M = sp.csc_matrix(model.K_linear), sp.csc_matrix(model.M)
    with pytest.raises(ritz.LanczosStall):
        ritz.modes_below(K, M, SparseSolver(K), 10, lambda found: (2 * np.pi * 3000.0) ** 2)
    monkeypatch.setattr(ritz, "MODEL", dataclasses.replace(ritz.MODEL, max_dense_dof=100))   # the sparse path
    lam, Phi, m, cut = ritz.ritz_basis(model, mode=1, harmonics=5)
    dense = model.eigensolution[0]
    # to the round-off of this pencil (eigenvalues spanning 1e12, an error ~ eps lam_max / lam): 7e-6 on the first
    assert m >= 24 and np.allclose(lam[:m], dense[:m], rtol=5e-5)


def test_sparse_solver_backends_agree_and_superlu_is_the_fallback():
    """SparseSolver: CHOLMOD (scikit-sparse, or cholespy) and SuperLU (with and without the nested-dissection
    ordering) give the same solutions for 1-D and 2-D right-hand sides; a matrix that is not positive definite goes
    to SuperLU, and SuperLU's "exactly singular" stays the error of a singular one."""
    import scipy.sparse as sp
    from nnm_solver.model.sparse import SparseSolver, cholespy_available, cholmod_available
    model = sparse_cantilever(60)
    K = sp.csc_matrix(model.K)
    b = np.random.default_rng(1).standard_normal((K.shape[0], 3))
    ref = np.linalg.solve(K.toarray(), b)
    backends = ["superlu"] + (["cholespy"] if cholespy_available() else []) + (["cholmod"] if cholmod_available()
                                                                                else [])
    for be in backends:
        s = SparseSolver(K, backend=be)
        assert s.backend == be
        assert np.allclose(s.solve(b), ref, rtol=1e-8, atol=1e-12 * np.abs(ref).max())
        assert np.allclose(s.solve(b[:, 0]), ref[:, 0], rtol=1e-8, atol=1e-12 * np.abs(ref).max())
    assert SparseSolver(K).backend == backends[-1]
    shifted = (K - 2.0 * model.eigensolution[0][3] * sp.csc_matrix(model.M)).tocsc()      # indefinite
    assert SparseSolver(shifted).backend == "superlu"
    with pytest.raises(RuntimeError, match="singular"):
        SparseSolver(sp.csc_matrix(np.array([[1.0, -1.0], [-1.0, 1.0]])))


@pytest.mark.slow
def test_a_ten_thousand_dof_lattice_runs_with_its_first_point_at_the_exact_linear_frequency():
    N, k, m = 100, 1e4, 0.5
    model = lattice(N, k, m)                       # 10,000 DOFs: above the dense eigensolution's limit
    b = nnm.continue_nnm(model, 1, 2e-2, method="hb", harmonics=5, condensed=True, floquet=False)
    assert b.status == "done" and b.settings.modal_basis == "ritz", b.message
    f1 = np.sqrt(k / m * 8 * np.sin(np.pi / (2 * (N + 1))) ** 2) / (2 * np.pi)
    from nnm_solver.model.ritz import ritz_system
    assert abs(np.sqrt(ritz_system(model, 1, 5).omega2[0]) / (2 * np.pi) / f1 - 1) < 1e-10
    # the first point holds START_NONLINEARITY = 1e-5 of its energy in the spring: a shift of that order
    assert 0 < b.frequency_hz[0] / f1 - 1 < 2e-5
    assert b.frequency_hz[-1] > 1.003 * b.frequency_hz[0]                   # the spring hardens it (0.5 %)
    assert b.x0.shape == (len(b), N * N)
    assert np.isclose(model.energy(b.x0[-1], b.v0[-1]), 2e-2, rtol=1e-6)


def test_skip_backbone_does_not_crawl_at_a_tongue_it_keeps_re_entering():
    """The shipped aircraft's mode 20 by condensed HB (H = 3) with tongues="skip": (builder 1.3) past about 6.6 J every
    jump over the 3:1 with mode 41 landed on the orbit it started from and the branch re-entered the tongue 469 times, 500
    points at one energy (max_points).  Now a re-entry jumps beyond the last landing and a failed jump costs a bounded
    number of orbits: the branch ends 'tongue' with the backbone below it, in few points, none repeated."""
    from pathlib import Path
    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "paris.h5")
    b = nnm.continue_nnm(model, 20, 40.0, method="hb", harmonics=3, condensed=True, floquet=False, tongues="skip")
    assert b.status == "tongue", b.message
    # (the family's end at 5.197 J is read as the 3:1 with mode 42 or, by a skeleton started for this energy_max, as a
    # 5:1 with mode 72 taking the orbit over: both resonances lie there)
    assert any(f"with mode {p}" in b.message for p in (41, 42, 72)) or "Skip.max_jumps" in b.message, b.message
    assert len(b) < 80 and np.sum(np.isclose(b.energy, b.energy.max(), rtol=1e-9)) == 1
    assert all(t.attempts <= 2 * len(nnm.Skip().jumps) * (t.reentries + 1) + 2 for t in b.tongues)
    assert b.frequency_hz.min() / b.frequency_hz[0] - 1 < -0.04
