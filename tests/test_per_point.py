"""The lean per-point path of condensed harmonic balance (issue 52): the energy gradient in closed form
(orbits/condensed_energy.py) against central differences of the energy, on complete and truncated linear parts,
polynomial, piecewise-linear and coupled elements, odd and full bases."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.condensed_hb import CondensedHBProblem, LinearPart
from nnm_solver.orbits.hb_basis import HBBasis


def chain(n=6, springs=None):
    """n masses (1.0 .. 1.5 kg) in a chain, grounded at both ends, with the given elements."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.diag(1.0 + 0.1 * np.arange(n)), K, springs)


MODELS = {
    "cubic": lambda: chain(springs=[nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=4, k3=-0.3)]),
    "polynomial": lambda: chain(springs=[nnm.PolynomialSpring(dof=1, coefficients={2: 0.4, 3: 0.9})]),
    "piecewise": lambda: chain(springs=[nnm.PiecewiseLinearSpring(dof=3, stiffnesses=[0.5, 2.0],
                                                                  breakpoints=[0.2])]),
    "coupled": lambda: chain(springs=[nnm.PolynomialStiffness(
        [[1, 1, 0], [2, 0, 0], [0, 2, 1], [0, 3, 0], [3, 0, 0]],
        [[2, 0, 0], [0, 1, 0], [0, 1.5, 0], [0, 0, .5], [1, 0, 0]], dofs=[0, 2, 5])]),
}


def _perturbed(p, a0, seed):
    rng = np.random.default_rng(seed)
    u, _ = p.start(a0)
    u = u + 0.1 * rng.standard_normal(len(u)) * np.abs(u[:-1]).max()
    u[-1] = 1.04
    return u


def _check_gradient(p, u):
    g, g_fd = p.energy_gradient(u), p.energy_gradient_fd(u, h=1e-6)
    assert np.all(np.isfinite(g))
    assert np.max(np.abs(g - g_fd)) < 1e-6 * np.max(np.abs(g)), np.max(np.abs(g - g_fd)) / np.max(np.abs(g))


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("kind", ["odd", "full"])
def test_energy_gradient_is_the_derivative_of_the_condensed_energy(name, kind):
    model = MODELS[name]()
    system = modal_system(model)
    if kind == "odd" and not system.elements.odd:
        pytest.skip("an odd basis needs odd forces")
    p = CondensedHBProblem(system, 1, HBBasis(5, kind))
    for seed in (0, 1):
        _check_gradient(p, _perturbed(p, 0.6, seed))


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_energy_gradient_with_the_left_out_modes_residual_flexibility(kind):
    """A truncated LinearPart (the first 3 of 6 modes and residual flexibilities R0, R1, not symmetric here: the
    gradient must not assume it) and the followed mode r = 1."""
    system = modal_system(MODELS["cubic"]())
    rng = np.random.default_rng(5)
    R0, R1 = 0.05 * rng.standard_normal((2, 2, 2))
    lin = LinearPart(system.omega2[:3], system.Bq[:, :3], R0=R0, R1=R1)
    p = CondensedHBProblem(system, 1, HBBasis(5, kind), lin)
    for seed in (2, 3):
        _check_gradient(p, _perturbed(p, 0.6, seed))


def test_energy_is_unchanged_by_the_cache_of_the_last_orbit():
    """The problem keeps the last orbit's amplitudes: the energy, state and orbit of u after another orbit's are
    those computed afresh, and the kept arrays cannot be changed by a caller."""
    system = modal_system(MODELS["cubic"]())
    p = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
    u1, u2 = _perturbed(p, 0.6, 7), _perturbed(p, 0.4, 8)
    fresh = CondensedHBProblem(system, 1, HBBasis(7, "odd"))
    E1 = fresh.energy(u1)
    for u in (u1, u2, u1):
        p.energy(u)
    assert p.energy(u1) == E1
    q0, v0, T = p.state(u1)
    f0 = fresh.state(u1)
    assert np.array_equal(q0, f0[0]) and np.array_equal(v0, f0[1]) and T == f0[2]
    with pytest.raises(ValueError):
        p.amplitudes(u1)[0][0, 0] = 1.0


# ---------------------------------------------------------------- the points' physical state, computed when read
from pathlib import Path  # noqa: E402

from nnm_solver.backbone.content import content_of  # noqa: E402
from nnm_solver.results.point import ModalState, Point, resolve_points  # noqa: E402
from nnm_solver.results.stops import LoopDetector  # noqa: E402

PARIS = Path(__file__).resolve().parents[1] / "assets" / "paris.h5"


def _lazy_points(model, mode, energy_max, **kw):
    """The points of a condensed-HB branch as the iterator yields them (their modal states not yet mapped), the
    eager physical states of each (one matrix-vector product per vector, as before issue 52), and the Branch."""
    it = nnm.iter_nnm(model, mode, energy_max, method="hb", condensed=True, **kw)
    points, eager = [], []
    for p in it:
        m = p.__dict__["modal"]
        assert m is not None                                  # nothing of size n computed yet
        eager.append((m.q0 @ m.phi.T, m.v0 @ m.phi.T, m.coefficients @ m.phi.T))
        points.append(p)
    return points, eager, it.branch()


@pytest.mark.parametrize("case", ["chain", "aircraft"])
def test_the_physical_states_computed_when_read_are_the_eager_ones(case):
    """x0, v0 and the coefficients that the Branch maps in one product when first read (PhysicalColumns) equal the
    point-by-point products (to 1e-14 of each vector's size), and the energy taken from the modal state equals the
    model's physical energy of (x0, v0) (the eager definition) to 1e-12 relative or the physical one's round-off,
    eps w_max^2 / w_mode^2 (the modal sum of squares is the accurate one; x^T K x of the aircraft's stiffness rounds to
    eps w_max^2 / w_20^2 = 2.6e-11: 5.4e-13 measured on one machine, 1.7e-12 on another)."""
    if case == "chain":
        model, mode, E, kw = MODELS["cubic"](), 1, 2.0, dict(harmonics=7)
    else:
        model, mode, E, kw = nnm.load_model(PARIS), 20, 0.3, dict(harmonics=9)
    points, eager, b = _lazy_points(model, mode, E, **kw)
    lam = model.eigensolution[0]
    rounding = max(1e-12, np.finfo(float).eps * lam[-1] / lam[mode - 1])      # the aircraft's: 2.6e-11
    assert len(b) == len(points) > 5 and b.status == "done"
    assert all(p.__dict__["modal"] is not None for p in points)     # the Branch maps nothing until its columns are read
    b.x0                                                      # (read: mapped now)
    for i, (p, (x0, v0, C)) in enumerate(zip(points, eager)):
        assert p.__dict__["modal"] is None                    # mapped, once, when the Branch's columns were read
        for got, want in ((b.x0[i], x0), (b.v0[i], v0), (b.coefficients[i], C), (p.x0, x0)):
            assert np.max(np.abs(got - want)) <= 1e-14 * np.max(np.abs(want))
        E_phys = float(model.energy(x0, v0))
        assert abs(b.energy[i] / E_phys - 1) < rounding, (i, b.energy[i] / E_phys - 1)


def test_a_point_made_with_a_modal_state():
    """Reading or setting one of x0, v0, coefficients maps all three; setting keeps the value set; a Point made
    with physical arrays (no modal state) is as before; resolve_points maps points of two modal systems."""
    rng = np.random.default_rng(4)
    phi1, phi2 = rng.standard_normal((5, 3)), rng.standard_normal((4, 2))

    def make(phi, coeffs=True):
        m = phi.shape[1]
        st = ModalState(phi, rng.standard_normal(m), rng.standard_normal(m), rng.standard_normal((3, m)) if coeffs
                        else None)
        return Point(1.0, 2.0, 0.5, None, None, np.full(2, np.nan), True, modal=st), st

    p, st = make(phi1)
    assert np.allclose(p.v0, st.v0 @ phi1.T) and p.modal is None
    assert np.allclose(p.x0, st.q0 @ phi1.T) and np.allclose(p.coefficients, st.coefficients @ phi1.T)
    p, st = make(phi1)
    p.coefficients = np.ones((2, 5))
    assert np.array_equal(p.coefficients, np.ones((2, 5))) and np.allclose(p.x0, st.q0 @ phi1.T)
    p, st = make(phi2, coeffs=False)
    assert p["coefficients"] is None and np.allclose(p["x0"], st.q0 @ phi2.T)
    p, st = make(phi2)
    import pickle
    q = pickle.loads(pickle.dumps(p))                          # pickled mapped (not with the shapes phi)
    assert q.modal is None and np.array_equal(q.x0, p.x0) and np.array_equal(q.coefficients, p.coefficients)
    plain = Point(1.0, 2.0, 0.5, np.arange(3.0), np.zeros(3), np.full(6, np.nan), True)
    assert plain.modal is None and np.array_equal(plain.x0, np.arange(3.0)) and plain.coefficients is None
    pts = [make(phi1), make(phi2), make(phi1, coeffs=False), make(phi2)]
    resolve_points([p for p, _ in pts])
    for p, st in pts:
        assert p.__dict__["modal"] is None and np.allclose(p.__dict__["_x0"], st.q0 @ st.phi.T)
        assert np.allclose(p.__dict__["_v0"], st.v0 @ st.phi.T)
        if st.coefficients is not None:
            assert np.allclose(p.__dict__["_coefficients"], st.coefficients @ st.phi.T)


def test_the_branch_columns_of_points_appended_with_modal_states():
    """PhysicalColumns: a Branch extended by points holding modal states (two modal systems) and by plain ones maps
    them when a column is first read, to the point-by-point products; a batch without coefficients drops them (as the
    eager columns did); a point changed after it was appended does not change the branch; pickled and read from two
    threads at once, the same columns."""
    import pickle
    import threading
    from nnm_solver.results.branch import Branch
    rng = np.random.default_rng(7)
    model = MODELS["cubic"]()
    n = model.n
    phis = [rng.standard_normal((n, 3)), rng.standard_normal((n, 2))]

    def modal_point(phi, coeffs=True):
        m = phi.shape[1]
        st = ModalState(phi, rng.standard_normal(m), rng.standard_normal(m),
                        rng.standard_normal((3, m)) if coeffs else None)
        return Point(1.0, 2.0, 0.5, None, None, np.full(2 * n, np.nan), True, modal=st), st

    made = [modal_point(phis[0]), modal_point(phis[1]), modal_point(phis[0])]
    b = Branch.from_points(model, 1, [p for p, _ in made])
    assert all(p.__dict__["modal"] is not None for p, _ in made)            # nothing mapped yet
    made[0][0].coefficients = np.zeros((3, n))                              # changed after it was appended
    for i, (_, st) in enumerate(made):
        assert np.allclose(b.x0[i], st.q0 @ st.phi.T) and np.allclose(b.v0[i], st.v0 @ st.phi.T)
        assert np.allclose(b.coefficients[i], st.coefficients @ st.phi.T)
    c = pickle.loads(pickle.dumps(b))
    assert np.array_equal(c.x0, b.x0) and np.array_equal(c.coefficients, b.coefficients)

    twice = Branch.from_points(model, 1, [p for p, _ in made])
    twice.extend([modal_point(phis[1])[0]])
    seen = []
    threads = [threading.Thread(target=lambda: seen.append(twice.coefficients)) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert seen[0] is seen[1] and seen[0].shape == (4, 3, n)

    plain = Point(1.0, 2.0, 0.5, np.arange(float(n)), np.zeros(n), np.full(2 * n, np.nan), True)
    b.extend([plain, modal_point(phis[1], coeffs=False)[0]])
    assert len(b.x0) == len(b) == 5 and b.coefficients is None and np.array_equal(b.x0[3], np.arange(float(n)))


def test_a_branch_of_lazily_mapped_points_loses_nothing_in_its_file(tmp_path):
    """Saved and read back: every column of the branch as it was computed."""
    model = MODELS["cubic"]()
    _, _, b = _lazy_points(model, 1, 2.0, harmonics=5)
    path = tmp_path / "b.h5"
    nnm.save_branch(path, b)
    (c,) = nnm.load_branches(path)
    for key in ("energy", "frequency_hz", "period", "x0", "v0", "coefficients", "freq_error", "steps",
                "fundamental_share", "stable"):
        assert np.array_equal(getattr(b, key), getattr(c, key)), key
    assert list(b.labels) == list(c.labels) and b.status == c.status and b.message == c.message


def test_content_from_the_coefficients_is_that_of_the_sampled_orbit():
    """The harmonic content from an HB orbit's coefficients (analysis/hb_series.py) against the transform of its
    sampled modal orbit, on the aircraft's points up to its 3:1 tongue (odd basis) and on the chain with an even
    law (full basis): the same labels and orders, the fractions and shares to round-off."""
    from nnm_solver.analysis.hb_series import basis_fourier_coefficients
    for model, mode, E, kw in ((nnm.load_model(PARIS), 20, 1.7, dict(harmonics=9)),
                               (MODELS["polynomial"](), 1, 1.0, dict(harmonics=6))):
        it = nnm.iter_nnm(model, mode, E, method="hb", condensed=True, error_estimate=False, **kw)
        n = 0
        for _ in it:
            prob, u = it._problem, it._last_kept[0].u
            Q, A = prob.modal_orbit(u), prob.coefficients(u)
            a = content_of(Q, mode - 1)
            b = content_of(Q, mode - 1, coefficients=basis_fourier_coefficients(prob.basis, A, 25))
            assert (a.label, a.k, a.partner_k) == (b.label, b.k, b.partner_k)
            assert abs(a.fraction - b.fraction) < 1e-13 and abs(a.share - b.share) < 1e-14
            assert np.allclose(a.amplitudes, b.amplitudes, rtol=0, atol=1e-14 * a.amplitudes.max())
            n += 1
        assert n > 5


def _reference_loop_hit(Y, y, move, skip=4, floor=1e-4):
    """The loop detector's segment test as written before issue 52 (every segment from the list of points)."""
    m = len(Y) - skip
    if m < 3 or move is None:
        return None
    Ya = np.array(Y[:m])
    ab = np.diff(Ya, axis=0)
    L = np.maximum(np.linalg.norm(ab, axis=1), 1e-300)
    u = ab / L[:, None]
    turn = np.zeros(len(ab))
    ang = np.arccos(np.clip(np.einsum("ij,ij->i", u[1:], u[:-1]), -1.0, 1.0))
    turn[1:] = np.maximum(turn[1:], ang)
    turn[:-1] = np.maximum(turn[:-1], ang)
    a = Ya[:-1]
    t = np.einsum("ij,ij->i", y - a, ab) / np.maximum(L * L, 1e-300)
    inside = (t > 0.0) & (t < 1.0)
    t = np.clip(t, 0.0, 1.0)
    d = np.linalg.norm(a + t[:, None] * ab - y, axis=1)
    same_way = u @ move >= 0.8 * max(np.linalg.norm(move), 1e-300)
    all_L = np.linalg.norm(np.diff(np.array(Y), axis=0), axis=1)
    since = np.sum(all_L) - np.concatenate([[0.0], np.cumsum(all_L)])[1:m] + np.linalg.norm(y - Y[-1])
    ok = np.flatnonzero((d <= 0.25 * L * turn + floor) & same_way & inside & (since > 3.0 * L))
    return int(ok[0]) if len(ok) else None


class _ReferenceLoopDetector:
    """LoopDetector.add as written before issue 52 (the points in a list)."""

    def __init__(self, mirror):
        self.mirror, self.Y, self.pending = mirror, [], None

    def add(self, q0, v0, w_r, T, T_r):
        z = np.concatenate([q0, v0 / w_r])
        nz = max(np.linalg.norm(z), 1e-300)
        y = np.concatenate([z / nz, [T / T_r, np.log(nz)]])
        move = y - self.Y[-1] if self.Y else None
        hit = _reference_loop_hit(self.Y, y, move)
        if hit is None and self.mirror and move is not None:
            flip = np.ones(len(y))
            flip[:-2] = -1.0
            hit = _reference_loop_hit(self.Y, y * flip, move * flip)
        self.Y.append(y)
        if hit is None:
            self.pending = None
            return None
        if self.pending is not None and abs(hit - self.pending) <= 3:
            return self.pending
        self.pending = hit
        return None


def test_the_loop_detector_with_cached_segments_finds_what_it_found_before():
    """Paths with laps (some mirrored, some points repeated: segments of length 0) through the detector and
    through the detector as written before (every segment recomputed from the list of points): the same answers
    at every point."""
    rng = np.random.default_rng(11)
    hits = found = 0
    for trial in range(12):
        det, ref, n = LoopDetector(mirror=trial % 2 == 0), _ReferenceLoopDetector(trial % 2 == 0), 4
        centre = rng.standard_normal(n)
        args = None
        for k in range(70):
            ang = 2 * np.pi * k / (9 + trial)
            if args is None or k % 17 != 6:                    # (else the same point again)
                q = centre + np.r_[np.cos(ang), np.sin(ang), 0.01 * rng.standard_normal(n - 2)] * (1 if k % 23 else -1)
                args = (q, 0.1 * rng.standard_normal(n) * (trial % 3 == 0), 2.0, 1.0 + 0.05 * np.sin(ang), 1.0)
            got, want = det.add(*args), ref.add(*args)
            assert got == want and det.pending == ref.pending, (trial, k)
            hits += ref.pending is not None
            found += want is not None
    assert hits > 20 and found > 5


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_restoring_ratio_from_the_coefficients_is_that_of_the_sampled_orbit(kind):
    """analysis/hb_series.series_restoring_ratio against results/stops.restoring_ratio of the sampled orbit, on the
    chain's orbits (random content, r near 1) and on a softening oscillator's from nearly linear (r = 1) up to its
    saddle at unit amplitude (r -> 0, where the escape test acts)."""
    from nnm_solver.analysis.hb_series import series_restoring_ratio
    from nnm_solver.results.stops import restoring_ratio
    basis = HBBasis(7, kind)
    rng = np.random.default_rng(9)
    S = basis.functions(2 * np.pi * np.arange(32) / 32)
    fund = list(basis.h).index(1)
    seen = []
    for model, scales, noise in ((MODELS["cubic"](), np.geomspace(1e-2, 3.0, 10), 0.05),
                                 (nnm.Model(np.eye(2), np.diag([1.0, 4.0]), [nnm.CubicSpring(dof=0, k3=-1.0)]),
                                  1 - np.geomspace(0.9, 1e-4, 20), 1e-4)):
        system = modal_system(model)
        for scale in scales:
            A = noise * scale * rng.standard_normal((len(basis), system.n))
            A[fund, 0] += scale
            want = restoring_ratio(system, S @ A)
            got = series_restoring_ratio(system, basis, A, 32)
            assert abs(got - want) <= 1e-10 * want + 1e-15 / want, (scale, got, want)      # r^2 to 1e-15
            seen.append(want)
    assert min(seen) < 0.05 and max(seen) > 0.99


@pytest.mark.parametrize("kind", ["cubic", "polynomial", "piecewise", "coupled"])
def test_the_modal_curvature_is_the_nonlinear_force_derivative(kind):
    """ModalSystem.curvature (content.tongue_partner's averaged partner frequency) equals the central difference of
    the modal nonlinear force's entry j along q_j, at random states, for springs, kinks and coupled elements (to the
    extrapolated difference's own error, ~1e-9 relative)."""
    sys_ = modal_system(MODELS[kind]())
    rng = np.random.default_rng(3)
    q = 0.4 * rng.standard_normal((6, sys_.n))
    def central(j, h):
        e = np.zeros(sys_.n)
        e[j] = h
        return (sys_.nonlinear_force(q + e)[:, j] - sys_.nonlinear_force(q - e)[:, j]) / (2 * h)

    for j in range(sys_.n):
        fd = (4 * central(j, 1e-6) - central(j, 2e-6)) / 3          # Richardson (kinks smoothed over 2e-4)
        got = sys_.curvature(q, j)
        assert got.shape == (6,)
        assert np.allclose(got, fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max()), (j, got, fd)
