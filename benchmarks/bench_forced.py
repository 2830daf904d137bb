"""Forced-response benchmark: converged points per second of ``nnm.forced_response``.

Usage (from the repository root)::

    python benchmarks/bench_forced.py                     # aircraft (condensed) + Duffing and 2-DOF, ~1 min
    python benchmarks/bench_forced.py --repeat 5
    python benchmarks/bench_forced.py --uncondensed 3     # + 3 points of the aircraft uncondensed (minutes)
    python benchmarks/bench_forced.py --nlvib ~/NLvib     # + NLvib's example 02 in GNU Octave, against nnm

Cases (each run --repeat times, the median reported, with the load average before it):

* ``paris``: assets/paris.h5 (548 DOFs, 4 cubic springs), mode 20 excited at the four tank attachments
  (examples/forced_aircraft.py's force pattern), zeta 0.2 %, f20 x [0.98, 1.005] (as the example), levels 1 and
  4 N per shaker (no fold / two folds on the builder-1.3 model; builder 1.2's rows used 33.5-34.5 Hz and 8 N), H = 5 and 7, odd basis, condensed (automatic), stability by the fold test.
* ``duffing``: x'' + 0.1 x' + x + 0.1 x^3 = 0.3 cos(w t), w = 0.5-2 rad/s, H = 9, uncondensed, Hill's
  multipliers at every point (the test case of tests/test_forced.py).
* ``2dof``: the 2-DOF benchmark (cubic spring 0.5 at DOF 0), force (0.05, 0.02) N, 0.13-0.21 Hz, H = 7,
  modal damping 2 % / 1 %, uncondensed and condensed, Hill's multipliers.

* ``nlvib`` (``--nlvib DIR``, a checkout of https://github.com/maltekrack/NLvib, and ``octave`` on the PATH):
  NLvib's example 02 (two masses, dampers coupling the modes, two cubic springs, 0.11 cos(w t), w = 0.8-1.4,
  H = 7, N = 29 samples), its HB continuation alone (``solve_and_continue`` + ``HB_residual``, no stability)
  run by Octave and timed with tic/toc, then nnm on the same equations (full basis, damping_matrix,
  samples=29, Hill's multipliers at every point); NLvib's points are plugged into nnm's HB equations (their
  largest relative residual says both solve the same problem, to NLvib's fsolve tolerance).

Points per second = converged points / wall time of the whole call (first orbit, continuation, fold location,
stability, the physical coefficients of every point); points per CPU second divides by this process's CPU
time instead (less sensitive to other jobs on a shared machine; one BLAS thread).  NLvib is MATLAB code; with
``--nlvib`` it runs in GNU Octave, usually slower than MATLAB: its points/s are Octave's, timed by tic/toc
around the continuation (Octave's start-up excluded).
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import nnm_solver as nnm  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))


def load():
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def timed(fn, repeat):
    """(result of the last run, (median wall s, median CPU s of this process), load averages before the runs)."""
    times, cpu, loads, out = [], [], [], None
    for _ in range(repeat):
        loads.append(load())
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return out, (statistics.median(times), statistics.median(cpu)), loads


def row(case, r, dt, loads):
    wall, cpu = dt
    print(f"| {case} | {len(r)} | {len(r.folds)} | {r.status} | {r.stability} | {wall:.3f} | {len(r) / wall:.0f} | "
          f"{len(r) / cpu:.0f} | {loads[0]} |", flush=True)


NLVIB_02 = r"""
addpath('{src}'); addpath('{src}/MechanicalSystems');
mi = [1 .05]; ki = [1 .0453 0]; di = [.002 .013 0]; Fex1 = [.11;0];
nonlinear_elements{{1}} = struct('type','cubicSpring','stiffness',1,'force_direction',[1;0]);
nonlinear_elements{{2}} = struct('type','cubicSpring','stiffness',.0042,'force_direction',[1;-1]);
oscillator = ChainOfOscillators(mi,di,ki,nonlinear_elements,Fex1);
H = 7; N = 4*H+1; Om_s = .8; Om_e = 1.4;
Q1 = (-Om_s^2*oscillator.M + 1i*Om_s*oscillator.D + oscillator.K)\Fex1;
y0 = zeros((2*H+1)*length(Q1),1);
y0(length(Q1)+(1:2*length(Q1))) = [real(Q1);-imag(Q1)];
Sopt = struct('Dscale',[1e-0*ones(size(y0));Om_s]);
Solopt = optimset('Display','off','Jacobian','on','MaxIter',50);
tic;
[X_HB,Solinfo_HB] = solve_and_continue(y0, @(X) HB_residual(X,oscillator,H,N,'FRF'), Om_s,Om_e,.02,Sopt,{{}},Solopt);
t = toc;
printf('NLVIB points %d time %.4f\n', size(X_HB,2), t);
dlmwrite('{out}', X_HB.', 'precision', 17);
"""


def nlvib_02(checkout, repeat):
    """NLvib's example 02 by Octave and by nnm (module docstring): one table row each, and the residual check."""
    import re
    import shutil
    import subprocess

    from nnm_solver.model.modal import modal_system
    from nnm_solver.orbits.forced_hb import ForcedBasis, ForcedHBProblem

    if shutil.which("octave") is None or not (checkout / "SRC" / "HB_residual.m").exists():
        print(f"| NLvib example 02 | (skipped: needs octave on the PATH and NLvib in {checkout}) |")
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x_hb.csv"
        script = Path(tmp) / "nlvib_02.m"
        script.write_text(NLVIB_02.format(src=(checkout / "SRC").as_posix(), out=out.as_posix()))
        times = []
        for _ in range(repeat):
            before = load()
            run = subprocess.run(["octave", "--no-gui", "--quiet", str(script)], cwd=tmp, capture_output=True,
                                 text=True, timeout=1800)
            m = re.search(r"NLVIB points (\d+) time ([\d.]+)", run.stdout)
            if m is None:
                print(f"| NLvib example 02 | (Octave failed: {run.stderr.strip().splitlines()[-1:]}) |")
                return
            times.append(float(m.group(2)))
        points = int(m.group(1))
        t = statistics.median(times)
        print(f"| NLvib example 02, H=7, Octave {octave_version()}, no stability | {points} | - | - | none | {t:.3f} | "
              f"{points / t:.0f} | - | {before} |", flush=True)
        X = np.loadtxt(out, delimiter=",", ndmin=2)
    M = np.diag([1.0, 0.05])
    K = np.array([[1.0453, -0.0453], [-0.0453, 0.0453]])
    C = np.array([[0.015, -0.013], [-0.013, 0.013]])
    model = nnm.Model(M, K, [nnm.CubicSpring(dof=0, k3=1.0), nnm.CubicSpring(dof=0, other=1, k3=0.0042)])
    run_nnm = lambda: nnm.forced_response(model, [0.11, 0.0], (0.8 / (2 * np.pi), 1.4 / (2 * np.pi)), 0.0,  # noqa: E731
                                          damping_matrix=C, harmonics=7, basis="full", samples=29)
    r, dt, loads = timed(run_nnm, repeat)
    row("NLvib example 02 by nnm, H=7, Hill", r, dt, loads)
    s = modal_system(model)
    problem = ForcedHBProblem(s, ForcedBasis(7, "full", 29), s.Phi.T @ np.array([0.11, 0.0]), s.Phi.T @ C @ s.Phi, 1.0)
    res = [problem.error(u, problem.residual(u)) for u in
           (problem.pack(s.to_modal(x[:-1].reshape(15, 2)), x[-1]) for x in X)]
    w = 2 * np.pi * r.frequency_hz
    changes = [f"{w[i]:.4f}-{w[i + 1]:.4f}" for i in np.flatnonzero(np.diff(r.stable.astype(int)))]
    print(f"\nNLvib's {len(X)} points in nnm's HB equations: relative residual median {np.median(res):.1e}, largest "
          f"{max(res):.1e}; nnm's folds at w = {', '.join(f'{2 * np.pi * f:.5f}' for f in r.fold_frequencies_hz)} "
          f"rad/s; stability changes (Hill) between w = {'; '.join(changes)} rad/s")


def octave_version():
    import subprocess
    out = subprocess.run(["octave", "--version"], capture_output=True, text=True).stdout
    return out.split("version")[-1].split()[0] if "version" in out else "?"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--uncondensed", type=int, default=0,
                    help="also this many points of the aircraft with the uncondensed equations (slow)")
    ap.add_argument("--nlvib", default=None, help="an NLvib checkout: run its example 02 in Octave and compare")
    args = ap.parse_args(argv)
    print(f"python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}; load average at start {load()}")
    print()
    print("| case | points | folds | status | stability | wall s (median) | points/s | points per CPU s "
          "| load avg (1, 5, 15 min) |")
    print("|---|---|---|---|---|---|---|---|---|")

    from forced_aircraft import force_pattern
    model = nnm.load_model(ROOT / "assets" / "paris.h5")
    pattern, _ = force_pattern(model)
    f20 = model.linear_modes()[0][19]
    band = (0.98 * f20, 1.005 * f20)                                      # as examples/forced_aircraft.py
    nnm.forced_response(model, pattern, band, 0.002, harmonics=5)          # warm-up (modes, caches)
    for H in (5, 7):
        for level in (1.0, 4.0):
            r, dt, loads = timed(lambda: nnm.forced_response(model, level * pattern, band, 0.002,
                                                             harmonics=H), args.repeat)
            row(f"paris mode 20, {level:g} N, H={H}, condensed", r, dt, loads)

    duffing = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=0.1)])
    r, dt, loads = timed(lambda: nnm.forced_response(duffing, [0.3], (0.5 / (2 * np.pi), 2 / (2 * np.pi)), 0.05,
                                                     harmonics=9), args.repeat)
    row("Duffing, H=9, Hill", r, dt, loads)
    two = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    for condensed in (False, True):
        r, dt, loads = timed(lambda: nnm.forced_response(two, [0.05, 0.02], (0.13, 0.21), [0.02, 0.01], harmonics=7,
                                                         condensed=condensed), args.repeat)
        row(f"2-DOF, H=7, {'condensed' if condensed else 'uncondensed'}, Hill", r, dt, loads)

    if args.uncondensed:
        r, dt, loads = timed(lambda: nnm.forced_response(model, 4 * pattern, band, 0.002, harmonics=5,
                                                         condensed=False, max_points=args.uncondensed), 1)
        row(f"paris mode 20, 4 N, H=5, uncondensed ({args.uncondensed} points)", r, dt, loads)
    if args.nlvib:
        nlvib_02(Path(args.nlvib).expanduser(), args.repeat)
    print(f"\nload average at the end {load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
