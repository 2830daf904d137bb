"""Forced responses (driver/forced.py, orbits/forced_hb.py), their stability, the energy-balance prediction of the
resonance peak (analysis/energy_balance.py) and their file (files/forced_io.py), against independent references:
long DOP853 integration of the damped, forced Duffing oscillator, the one-harmonic frequency-response equation,
the closed-form linear response, and the uncondensed equations for the condensed ones."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.forced_hb import ForcedBasis, ForcedHBProblem
from nnm_solver.orbits.forced_hb_condensed import CondensedForcedHBProblem

# x'' + 2 zeta x' + x + k3 x^3 = F cos(w t): bistable between its two folds near w = 1.15 and 1.21
K3, ZETA, F = 0.1, 0.05, 0.3
W_RANGE = (0.5, 2.0)                       # rad/s


def duffing(k3=K3):
    return nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=k3)], name="Duffing")


def two_dof(k3=0.5):
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=k3)])


def hz(w):
    return w / (2 * np.pi)


@pytest.fixture(scope="module")
def curve():
    return nnm.forced_response(duffing(), [F], (hz(W_RANGE[0]), hz(W_RANGE[1])), ZETA, harmonics=9, tol=1e-12)


def ode_peak(w, y0, periods, k3=K3, zeta=ZETA, force=F):
    """max |x| over the last period of DOP853 (rtol 1e-10) from y0 after ``periods`` periods, and the final state."""
    T = 2 * np.pi / w

    def rhs(t, y):
        return [y[1], force * np.cos(w * t) - 2 * zeta * y[1] - y[0] - k3 * y[0] ** 3]

    sol = solve_ivp(rhs, (0.0, periods * T), y0, method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True)
    x = np.abs(sol.sol(np.linspace((periods - 1) * T, periods * T, 4001))[0])
    k = int(np.argmax(x))
    y0_, y1, y2 = x[k - 1:k + 2]
    return y1 - 0.125 * (y0_ - y2) ** 2 / (y0_ - 2 * y1 + y2)


def branch_point(curve, w_target, branch):
    """Index of the point nearest w_target on the lower-frequency ('low': before the first fold), middle or
    upper-frequency ('high': after the second fold) branch of the curve."""
    i1, i2 = curve.folds[0]["index"], curve.folds[1]["index"]
    idx = {"low": np.arange(0, i1), "middle": np.arange(i1, i2), "high": np.arange(i2, len(curve))}[branch]
    w = 2 * np.pi * curve.frequency_hz[idx]
    return int(idx[np.argmin(np.abs(w - w_target))])


def test_duffing_folds_and_stability(curve):
    """Two folds, the continuation went through both; the middle branch unstable by Hill's method (a real multiplier
    > 1) and by the fold test, the outer branches stable; the curve reaches the end of the range."""
    assert curve.status == "done", curve.message
    assert np.isclose(curve.frequency_hz[-1], hz(W_RANGE[1]), rtol=1e-14)
    assert len(curve.folds) == 2 and all(f["located"] for f in curve.folds)
    i1, i2 = curve.folds[0]["index"], curve.folds[1]["index"]
    assert curve.stability == "hill" and not curve.condensed and curve.basis_kind == "odd"
    assert np.all(curve.stable[:i1]) and np.all(curve.stable[i2:])
    assert i2 - i1 >= 5 and not np.any(curve.stable[i1:i2])
    assert np.array_equal(curve.stable, curve.fold_sign > 0)
    mid = curve.floquet[(i1 + i2) // 2]
    assert abs(mid[0].imag) < 1e-9 and mid[0].real > 1.01            # saddle: a real multiplier > 1
    w = 2 * np.pi * curve.frequency_hz
    assert np.all(np.diff(w[:i1]) > 0) and np.all(np.diff(w[i1:i2]) < 0) and np.all(np.diff(w[i2:]) > 0)


@pytest.mark.parametrize("w_target, branch", [(1.17, "low"), (1.19, "low"), (1.17, "high"), (1.0, "low")])
def test_duffing_amplitude_against_time_integration(curve, w_target, branch):
    """Steady state of a long DOP853 integration at points of both stable branches around the fold: from the HB orbit's
    state on the resonant (large-amplitude) branch, from rest on the other (whose basin holds the rest state)."""
    i = branch_point(curve, w_target, branch)
    w = 2 * np.pi * curve.frequency_hz[i]
    _, x, v = curve.orbit(i, 4)
    if branch == "high":
        ref = ode_peak(w, [0.0, 0.0], 110)          # transients e^(-zeta t): 1e-11 after 110 periods
    else:
        ref = ode_peak(w, [x[0, 0], v[0, 0]], 40)
    assert abs(curve.amplitude(0)[i] / ref - 1) <= 1e-5
    if branch == "high":                              # the two branches really differ at this frequency
        j = branch_point(curve, w, "low")
        assert curve.amplitude(0)[j] > 2 * curve.amplitude(0)[i]


def test_duffing_middle_branch_is_left_by_the_time_integration(curve):
    """The middle branch's orbit, perturbed by 1e-6, ends on one of the two stable branches (Hill's flag, by time
    integration)."""
    i = (curve.folds[0]["index"] + curve.folds[1]["index"]) // 2
    w = 2 * np.pi * curve.frequency_hz[i]
    _, x, v = curve.orbit(i, 4)
    end = ode_peak(w, [x[0, 0] * (1 + 1e-6), v[0, 0]], 150)
    a_mid = curve.amplitude(0)[i]
    others = [curve.amplitude(0)[branch_point(curve, w, b)] for b in ("low", "high")]
    assert abs(end / a_mid - 1) > 0.1
    assert min(abs(end / a - 1) for a in others) < 1e-3


def one_harmonic_folds(k3=K3, zeta=ZETA, force=F):
    """Fold frequencies (rad/s) of the one-harmonic frequency-response equation
    a^2 [(1 + 3/4 k3 a^2 - w^2)^2 + (2 zeta w)^2] = F^2, by the extrema of w(a) on a fine amplitude grid refined by a
    parabola (independent of the continuation)."""
    a = np.linspace(0.2, 3.0, 400001)
    b = 1 + 0.75 * k3 * a * a
    p, q = 2 * b - 4 * zeta * zeta, b * b - force * force / (a * a)
    disc = p * p / 4 - q
    out = []
    ok = disc >= 0
    X = p / 2 + np.sqrt(np.where(ok, disc, 0.0))          # the branch over the resonance, X = w^2
    w = np.where(ok, np.sqrt(X), np.nan)
    d = np.diff(w)
    for k in np.flatnonzero((d[1:] * d[:-1] < 0) & ok[1:-1] & ok[:-2] & ok[2:]):
        y0, y1, y2 = w[k:k + 3]
        out.append(y1 - 0.125 * (y0 - y2) ** 2 / (y0 - 2 * y1 + y2))
    return sorted(out)


def test_duffing_fold_frequencies(curve):
    """The located folds against the one-harmonic frequency-response equation, to its truncation: the relative error
    of the one-harmonic balance is about the third harmonic's share of the fold orbit times the nonlinear share of
    the stiffness, 3/4 k3 a^2 / w^2 (measured: 0.3-0.5 times that); and against a finer series (H = 15) to 1e-9."""
    w_hb = np.sort(2 * np.pi * curve.fold_frequencies_hz)
    w_1 = one_harmonic_folds()
    assert len(w_1) == 2
    for wf, w1, fold in zip(w_hb, w_1, sorted(curve.folds, key=lambda f: f["frequency_hz"])):
        X = fold["coefficients"][:, 0]
        a1 = np.hypot(X[0], X[1])
        truncation = np.hypot(X[2], X[3]) / a1 * 0.75 * K3 * a1 ** 2 / wf ** 2
        assert abs(wf / w1 - 1) < truncation, (wf, w1, truncation)
    fine = nnm.forced_response(duffing(), [F], (hz(1.1), hz(1.3)), ZETA, harmonics=15, tol=1e-12, stability="fold")
    assert np.allclose(np.sort(2 * np.pi * fine.fold_frequencies_hz), w_hb, rtol=1e-9, atol=0)


@pytest.mark.slow
def test_duffing_jump_at_the_fold_by_time_integration(curve):
    """0.5 % below the upper fold the resonant orbit persists; 0.5 % above it, started from the fold orbit, the
    integration drops to the other branch (the jump)."""
    top = max(curve.folds, key=lambda f: f["frequency_hz"])
    wf = 2 * np.pi * top["frequency_hz"]
    X = top["coefficients"][:, 0]
    basis = curve.basis
    x0, v0 = basis.functions([0.0])[0] @ X, wf * (basis.derivatives([0.0])[0] @ X)
    a_fold = np.hypot(X[0], X[1])
    above = ode_peak(wf * 1.005, [x0, v0], 250)
    below = ode_peak(wf * 0.995, [x0, v0], 250)
    assert above < 0.5 * a_fold and below > 0.9 * a_fold


def test_linear_response_phase_amplitude_and_multipliers():
    """No nonlinear element: amplitude |F / (1 - w^2 + 2 i zeta w)|, phase of the fundamental -atan2(2 zeta w, 1 - w^2)
    (-pi/2 at resonance, unwrapped past it), Hill's multipliers exp((-zeta +- i sqrt(1 - zeta^2)) T)."""
    z = 0.02
    seen = []
    r = nnm.forced_response(nnm.Model(np.eye(1), np.eye(1)), [2.0], (hz(0.5), hz(1.8)), z, harmonics=3, tol=1e-12,
                            on_point=seen.append)
    assert r.status == "done" and not r.folds
    assert [p["index"] for p in seen] == list(range(len(r))) and seen[-1]["frequency_hz"] == r.frequency_hz[-1]
    w = 2 * np.pi * r.frequency_hz
    H = 2.0 / (1 - w * w + 2j * z * w)
    assert np.allclose(r.amplitude(0), np.abs(H), rtol=1e-10)
    assert np.allclose(r.phase(0), -np.arctan2(2 * z * w, 1 - w * w), atol=1e-10)
    assert r.phase(0)[-1] < -np.pi / 2
    T = 2 * np.pi / w
    lam = -z + 1j * np.sqrt(1 - z * z)
    assert np.allclose(np.abs(r.floquet[:, 0]), np.exp(-z * T), rtol=1e-8)
    assert np.allclose(np.sort_complex(r.floquet[5]), np.sort_complex(np.exp(np.array([lam, np.conj(lam)]) * T[5])))


@pytest.mark.parametrize("zeta", [0.001, 0.01])
def test_energy_balance_predicts_the_peak(zeta):
    """Light damping: the peak of the forced response (frequency and amplitude) against the energy balance along the
    conservative backbone (HB), within 1 %, and its phase-resonance point within 0.1 % (measured: 3e-5 and 1e-4,
    the linear interpolations between points)."""
    model = duffing()
    force = 2 * zeta * 1.0                         # a peak amplitude near 1 (linear: F / (2 zeta))
    backbone = nnm.continue_nnm(model, 1, 2.0, method="hb", harmonics=9, floquet=False)
    r = nnm.forced_response(model, [force], (hz(0.9), hz(1.2)), zeta, harmonics=9, tol=1e-11, stability="fold")
    eb = nnm.energy_balance(backbone, [force], zeta)
    assert np.all(np.diff(eb.force_scale) > 0)
    pred = eb.at_scale(1.0, 0)
    peak = r.peak(0)
    assert pred is not None and 0.5 < peak["amplitude"] < 2
    assert abs(peak["frequency_hz"] / pred["frequency_hz"] - 1) < 0.01
    assert abs(peak["amplitude"] / pred["amplitude"] - 1) < 0.01
    # energy balance predicts the phase-resonance point (force along the velocity): closer still
    pr = r.phase_resonance(0)
    assert len(pr) == 1
    assert abs(pr[0]["frequency_hz"] / pred["frequency_hz"] - 1) < 1e-3
    assert abs(pr[0]["amplitude"] / pred["amplitude"] - 1) < 1e-3
    # the single-mode formula at small amplitude: alpha = 2 zeta w a / F for the unit force pattern
    a0 = eb.amplitude(0)[0]
    assert np.isclose(eb.force_scale[0] * force, 2 * zeta * 2 * np.pi * eb.frequency_hz[0] * a0, rtol=1e-3)


@pytest.mark.parametrize("basis", ["odd", "full"])
def test_two_dof_condensed_equals_uncondensed(basis):
    """The 2-DOF benchmark forced at both DOFs through the first resonance: the condensed orbits solve the uncondensed
    equations, and the folds, the end point and the peak agree to 1e-9."""
    model = two_dof()
    force = np.array([0.05, 0.02])
    kw = dict(harmonics=7, tol=1e-12, basis=basis, damping=[0.02, 0.01])
    f_range = (0.13, 0.21)
    a = nnm.forced_response(model, force, f_range, condensed=False, **kw)
    b = nnm.forced_response(model, force, f_range, condensed=True, **kw)
    assert a.status == b.status == "done" and b.condensed and not a.condensed
    assert len(a.folds) == len(b.folds) == 2
    assert np.allclose(a.fold_frequencies_hz, b.fold_frequencies_hz, rtol=1e-9, atol=0)
    assert np.allclose(a.coefficients[-1], b.coefficients[-1], rtol=0, atol=1e-9 * np.abs(a.coefficients[-1]).max())
    assert abs(a.peak(0)["amplitude"] / b.peak(0)["amplitude"] - 1) < 1e-3     # parabolas through other points
    system = modal_system(model)
    fb = ForcedBasis(7, basis)
    full = ForcedHBProblem(system, fb, system.Phi.T @ force, 2 * np.array([0.02, 0.01]) * np.sqrt(system.omega2), 1.0)
    for i in range(0, len(b), 5):
        u = full.pack(system.to_modal(b.coefficients[i]), 2 * np.pi * b.frequency_hz[i])
        assert full.error(u, full.residual(u)) < 1e-10
    assert np.array_equal(a.stable[[0, -1]], b.stable[[0, -1]]) and np.all(a.stable[[0, -1]])
    assert np.any(~b.stable) and np.array_equal(b.stable, b.fold_sign > 0)


@pytest.mark.parametrize("kind", ["odd", "full"])
def test_condensed_jacobian_matches_finite_differences(kind):
    model = nnm.Model(np.diag(1 + 0.1 * np.arange(5)), 2 * np.eye(5) - np.eye(5, k=1) - np.eye(5, k=-1),
                      [nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=4, k3=-0.3)])
    system = modal_system(model)
    fq = system.Phi.T @ np.array([0.0, 0.3, 0.0, 0.1, 0.0])
    c = 0.06 * np.sqrt(system.omega2)
    rng = np.random.default_rng(1)
    for P in (CondensedForcedHBProblem(system, ForcedBasis(5, kind), fq, c, 1.0),
              ForcedHBProblem(system, ForcedBasis(5, kind), fq, c, 1.0)):
        u = P.linear_start(0.9)
        u[:-1] += 0.3 * rng.standard_normal(len(u) - 1) * np.abs(u[:-1]).max()
        r, J = P.jacobian(u)
        Jfd = np.zeros_like(J)
        for i in range(len(u)):
            e = np.zeros(len(u))
            e[i] = 1e-6 * max(1.0, abs(u[i]))
            Jfd[:, i] = (P.residual(u + e) - P.residual(u - e)) / (2 * e[i])
        assert np.allclose(r, P.residual(u))
        assert np.max(np.abs(J - Jfd)) < 1e-7 * np.max(np.abs(J))


def test_damping_matrix_proportional_and_coupling():
    """A Rayleigh matrix a M + b K is modal damping zeta_k = a / (2 w_k) + b w_k / 2 (condensed allowed); a dashpot
    from DOF 0 to the ground couples the modes (uncondensed) and its response matches DOP853."""
    model = two_dof()
    force = np.array([0.05, 0.0])
    w = np.sqrt(modal_system(model).omega2)
    al, be = 0.01, 0.02
    kw = dict(condensed=True, harmonics=5, tol=1e-12, stability="none")
    ray = nnm.forced_response(model, force, (0.15, 0.17), 0.0, damping_matrix=al * np.eye(2) + be * model.K, **kw)
    mod = nnm.forced_response(model, force, (0.15, 0.17), al / (2 * w) + be * w / 2, **kw)
    assert np.allclose(ray.coefficients[-1], mod.coefficients[-1], atol=1e-12)
    C = np.diag([0.03, 0.0])
    with pytest.raises(nnm.NNMInputError, match="couples the modes"):
        nnm.forced_response(model, force, (0.12, 0.2), 0.01, damping_matrix=C, condensed=True)
    r = nnm.forced_response(model, force, (0.14, 0.18), 0.01, damping_matrix=C, harmonics=7, tol=1e-12,
                            stability="fold")
    assert r.status == "done" and not r.condensed
    i = int(np.argmax(r.amplitude(0)))
    wi = 2 * np.pi * r.frequency_hz[i]
    _, x, v = r.orbit(i, 4)
    Cfull = C + 2 * 0.01 * (r.model.M @ modal_system(model).Phi @ np.diag(w) @ modal_system(model).Phi.T @ r.model.M)
    Kn = model.K

    def rhs(t, y):
        xx, vv = y[:2], y[2:]
        fnl = np.array([0.5 * xx[0] ** 3, 0.0])
        return np.concatenate([vv, force * np.cos(wi * t) - Cfull @ vv - Kn @ xx - fnl])

    T = 2 * np.pi / wi
    sol = solve_ivp(rhs, (0, 30 * T), np.concatenate([x[0], v[0]]), method="DOP853", rtol=1e-10, atol=1e-12,
                    dense_output=True)
    xs = np.abs(sol.sol(np.linspace(29 * T, 30 * T, 4001))[0])
    k = int(np.argmax(xs))
    ref = xs[k] - 0.125 * (xs[k - 1] - xs[k + 1]) ** 2 / (xs[k - 1] - 2 * xs[k] + xs[k + 1])
    assert abs(r.amplitude(0)[i] / ref - 1) < 1e-5


def test_file_round_trip_and_refusal(tmp_path, curve):
    path = tmp_path / "duffing.h5"
    nnm.save_model(path, curve.model)
    assert nnm.load_forced_responses(path) == []
    g1 = nnm.save_forced_response(path, curve, name="level 1")
    g2 = nnm.save_forced_response(path, curve, name="level 1")
    assert (g1, g2) == ("level 1", "level 1_2")
    back = nnm.load_forced_responses(path)
    assert len(back) == 2
    r = back[0]
    for key in ("frequency_hz", "coefficients", "floquet", "stable", "fold_sign", "force", "damping"):
        assert np.array_equal(getattr(r, key), getattr(curve, key)), key
    assert (r.status, r.harmonics, r.basis_kind, r.stability) == (curve.status, 9, "odd", "hill")
    assert np.array_equal(r.fold_frequencies_hz, curve.fold_frequencies_hz)
    assert np.array_equal(r.folds[1]["coefficients"], curve.folds[1]["coefficients"])
    assert np.array_equal(r.amplitude(0), curve.amplitude(0))
    before = path.read_bytes()
    other = nnm.forced_response(duffing(k3=0.2), [F], (hz(0.5), hz(0.6)), ZETA, harmonics=3)
    with pytest.raises(nnm.NNMInputError, match="another model") as exc:
        nnm.save_forced_response(path, other)
    assert "\n" not in str(exc.value) and path.read_bytes() == before
    # a new file gets the model; branches and forced responses live side by side
    p2 = tmp_path / "new.h5"
    nnm.save_forced_response(p2, other)
    nnm.save_branch(p2, nnm.continue_nnm(other.model, 1, 0.1, method="hb", harmonics=3, floquet=False))
    assert len(nnm.load_branches(p2)) == 1 and nnm.load_forced_responses(p2)[0].name == "forced"


def test_plot(tmp_path, curve):
    from nnm_solver.results.forced_plot import plot_forced
    backbone = nnm.continue_nnm(duffing(), 1, 6.0, method="hb", harmonics=5, floquet=False)
    eb = nnm.energy_balance(backbone, [1.0], ZETA)
    out = tmp_path / "frf.png"
    ax = plot_forced(curve, 0, backbones=backbone, predictions=eb, path=out)
    assert out.stat().st_size > 1000
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("unstable" in s for s in labels) and any("energy balance" in s for s in labels)


@pytest.mark.parametrize("kwargs, match", [
    (dict(damping=-0.01), "damping is -0.01: damping ratios must be >= 0"),
    (dict(damping=[0.01, -0.02]), "damping ratio of mode 2 is -0.02"),
    (dict(damping=float("nan")), "damping is nan"),
    (dict(damping=[0.01, 0.01, 0.01]), "damping has 3 ratios, the model has 2 modes"),
    (dict(force=[1.0, 2.0, 3.0]), "force has 3 entries, the model has 2 DOFs"),
    (dict(force=[1.0, float("nan")]), r"force\[1\] is nan"),
    (dict(force=[0.0, 0.0]), "force is zero"),
    (dict(f_range_hz=(0.2, 0.2)), "is empty"),
    (dict(f_range_hz=(-0.1, 0.2)), "must be positive and finite"),
    (dict(f_range_hz=(0.1, float("nan"))), "must be positive and finite"),
    (dict(f_range_hz=(0.1, 0.2, 0.3)), "must be two frequencies"),
    (dict(harmonics=0), "harmonics must be a positive integer"),
    (dict(basis="cosine"), "basis must be one of"),
    (dict(stability="monodromy"), "stability must be one of"),
    (dict(condensed="yes"), "condensed must be True, False or None"),
    (dict(damping_matrix=np.eye(3)), r"damping_matrix has shape \(3, 3\)"),
    (dict(damping_matrix=-np.eye(2)), "not positive semi-definite"),
])
def test_bad_input_one_clear_line(kwargs, match):
    args = dict(model=two_dof(), force=[1.0, 0.0], f_range_hz=(0.1, 0.2), damping=0.01)
    args.update(kwargs)
    with pytest.raises(nnm.NNMInputError, match=match) as exc:
        nnm.forced_response(**args)
    assert "\n" not in str(exc.value)


def test_bad_input_elements_and_energy_balance():
    even = nnm.Model(np.eye(2), two_dof().K, [nnm.PolynomialSpring(dof=0, coefficients={2: 0.3})])
    with pytest.raises(nnm.NNMInputError, match="basis='odd' needs odd element forces"):
        nnm.forced_response(even, [1.0, 0.0], (0.1, 0.2), 0.01, basis="odd")
    backbone = nnm.continue_nnm(two_dof(), 1, 0.5, method="hb", harmonics=3, floquet=False)
    with pytest.raises(nnm.NNMInputError, match="force has 1 entries, the model has 2 DOFs"):
        nnm.energy_balance(backbone, [1.0], 0.01)
    with pytest.raises(nnm.NNMInputError, match="damping is -1"):
        nnm.energy_balance(backbone, [1.0, 0.0], -1)


def test_sweep_down_and_a_curve_leaving_the_range():
    """Down the frequency range: the same curve (folds to 1e-10, the end points' amplitudes); started on the lower
    branch inside the bistable range and swept down, the curve turns at the fold and leaves through f_start."""
    up = nnm.forced_response(duffing(), [F], (hz(0.8), hz(1.5)), ZETA, harmonics=5, tol=1e-12, stability="fold")
    down = nnm.forced_response(duffing(), [F], (hz(1.5), hz(0.8)), ZETA, harmonics=5, tol=1e-12, stability="fold")
    assert up.status == down.status == "done"
    assert np.allclose(up.fold_frequencies_hz, down.fold_frequencies_hz[::-1], rtol=1e-10, atol=0)
    assert np.allclose(up.amplitude(0)[[0, -1]], down.amplitude(0)[[-1, 0]], rtol=1e-10)
    back = nnm.forced_response(duffing(), [F], (hz(1.18), hz(0.8)), ZETA, harmonics=5, tol=1e-12, stability="fold")
    assert back.status == "left_range" and len(back.folds) == 1 and "left the range" in back.message
    assert np.all(2 * np.pi * back.frequency_hz <= 1.18 + 1e-12)


def nlvib_02():
    """NLvib's example 02 (Krack & Gross, Harmonic Balance for Nonlinear Vibration Problems, 2019): a chain of two
    masses (1, 0.05) with springs (1, 0.0453), dampers (0.002, 0.013) coupling the modes, a cubic spring 1 at DOF 0
    and 0.0042 between the DOFs, 0.11 cos(w t) on DOF 0; turning points and Neimark-Sacker bifurcations."""
    M = np.diag([1.0, 0.05])
    K = np.array([[1.0453, -0.0453], [-0.0453, 0.0453]])
    C = np.array([[0.015, -0.013], [-0.013, 0.013]])
    springs = [nnm.CubicSpring(dof=0, k3=1.0), nnm.CubicSpring(dof=0, other=1, k3=0.0042)]
    return nnm.Model(M, K, springs), C


@pytest.mark.slow
def test_hill_multipliers_against_the_monodromy_of_dop853():
    """Hill's multipliers with a damping matrix that couples the modes, against the monodromy matrix of the variational
    equations integrated with DOP853 over one period (rtol 1e-12) from the HB orbit: a stable orbit, one unstable
    through a complex pair (Neimark-Sacker: the fold test does not see it) and one between the folds (real > 1)."""
    model, C = nlvib_02()
    r = nnm.forced_response(model, [0.11, 0.0], (hz(1.0), hz(1.25)), 0.0, damping_matrix=C, harmonics=11, tol=1e-12,
                            basis="full")
    assert r.stability == "hill" and not r.condensed and len(r.folds) == 2
    M, K = model.M, model.K
    Minv = np.linalg.inv(M)
    w = 2 * np.pi * r.frequency_hz

    def variational(t, Y, om):
        x, v, Phi = Y[:2], Y[2:4], Y[4:].reshape(4, 4)
        d = x[0] - x[1]
        fnl = np.array([x[0] ** 3 + 0.0042 * d ** 3, -0.0042 * d ** 3])
        kd = 3 * 0.0042 * d * d
        Kt = K + np.array([[3 * x[0] ** 2 + kd, -kd], [-kd, kd]])
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ Kt, -Minv @ C]])
        acc = Minv @ (np.array([0.11 * np.cos(om * t), 0.0]) - C @ v - K @ x - fnl)
        return np.concatenate([v, acc, (A @ Phi).ravel()])

    kinds = []
    for target in (1.05, 1.15, 1.21):
        i = int(np.argmin(np.abs(w - target)))
        _, x, v = r.orbit(i, 4)
        sol = solve_ivp(variational, (0.0, 2 * np.pi / w[i]), np.concatenate([x[0], v[0], np.eye(4).ravel()]),
                        method="DOP853", rtol=1e-12, atol=1e-14, args=(w[i],))
        assert np.linalg.norm(sol.y[:4, -1] - sol.y[:4, 0]) < 1e-9             # the HB orbit is periodic
        mu = np.sort_complex(np.linalg.eigvals(sol.y[4:, -1].reshape(4, 4)))
        assert np.max(np.abs(np.sort_complex(r.floquet[i]) - mu)) < 1e-8
        top = r.floquet[i][0]
        kinds.append((bool(r.stable[i]), abs(top.imag) > 1e-6, int(r.fold_sign[i])))
    assert [k[0] for k in kinds] == [True, False, False] and [k[2] for k in kinds] == [1, 1, -1]
    assert kinds[1][1] and not kinds[2][1]           # unstable by a complex pair, then by a real multiplier
