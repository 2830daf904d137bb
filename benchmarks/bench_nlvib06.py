"""NLvib's example 06 (two orthogonal springs in large deflection, undamped) side by side with nnm: issue 55's check.

    NLVIB_DIR=/path/to/NLvib python benchmarks/bench_nlvib06.py [--octave octave] [--H 7]

NLvib (in GNU Octave, its own example settings: H = 7, N = 4 H + 1, continuation in log10 of the modal amplitude
from -6, step 0.01, up to log10 a = -0.15 or omega < 1) computes NNM 1 of

    q1'' + om1^2 q1 + om1^2/2 (3 q1^2 + q2^2) + om2^2 q1 q2 + (om1^2 + om2^2)/2 q1 (q1^2 + q2^2) = 0
    q2'' + om2^2 q2 + om2^2/2 (3 q2^2 + q1^2) + om1^2 q1 q2 + (om1^2 + om2^2)/2 q2 (q1^2 + q2^2) = 0

with om1 = 1.13, om2 = 2 and the damping set to zero (its NMA then returns del = 0: the conservative NNM).  Octave
writes NLvib's points (its Fourier coefficients and frequencies) with ``save -v7``; here each point's energy is
computed from its coefficients (kinetic + linear + the PolynomialStiffness potential at t = 0, where q' = 0 for
nnm's phase: NLvib's phase differs, so the energy is taken as the mean over one period of the HB orbit), and nnm
solves (a) its own HB equations (same H) at NLvib's amplitude and (b) the exact orbit by shooting (gauss6, its branch
interpolated in energy).  nnm's HB is compared at NLvib's own amplitude measure, the fundamental amplitude |Q_1,1|
of q1 (the same equations at the same point: the energy of a truncated orbit is defined only to its truncation, at
t = 0 for nnm and here the mean over the period).  Reported: the largest relative frequency difference over NLvib's points below the
first energy maximum for each, and the times.  Without Octave or an NLvib checkout: prints why, exits 0.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

SCRIPT = """addpath([nlvib '/SRC']); addpath([nlvib '/SRC/MechanicalSystems']);
om1 = 1.13; om2 = 2; M = eye(2); D = zeros(2); K = diag([om1^2 om2^2]);
p = [2 0; 1 1; 0 2; 3 0; 2 1; 1 2; 0 3];
E = [3*om1^2/2 om2^2/2; om2^2 om1^2; om1^2/2 3*om2^2/2; (om1^2+om2^2)/2*[1 0; 0 1; 1 0; 0 1]];
oscillator = System_with_PolynomialStiffnessNonlinearity(M,D,K,p,E,[1;1]);
n = oscillator.n; analysis = 'NMA'; N = 4*H+1; imod = 1; log10a_s = -6; log10a_e = -.15; inorm = 1;
om = sqrt(K(imod,imod)); phi = zeros(n,1); phi(imod) = 1;
Psi = zeros((2*H+1)*n,1); Psi(n+(1:n)) = phi; x0 = [Psi;om;0];
ds = .01; Sopt.termination_criterion = {@(Y) Y(end-2)<1.0};
Solopt = optimset('Display','off','Jacobian','on','MaxIter',50);
t0 = tic; c0 = cputime;
X = solve_and_continue(x0, @(X) HB_residual(X,oscillator,H,N,analysis,inorm), log10a_s, log10a_e, ds, Sopt, {}, Solopt);
wall = toc(t0); cpu = cputime - c0;
om_NM = X(end-2,:); del_NM = X(end-1,:); a_NM = 10.^X(end,:);
Q_NM = X(1:end-3,:).*repmat(a_NM,size(X,1)-3,1);
save('-v7', mat, 'om_NM', 'del_NM', 'Q_NM', 'wall', 'cpu', 'H');
"""


def nlvib_points(octave, nlvib, H, workdir):
    mat = str(Path(workdir) / "nlvib06.mat")
    script = Path(workdir) / "nlvib06.m"
    script.write_text(f"nlvib = '{nlvib}'; H = {H}; mat = '{mat}';\n" + SCRIPT)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    out = subprocess.run([octave, "--no-gui", "--quiet", "--no-window-system", str(script)], cwd=workdir, env=env,
                         capture_output=True, text=True, timeout=3600)
    if not Path(mat).is_file():
        raise RuntimeError(f"NLvib failed in Octave:\n{out.stdout[-2000:]}\n{out.stderr[-2000:]}")
    from scipy.io import loadmat
    return loadmat(mat)


def orbit_energy(model, Q, om, H, samples=256):
    """Mean energy over one period of the HB orbit with NLvib's coefficients Q ((2H + 1) n: mean, cos 1, sin 1,
    ...) and angular frequency om (constant to the truncation)."""
    n = model.n
    C = Q.reshape(2 * H + 1, n)
    th = 2 * np.pi * np.arange(samples) / samples
    k = np.arange(1, H + 1)
    q = C[0] + np.cos(np.outer(th, k)) @ C[1::2] + np.sin(np.outer(th, k)) @ C[2::2]
    v = om * (-np.sin(np.outer(th, k)) * k @ C[1::2] + np.cos(np.outer(th, k)) * k @ C[2::2])
    return float(np.mean(model.energy(q, v)))


def hb_at_amplitudes(model, H, a1, guess_branch):
    """nnm's HB frequency (Hz) at each fundamental amplitude a1 (m) of coordinate q1 (NLvib's own amplitude
    measure, so that both solve the same equations at the same point): Newton on [HB equations; |Q_1,1| - a1_i]
    (least squares: the full basis' phase row makes one more row), from nnm's branch."""
    from nnm_solver.model.modal import modal_system
    from nnm_solver.orbits.harmonic_balance import HBProblem
    system = modal_system(model)
    prob = HBProblem(system, 0, guess_branch.settings.hb_basis())
    c1, s1 = 1, 2                                          # full basis: mean, cos 1, sin 1, ...
    U = [prob.pack(np.array([system.to_modal(x) for x in np.asarray(guess_branch.coefficients_at(i))]),
                   2 * np.pi * guess_branch.frequency_hz[i]) for i in range(len(guess_branch.energy))]
    amp = lambda u: float(np.hypot(*prob.unpack(u)[0][[c1, s1], 0]))
    ab = np.array([amp(u) for u in U])
    out = []
    for ai in a1:
        j = int(np.argmin(np.abs(ab - ai)))
        u = U[j].copy()
        prob.q_ref = prob.initial_state(u)[0] / np.linalg.norm(prob.initial_state(u)[0])
        for _ in range(40):
            r, J = prob.jacobian(u)
            A = prob.unpack(u)[0]
            g = np.zeros(len(u))
            g[c1 * prob.n] = A[c1, 0] / amp(u)
            g[s1 * prob.n] = A[s1, 0] / amp(u)
            du = np.linalg.lstsq(np.vstack([J, g]), -np.concatenate([r, [amp(u) - ai]]), rcond=None)[0]
            u = u + du
            if np.linalg.norm(du) <= 1e-14 * np.linalg.norm(u):
                break
        out.append(u[-1] * prob.w_r / (2 * np.pi))
    return np.array(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--octave", default=os.environ.get("OCTAVE", "octave"))
    ap.add_argument("--nlvib", default=os.environ.get("NLVIB_DIR"))
    ap.add_argument("--H", type=int, default=7)
    ap.add_argument("--verbose", action="store_true", help="every point's difference")
    a = ap.parse_args(argv)
    octave = shutil.which(a.octave)
    if octave is None or not a.nlvib or not (Path(a.nlvib) / "SRC" / "HB_residual.m").is_file():
        print("skipped: " + ("GNU Octave not found" if octave is None else "no NLvib checkout (NLVIB_DIR or --nlvib)"))
        return 0
    import nnm_solver as nnm
    from scipy.interpolate import CubicSpline
    from test_polynomial_stiffness import example06
    print(f"load average: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as work:
        res = nlvib_points(octave, str(Path(a.nlvib).resolve()), a.H, work)
    om, Q, H = res["om_NM"].ravel(), res["Q_NM"], int(res["H"].ravel()[0])
    print(f"NLvib: {len(om)} points, {float(res['cpu'].ravel()[0]):.2f} s CPU, {float(res['wall'].ravel()[0]):.2f} s "
          f"wall; max |del| {np.max(np.abs(res['del_NM'])):.1e}")
    model = example06()
    E = np.array([orbit_energy(model, Q[:, i], om[i], H) for i in range(len(om))])
    f = om / (2 * np.pi)
    k = int(np.argmax(np.diff(E) < 0)) + 1 if np.any(np.diff(E) < 0) else len(E)
    E, f = E[:k], f[:k]
    keep = E > 1e-9                                   # the first points: the linear mode, energies ~1e-12
    E, f = E[keep], f[keep]
    t = time.process_time()
    hb = nnm.continue_nnm(model, 1, 1.2 * E[-1], "hb", harmonics=H, energy_min=E[0] * 0.9, tol=1e-11,
                          max_rel_step=0.1, max_points=400)
    t_hb = time.process_time() - t
    t = time.process_time()
    sh = nnm.continue_nnm(model, 1, 1.2 * E[-1], "shooting", energy_min=E[0] * 0.9, tol=1e-11, max_points=400)
    t_sh = time.process_time() - t
    print(f"nnm HB (H = {H}): {len(hb)} points, {t_hb:.2f} s CPU, {hb.status}; shooting (gauss6): {len(sh)} points, "
          f"{t_sh:.2f} s CPU, {sh.status}")
    inside = (E >= hb.energy[0]) & (E <= hb.energy[-1])
    a1 = np.hypot(Q[2, :], Q[4, :])[:k][keep]        # |Q_1,1|: rows n + 1 (cos 1) and 2n + 1 (sin 1), 1-based
    f_hb = hb_at_amplitudes(model, H, a1[inside], hb)
    d_hb = np.abs(f_hb / f[inside] - 1)
    inside_sh = (E >= sh.energy[0]) & (E <= sh.energy[-1])
    f_sh = CubicSpline(sh.energy, sh.frequency_hz)(E[inside_sh])
    d_sh = np.abs(f_sh / f[inside_sh] - 1)
    print(f"NLvib's {int(inside.sum())} points from {E[inside][0]:.3g} J to {E[inside][-1]:.4g} J "
          f"(f {f[inside][0]:.6f} -> {f[inside][-1]:.6f} Hz):")
    print(f"  nnm HB (same H) at NLvib's amplitudes |Q_1,1|: max |f_nnm / f_NLvib - 1| = {d_hb.max():.2e}")
    print(f"  nnm shooting (spline at NLvib's energies): max |f_nnm / f_NLvib - 1| = {d_sh.max():.2e}")
    if a.verbose:
        for Ei, fi, dh in zip(E[inside], f[inside], d_hb):
            print(f"    E {Ei:.4e} J  f_NLvib {fi:.8f} Hz  HB diff {dh:.2e}")
    print(f"load average: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
