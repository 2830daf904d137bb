"""Round 3 of the lean per-point path of condensed harmonic balance (issue 52): each cut computes the numbers of the form
it replaced, or decides the same way (checked here against that form), and the branches are the same bit for bit.

* continuation/linalg.all_finite: np.all(np.isfinite(x))'s answer from one dot product (the corrector's test at every
  iteration); LeastSquares.rcond made when read;
* the condensed problem keeps the energy (and gradient) of its last three orbits, and the engine asks for a step end's
  energy with its gradient where one kernel pass makes both (gradient_with_energy);
* the truncation estimate embeds its vectors by index arrays made once (hb_error._embedding);
* the loop detector screens the earlier segments in one compiled pass (results/stops._screened);
* the harmonic amplitudes gathered by np.bincount (analysis/hb_series.basis_harmonic_amplitudes).
"""
import importlib
import math
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.continuation import engine, linalg
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits import condensed_energy_kernels, condensed_kernels
from nnm_solver.orbits.condensed_hb import CondensedHBProblem
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis, harmonics_in
from nnm_solver.orbits.hb_error import HBTruncationError
from nnm_solver.results import stops

ROOT = Path(__file__).resolve().parent.parent
newton = importlib.import_module("nnm_solver.continuation.newton")     # (the package exports a function of that name)
needs_numba = pytest.mark.skipif(not condensed_kernels.AVAILABLE, reason="numba is not installed")


def chain(n=5, springs=None):
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.eye(n), K, springs=springs or [nnm.CubicSpring(dof=0, k3=0.8),
                                                       nnm.CubicSpring(dof=2, other=4, k3=-0.3)])


def numpy_all_finite(x):
    return bool(np.all(np.isfinite(x)))


def test_all_finite_is_numpys_answer():
    rng = np.random.default_rng(0)
    cases = [np.zeros(0), np.ones(1), rng.standard_normal(23), np.full(5, 1e200), np.array([1e-300, -1e308, 3.0]),
             rng.standard_normal((3, 4)), np.arange(6), rng.standard_normal(7).astype(np.float32),
             rng.standard_normal(4) + 1j * rng.standard_normal(4)]
    for bad in (np.nan, np.inf, -np.inf):
        for i in (0, 11, 22):
            x = rng.standard_normal(23)
            x[i] = bad
            cases.append(x)
        cases.append(np.array([1e200, bad]))
        z = rng.standard_normal(3) + 0j
        z[1] = complex(0.0, bad)
        cases.append(z)
    for x in cases:
        assert linalg.all_finite(x) == numpy_all_finite(x), x


def test_rcond_is_made_when_read_from_the_factor():
    import scipy.linalg as sla
    rng = np.random.default_rng(1)
    for shape in ((23, 22), (22, 22), (80, 80), (90, 70)):
        A = rng.standard_normal(shape)
        ls = linalg.LeastSquares(np.array(A, order="F"))
        if shape[0] == shape[1] and shape[1] >= linalg.LeastSquares.EXPLICIT_Q:
            d = np.abs(np.diag(sla.lu_factor(A)[0]))
        else:
            d = np.abs(np.diag(sla.qr(A, mode="economic")[1]))
        assert ls.rcond == d.min() / d.max()


def reference_embed(self, big, u):
    """HBTruncationError._embed as written before round 3 (harmonics_in on the reshaped coefficient block)."""
    u = np.asarray(u)
    k = self.nb * self._width
    if u.ndim == 2:
        C = harmonics_in(big.basis, self.basis, u[:, :k].reshape(len(u), self.nb, self._width)
                         .transpose(1, 0, 2).reshape(self.nb, -1))
        C = C.reshape(len(big.basis), len(u), self._width).transpose(1, 0, 2).reshape(len(u), -1)
        return np.concatenate([C, u[:, k:]], axis=1)
    C = harmonics_in(big.basis, self.basis, u[:k].reshape(self.nb, self._width))
    return np.concatenate([C.ravel(), u[k:]])


@pytest.mark.parametrize("cls", [CondensedHBProblem, HBProblem])
@pytest.mark.parametrize("kind", ["odd", "full"])
def test_embedding_by_index_arrays_is_harmonics_in(cls, kind):
    system = modal_system(chain())
    rng = np.random.default_rng(2)
    for H, H2 in ((1, 3), (3, 5), (5, 9), (9, 11)):
        small, big = cls(system, 0, HBBasis(H, kind)), cls(system, 0, HBBasis(H2, kind))
        n = small.nb * small._width + (2 if cls is CondensedHBProblem else 1)
        for shape in ((n,), (2, n), (5, n)):
            for _ in range(2):                  # (the second time from the kept index arrays)
                u = rng.standard_normal(shape)
                got, want = small._embed(big, u), reference_embed(small, big, u)
                assert got.shape == want.shape and np.array_equal(got, want)
        assert small._embed(small._larger(), np.ones(n)).shape == (len(small._larger().basis) * small._width + n
                                                                   - small.nb * small._width,)


def _orbits(p, count=3):
    rng = np.random.default_rng(3)
    out = []
    for a0 in np.linspace(0.3, 0.7, count):
        u, _ = p.start(a0)
        out.append(u + 0.05 * rng.standard_normal(len(u)) * np.abs(u[:-1]).max())
    return out


@needs_numba
def test_the_energy_of_the_last_three_orbits_is_kept(monkeypatch):
    """Kernel calls counted: an orbit asked again while it is one of the last three costs none, a fourth orbit pushes
    the oldest out, a gradient asked where only the energy is kept costs one; the numbers are a fresh problem's."""
    system = modal_system(chain())
    p = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
    u1, u2, u3, u4 = _orbits(p, 4)
    calls = []
    kernel = condensed_energy_kernels.energy_gradient
    monkeypatch.setattr(condensed_energy_kernels, "energy_gradient", lambda *a: calls.append(a[1]) or kernel(*a))

    def fresh(u):
        q = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
        return q.energy(u), q.energy_gradient(u)

    (E1, g1), (E2, g2), (E3, _), (E4, _) = fresh(u1), fresh(u2), fresh(u3), fresh(u4)
    calls.clear()
    assert p.energy(u1) == E1 and np.array_equal(p.energy_gradient(u2), g2) and p.energy(u3) == E3
    assert calls == [False, True, False]
    assert p.energy(u1) == E1 and p.energy(u2) == E2 and np.array_equal(p.energy_gradient(u2), g2)
    assert p.energy(u3) == E3 and calls == [False, True, False]            # all three kept
    assert np.array_equal(p.energy_gradient(u1), g1) and calls[-1] is True   # (only its energy was kept): u2, u3, u1
    n = len(calls)
    assert p.energy(u4) == E4 and len(calls) == n + 1                       # u3, u1, u4 kept: u2 pushed out
    assert p.energy(u3) == E3 and p.energy(u1) == E1 and len(calls) == n + 1
    assert p.energy(u2) == E2 and len(calls) == n + 2


@needs_numba
def test_the_engines_step_end_energy_comes_with_its_gradient(monkeypatch):
    """engine._Remembered on the condensed problem: the energy is the problem's own, bit for bit (the kernel's energy
    does not depend on whether the gradient is made), and the slope asked next costs no kernel call; without the
    compiled kernels (numpy forms) the energy alone is asked for."""
    system = modal_system(chain())
    for u in _orbits(CondensedHBProblem(system, 1, HBBasis(7, "odd")), 4):
        p, q = CondensedHBProblem(system, 1, HBBasis(7, "odd")), CondensedHBProblem(system, 1, HBBasis(7, "odd"))
        assert p.gradient_with_energy
        E = engine._Remembered(p)(u)
        assert E == q.energy(u)
        kernel = condensed_energy_kernels.energy_gradient
        calls = []
        with monkeypatch.context() as m:
            m.setattr(condensed_energy_kernels, "energy_gradient", lambda *a: calls.append(a) or kernel(*a))
            assert np.array_equal(p.energy_gradient(u), q.energy_gradient(u)) and len(calls) == 1   # (q's, not p's)
    with monkeypatch.context() as m:
        m.setattr(condensed_kernels, "AVAILABLE", False)
        assert not CondensedHBProblem(system, 1, HBBasis(7, "odd")).gradient_with_energy


def numpy_screen(a, ab, L, ang, y, floor):
    """LoopDetector._screen's numpy form (without numba)."""
    turn = np.zeros(len(ab))
    turn[1:] = np.maximum(turn[1:], ang)
    turn[:-1] = np.maximum(turn[:-1], ang)
    reach = 0.25 * L * turn + floor
    near = np.flatnonzero(stops._segment_distance(a[:, -2], a[:, -1], ab[:, -2], ab[:, -1], y[-2], y[-1])
                          <= reach * (1 + 1e-9))
    return near, reach[near]


@needs_numba
def test_the_compiled_screen_is_the_numpy_form():
    rng = np.random.default_rng(5)
    found = 0
    for trial in range(1500):
        k = int(rng.integers(2, 60))
        a = rng.standard_normal((k, 5)) * rng.choice([1e-3, 1.0, 10.0])
        ab = rng.standard_normal((k, 5)) * rng.choice([1e-4, 1e-2, 1.0])
        if trial % 7 == 0:
            ab[rng.integers(k)] = 0.0               # a repeated point: a segment of length 0
        if trial % 11 == 0:
            a[rng.integers(k), -1] = np.nan
        L = np.maximum(np.linalg.norm(ab, axis=1), 1e-300)
        ang = rng.uniform(0, np.pi, k - 1) * rng.choice([1e-3, 0.1, 1.0])
        y = a[rng.integers(k)] + rng.standard_normal(5) * rng.choice([1e-4, 1e-2, 1.0])
        want = numpy_screen(a, ab, L, ang, y, 1e-4)
        got = stops._screened(a[:, -2], a[:, -1], ab[:, -2], ab[:, -1], L, ang, float(y[-2]), float(y[-1]), 1e-4)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]), trial
        found += len(want[0])
    assert found > 1000


@needs_numba
def test_the_loop_detector_with_the_compiled_screen_answers_as_with_numpys(monkeypatch):
    """Paths that grow in amplitude and period, then lap (some mirrored, some points repeated), through the detector
    with the compiled screen and with the numpy form: the same answers at every point, and laps found."""
    rng = np.random.default_rng(12)
    found = 0
    for trial in range(10):
        det = stops.LoopDetector(mirror=trial % 2 == 0)
        with monkeypatch.context() as m:
            m.setattr(stops, "numba", None)
            ref = stops.LoopDetector(mirror=trial % 2 == 0)
        n, args = 4, None
        centre = rng.standard_normal(n)
        for k in range(80):
            ang = 2 * np.pi * k / (9 + trial)
            grow = 1.0 + 0.05 * min(k, 20)           # the amplitude and period move on, then the path laps
            if args is None or k % 17 != 6:
                q = grow * (centre + np.r_[np.cos(ang), np.sin(ang), 0.01 * rng.standard_normal(n - 2)]) * (
                    1 if k % 23 else -1)
                args = (q, 0.1 * rng.standard_normal(n) * (trial % 3 == 0), 2.0, grow + 0.05 * np.sin(ang), 1.0)
            got = det.add(*args)
            with monkeypatch.context() as m:
                m.setattr(stops, "numba", None)
                want = ref.add(*args)
            assert got == want and det.pending == ref.pending, (trial, k)
            found += want is not None
    assert found > 5


def reference_amplitudes(basis, A, n, r):
    """basis_harmonic_amplitudes as written before round 3 (np.add.at)."""
    sq = A * A
    rows = sq.sum(axis=1)
    sq[:, r] = 0.0
    rows_r = sq.sum(axis=1)
    h = np.asarray(basis.h)
    keep = h <= n
    amps2, others2 = np.zeros(int(n) + 1), np.zeros(int(n) + 1)
    np.add.at(amps2, h[keep], rows[keep])
    np.add.at(others2, h[keep], rows_r[keep])
    return np.sqrt(amps2), np.sqrt(others2)


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_harmonic_amplitudes_by_bincount_are_add_ats(kind):
    from nnm_solver.analysis.hb_series import basis_harmonic_amplitudes
    rng = np.random.default_rng(6)
    for H in (1, 3, 9, 13):
        basis = HBBasis(H, kind)
        for n in (0, 3, 9, 20):
            A = rng.standard_normal((len(basis), 40)) * rng.choice([1e-8, 1.0, 1e8])
            got, want = basis_harmonic_amplitudes(basis, A, n, 7), reference_amplitudes(basis, A, n, 7)
            assert all(np.array_equal(x, y) for x, y in zip(got, want))


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


CASES = {"aircraft to 3 J": (lambda: nnm.load_model(str(ROOT / "assets" / "paris.h5")), 20, 3.0, dict(harmonics=9)),
         "2-DOF to 200 J, skip": (two_dof, 1, 200.0, dict(tongues="skip"))}


@needs_numba
@pytest.mark.parametrize("name", sorted(CASES))
def test_round_three_gives_round_twos_branch_bit_for_bit(name, monkeypatch):
    """The branch with round 3's forms and with the forms they replaced (numpy's finiteness test, the energy alone at a
    step's end, the numpy screen, the embedding by harmonics_in): equal in every column, bit for bit."""
    make, mode, E, kw = CASES[name]
    model = make()
    new = nnm.continue_nnm(model, mode, E, method="hb", condensed=True, **kw)
    with monkeypatch.context() as m:
        m.setattr(engine, "all_finite", numpy_all_finite)
        m.setattr(newton, "all_finite", numpy_all_finite)
        m.setattr(CondensedHBProblem, "gradient_with_energy", False)
        m.setattr(stops, "numba", None)
        m.setattr(HBTruncationError, "_embed", reference_embed)
        old = nnm.continue_nnm(model, mode, E, method="hb", condensed=True, **kw)
    assert (new.status, new.message, list(new.labels)) == (old.status, old.message, list(old.labels))
    assert len(new) > 20
    for column in ("energy", "frequency_hz", "freq_error", "fundamental_share", "x0", "v0", "stable"):
        assert np.array_equal(getattr(new, column), getattr(old, column), equal_nan=True), column
    assert [(e["kind"], e["energy"]) for e in new.events] == [(e["kind"], e["energy"]) for e in old.events]
    assert [repr(t) for t in new.tongues] == [repr(t) for t in old.tongues]


def test_the_skeletons_kept_log_frequencies_and_pieces_are_fresh_ones():
    """Skeleton.log_frequency (kept per energy: the lock test asks for the run's energies at every point) and
    frequency_at (each spline piece's cubics kept) give a fresh skeleton's numbers, asked in any order and again."""
    from nnm_solver.backbone.skeleton import compute_skeleton
    system = modal_system(two_dof())
    sk = compute_skeleton(system, 1, 50.0)
    E = np.geomspace(sk.energy[0], sk.energy[-1], 301)
    order = np.random.default_rng(7).permutation(np.r_[E, E[::3], E[::-7]])
    for e in order:
        assert sk.log_frequency(e) == np.interp(math.log(e), np.log(sk.energy), np.log(sk.frequency_hz))
    fresh = compute_skeleton(system, 1, 50.0)
    for e in order:
        fresh._pieces.clear()
        assert sk.frequency_at(e) == fresh.frequency_at(e) or (np.isnan(sk.frequency_at(e))
                                                               and np.isnan(fresh.frequency_at(e)))
