"""nnm side by side with NLvib (Krack & Gross's MATLAB harmonic-balance toolbox) on NLvib's own examples.

    NLVIB_DIR=/path/to/NLvib python benchmarks/bench_peers.py [--cases 04 09] [--repeats 3] [--octave octave]

NLvib's examples 04 (2-DOF oscillator with a cubic spring, NNM 1) and 09 (38-DOF clamped beam with a cubic spring at
its tip, NNM 1) are run in GNU Octave with NLvib's own settings (continuation in log10 of the modal amplitude, its
step length, scaling and time samples; example 04 with H = 7 and up to log10 a = 0.9, ~55 J, instead of its H = 9
up to the tongues: the range of the 2-DOF benchmark's pitchfork at 40.97 J).  Octave writes the matrices, the
spring and NLvib's points with ``save -v7``; nnm loads the same model with ``load_mat_model`` and computes the same
path (same H, from NLvib's first energy until NLvib's last frequency is reached, through the 5:1 tongue of example
09) by harmonic balance with the Floquet multipliers at every point (Hill's method), without them, and by shooting
(Newmark, 200 steps per period).  Reported: points, CPU and wall times (medians of --repeats; both sides single-
threaded: OPENBLAS_NUM_THREADS=1 for Octave, threadpoolctl for nnm; the load average with each timing), the ratio
NLvib CPU / nnm CPU, nnm's events, and the agreement: NLvib's frequency against nnm's HB orbit at the same energy
(nnm's HB equations solved at each of NLvib's energies below the first energy maximum, started from nnm's branch:
the difference of the two solvers' orbits, not of the point spacing), and the same for shooting by interpolation of
its branch (PCHIP in log energy; includes Newmark's discretisation error).

Nothing of NLvib is copied here: the Octave scripts are written to a temporary folder and call NLvib's SRC from
NLVIB_DIR (or --nlvib).  Without Octave or an NLvib checkout the benchmark prints why and exits 0 (skipped).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

OCTAVE_SOLVER = "Solopt = optimset('Display','off','Jacobian','on','MaxIter',50);"    # Octave 7: explicit options

_HEAD = """addpath([nlvib '/SRC']); addpath([nlvib '/SRC/MechanicalSystems']);
"""

CASE_04 = """mi = [1 1]; ki = [1 1 1]; di = 0*ki; knl = .5;
nonlinear_elements = struct('type','cubicSpring','stiffness',knl,'force_direction',[1;0]);
sys_ = ChainOfOscillators(mi,di,ki,nonlinear_elements);
n = sys_.n; idof = 1;
[PHI_lin,OM2] = eig(sys_.K,sys_.M); [om_lin,ind] = sort(sqrt(diag(OM2))); PHI_lin = PHI_lin(:,ind);
analysis = 'NMA'; N = 4*H+1; imod = 1; log10a_s = -1; log10a_e = {a_end}; inorm = 2;
om = om_lin(imod); phi = PHI_lin(:,imod);
Psi = zeros((2*H+1)*n,1); Psi(n+(1:n)) = phi; x0 = [Psi;om;0];
ds = .013;
Sopt = struct('Dscale',[1e-1*ones(size(x0,1)-2,1);1;1e-8;1],'dynamicDscale',1);
fun = @(X) HB_residual(X,sys_,H,N,analysis,inorm);
"""

CASE_09 = """len = .7; height = .014; thickness = .014; E = 2.05e11; rho = 7800; BCs = 'clamped-free'; n_nodes = 20;
sys_ = FE_EulerBernoulliBeam(len,height,thickness,E,rho,BCs,n_nodes);
knl = 6e9;
add_nonlinear_attachment(sys_,n_nodes,'trans','cubicSpring','stiffness',knl);
n = sys_.n; idof = find(sys_.nonlinear_elements{{1}}.force_direction);
[PHI_lin,OM2] = eig(sys_.K,sys_.M); om_lin = sqrt(diag(OM2)); [om_lin,ind] = sort(om_lin); PHI_lin = PHI_lin(:,ind);
analysis = 'NMA'; N = 4*H+1; imod = 1; log10a_s = -5; log10a_e = {a_end}; inorm = n-1;
om = om_lin(imod); phi = PHI_lin(:,imod);
Psi = zeros((2*H+1)*n,1); Psi(n+(1:n)) = phi; x0 = [Psi;om;0]; qscl = max(abs(Psi));
ds = .6;
Sopt = struct('Dscale',[qscl*1e-2*ones(size(x0,1)-2,1);om;1e0;1e0],'dynamicDscale',1);
fscl = mean(abs(sys_.K*phi));
fun = @(X) HB_residual(X,sys_,H,N,analysis,inorm,fscl);
"""

_TAIL = OCTAVE_SOLVER + """
t0 = tic; c0 = cputime;
X_HB = solve_and_continue(x0, fun, log10a_s, log10a_e, ds, Sopt, {{}}, Solopt);
wall = toc(t0); cpu = cputime - c0;
printf('NLVIB_RESULT %d %.6f %.6f\\n', size(X_HB,2), wall, cpu);
M = full(sys_.M); K = full(sys_.K); springs = [idof 0 knl];
om_HB = X_HB(end-2,:); a_HB = 10.^X_HB(end,:);
Q_HB = X_HB(1:end-3,:).*repmat(a_HB,size(X_HB,1)-3,1);
energy = zeros(size(a_HB));
for i=1:size(X_HB,2)
  Qi = reshape(Q_HB(:,i),n,2*H+1); q0 = Qi(:,1) + sum(Qi(:,2:2:end),2); u0 = sum(Qi(:,3:2:end),2)*om_HB(i);
  energy(i) = 1/2*u0'*M*u0 + 1/2*q0'*K*q0 + knl*q0(idof)^4/4;
end
save('-v7', '{mat}', 'M', 'K', 'springs', 'energy', 'om_HB', 'Q_HB', 'wall', 'cpu', 'H');
"""

#: case: (title, Octave body, H, log10 of the last modal amplitude)
CASES = {
    "04": ("NLvib example 04: 2-DOF oscillator, cubic spring, NNM 1", CASE_04, 7, 0.9),
    "09": ("NLvib example 09: clamped beam (38 DOF), cubic spring at the tip, NNM 1", CASE_09, 5, -3.0),
}


def load():
    return os.getloadavg()[0]


def nlvib_dir(arg):
    d = arg or os.environ.get("NLVIB_DIR")
    if d and (Path(d) / "SRC" / "HB_residual.m").is_file() and (Path(d) / "SRC" / "solve_and_continue.m").is_file():
        return str(Path(d).resolve())
    return None


def run_nlvib(case, octave, nlvib, workdir, repeats):
    """NLvib in Octave: (median CPU s, median wall s, points, load, the .mat file with the model and the points)."""
    title, body, H, a_end = CASES[case]
    mat = str(Path(workdir) / f"nlvib_{case}.mat")
    script = Path(workdir) / f"nlvib_{case}.m"
    script.write_text(f"nlvib = '{nlvib}'; H = {H};\n" + _HEAD + body.format(a_end=a_end) + _TAIL.format(mat=mat))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    cpu, wall, loads, points = [], [], [], None
    for _ in range(repeats):
        loads.append(load())
        out = subprocess.run([octave, "--no-gui", "--quiet", "--no-window-system", str(script)], cwd=workdir, env=env,
                             capture_output=True, text=True, timeout=1800)
        m = re.search(r"NLVIB_RESULT (\d+) ([\d.]+) ([\d.]+)", out.stdout)
        if m is None:
            raise RuntimeError(f"NLvib example {case} failed in Octave:\n{out.stdout[-2000:]}\n{out.stderr[-2000:]}")
        points = int(m.group(1))
        wall.append(float(m.group(2)))
        cpu.append(float(m.group(3)))
    return dict(cpu=float(np.median(cpu)), wall=float(np.median(wall)), points=points, load=float(np.median(loads)),
                cpu_runs=cpu, mat=mat)


#: the HB runs' period cap per step: 2 %, about NLvib's own steps (its steps change the period by up to 1.4 % on
#: example 04 and 7.8 % on 09); nnm's default for HB stays 0.5 % (MAX_PERIOD_STEP in driver/api.py), whose denser
#: points keep straight lines between them within 1e-4 of the curve (tests/test_elements.py, test_forced.py)
HB_PERIOD_STEP = 0.02


def nnm_path(model, H, E, f, **kw):
    """nnm's branch along NLvib's path: from NLvib's first energy until NLvib's last frequency is reached.  NLvib
    follows example 09's 5:1 tongue; nnm's default jumps tongues above 3:1 (backbone/settings.py, Follow.max_order),
    so the path is asked for with every tongue followed (tongues="follow-all"): without it nnm stays on the backbone
    where NLvib is in the tongue (0.51 relative frequency difference at NLvib's energies, 2026-12-07)."""
    import nnm_solver as nnm
    kw.setdefault("tongues", "follow-all")
    kw.setdefault("freq_tol", None)        # NLvib's H (and Newmark's 200 steps) kept: no raised truncation or steps
    it = nnm.iter_nnm(model, 1, 1.5 * float(np.max(E)), energy_min=float(E[0]), **kw)
    for p in it:
        if p.frequency_hz >= f[-1] * (1 - 1e-9):
            break
    return it.branch()


def time_nnm(make_model, H, E, f, repeats, cached=False, **kw):
    """(branch, timings) of nnm's path, medians of ``repeats``.  Each timed run gets a new model from make_model()
    (outside the timing): the backbone's skeleton (driver/skeleton.py, labels the points; computed once per model
    and mode, then cached) is part of a first run's cost, as it is for a user's first branch of a model.
    cached=True times runs on one model after a first one (the skeleton cached: a model's second branch)."""
    from threadpoolctl import threadpool_limits
    cpu, wall, loads = [], [], []
    with threadpool_limits(1):
        model = make_model()
        nnm_path(model, H, E, f, **kw)                      # warm-up: numba kernels, caches
        for _ in range(repeats):
            if not cached:
                model = make_model()
            loads.append(load())
            t, c = time.perf_counter(), time.process_time()
            b = nnm_path(model, H, E, f, **kw)
            cpu.append(time.process_time() - c)
            wall.append(time.perf_counter() - t)
    return b, dict(cpu=float(np.median(cpu)), wall=float(np.median(wall)), points=len(b.energy),
                   load=float(np.median(loads)), cpu_runs=cpu)


def below_first_fold(E):
    d = np.diff(E)
    return int(np.argmax(d < 0)) + 1 if np.any(d < 0) else len(E)


def hb_agreement(model, branch, H, E, f):
    """max |f_nnm(E_i) / f_i - 1| over NLvib's points below its first energy maximum, f_nnm(E_i): nnm's HB equations
    solved at the energy E_i (Newton on the HB residual and the energy), started from nnm's branch."""
    from nnm_solver.model.modal import modal_system
    from nnm_solver.orbits.harmonic_balance import HBProblem
    s = branch.settings
    system = modal_system(model)
    prob = HBProblem(system, 0, s.hb_basis())
    nb_ = below_first_fold(np.asarray(branch.energy))
    Eb = np.asarray(branch.energy)[:nb_]
    U = [prob.pack(np.array([system.to_modal(x) for x in np.asarray(branch.coefficients_at(i))]),
                   2 * np.pi * branch.frequency_hz[i]) for i in range(nb_)]
    worst = 0.0
    for Ei, fi in zip(E[:below_first_fold(E)], f[:below_first_fold(E)]):
        j = int(np.clip(np.searchsorted(Eb, Ei), 1, nb_ - 1))
        t = (np.log(Ei) - np.log(Eb[j - 1])) / (np.log(Eb[j]) - np.log(Eb[j - 1]))
        u = (1 - t) * U[j - 1] + t * U[j]
        for _ in range(30):
            r, J = prob.jacobian(u)
            g = prob.energy_gradient(u)
            du = np.linalg.lstsq(np.vstack([J, g / Ei]), -np.concatenate([r, [(prob.energy(u) - Ei) / Ei]]),
                                 rcond=None)[0]
            u = u + du
            if np.linalg.norm(du) <= 1e-13 * np.linalg.norm(u):
                break
        worst = max(worst, abs(u[-1] * prob.w_r / (2 * np.pi) / fi - 1))
    return worst


def interpolated_agreement(branch, E, f):
    from scipy.interpolate import PchipInterpolator
    Eb, fb = np.asarray(branch.energy), np.asarray(branch.frequency_hz)
    k = below_first_fold(Eb)
    i = below_first_fold(E)
    inside = (E[:i] >= Eb[0]) & (E[:i] <= Eb[k - 1])
    fi = PchipInterpolator(np.log(Eb[:k]), fb[:k])(np.log(E[:i][inside]))
    return float(np.max(np.abs(fi / f[:i][inside] - 1)))


def events(b):
    return ", ".join(f"{e['kind']} {e['energy']:.6g} J" for e in b.events) or "none"


def dense_check(model, H, E, f, b_hb, cap):
    """The same HB path with the dense Hill route (hill.py's reference): its events, and how the default route's
    branch compares (points, stability flags point by point, events' kinds and energies)."""
    from nnm_solver.orbits.harmonic_balance import HBProblem
    from threadpoolctl import threadpool_limits
    saved = HBProblem.hill_method
    HBProblem.hill_method = "dense"
    try:
        with threadpool_limits(1):
            t = time.process_time()
            b_d = nnm_path(model, H, E, f, method="hb", harmonics=H, floquet=True, max_period_step=cap)
            cpu = time.process_time() - t
    finally:
        HBProblem.hill_method = saved
    same_points = len(b_d.energy) == len(b_hb.energy)
    flags = int(np.sum(np.asarray(b_d.stable) != np.asarray(b_hb.stable))) if same_points else None
    kinds = [e["kind"] for e in b_d.events] == [e["kind"] for e in b_hb.events]
    worst = (max((abs(a["energy"] / b["energy"] - 1) for a, b in zip(b_hb.events, b_d.events)), default=0.0)
             if kinds else None)
    print(f"dense Hill route: {len(b_d.energy)} points in {cpu:.2f} s CPU, events {events(b_d)}; default route: "
          f"{'the same points' if same_points else 'other points'}, stability flags differing at "
          f"{flags if same_points else '-'} points, events {'of the same kinds' if kinds else 'of other kinds'}"
          + (f", largest relative energy difference {worst:.1e}" if kinds else ""))
    return dict(points=len(b_d.energy), cpu=cpu, events=[(e["kind"], e["energy"]) for e in b_d.events],
                same_points=same_points, flags_differing=flags, same_kinds=kinds, worst_event_rdiff=worst)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", nargs="+", default=["04", "09"], choices=sorted(CASES))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--octave", default=os.environ.get("OCTAVE", "octave"))
    ap.add_argument("--nlvib", default=None, help="NLvib checkout (default: $NLVIB_DIR)")
    ap.add_argument("--json", default=None, help="also write the results to this file")
    ap.add_argument("--hb-period-steps", nargs="+", type=float, default=[HB_PERIOD_STEP],
                    help="period caps of the HB runs with multipliers (the first one also for the run without and "
                         "the agreement; each further one adds a row)")
    ap.add_argument("--dense-check", action="store_true",
                    help="also follow the HB path once with the dense Hill route (every eigenpair of the Hill matrix, "
                         "the reference) and compare its flags and events with the default route's (~1-2 min on 09)")
    args = ap.parse_args(argv)
    octave = shutil.which(args.octave)
    nlvib = nlvib_dir(args.nlvib)
    if octave is None or nlvib is None:
        why = "GNU Octave not found" if octave is None else "no NLvib checkout (set NLVIB_DIR or --nlvib)"
        print(f"bench_peers: skipped: {why}")
        return 0
    import scipy.io
    import nnm_solver as nnm
    results = {}
    with tempfile.TemporaryDirectory(prefix="bench_peers_") as work:
        for case in args.cases:
            title, _, H, _ = CASES[case]
            print(f"\n## {title} (H = {H})", flush=True)
            nl = run_nlvib(case, octave, nlvib, work, args.repeats)
            d = scipy.io.loadmat(nl["mat"])
            E, f = d["energy"].ravel(), d["om_HB"].ravel() / (2 * np.pi)
            def make_model(mat=nl["mat"], name=f"nlvib_{case}"):
                return nnm.load_mat_model(mat, name=name)
            model = make_model()
            rows = {"NLvib HB (Octave)": nl}
            cap, more = args.hb_period_steps[0], args.hb_period_steps[1:]
            hb = dict(method="hb", harmonics=H, max_period_step=cap)
            b_hb, rows["nnm HB, multipliers at every point"] = time_nnm(make_model, H, E, f, args.repeats,
                                                                         floquet=True, **hb)
            _, rows["nnm HB, multipliers at every point, the model's second branch (skeleton cached)"] = time_nnm(
                make_model, H, E, f, args.repeats, cached=True, floquet=True, **hb)
            _, rows["nnm HB, no multipliers"] = time_nnm(make_model, H, E, f, args.repeats, floquet=False, **hb)
            extra_events = {}
            for c in more:
                name = f"nnm HB, multipliers at every point, period cap {100 * c:g} %"
                b_c, rows[name] = time_nnm(make_model, H, E, f, args.repeats, method="hb", harmonics=H, floquet=True,
                                           max_period_step=c)
                extra_events[name] = events(b_c)
            b_sh, rows["nnm shooting (Newmark 200)"] = time_nnm(make_model, H, E, f, args.repeats, method="shooting")
            agree_hb = hb_agreement(model, b_hb, H, E, f)
            agree_sh = interpolated_agreement(b_sh, E, f)
            print(f"energy {E[0]:.4g} .. {E.max():.4g} J, NLvib's last point {E[-1]:.4g} J at {f[-1]:.5g} Hz; "
                  f"{len(E[:below_first_fold(E)])} NLvib points below its first energy maximum")
            print("| run | points | CPU s | wall s | NLvib CPU / this CPU | load |")
            print("|---|---|---|---|---|---|")
            for name, r in rows.items():
                ratio = nl["cpu"] / r["cpu"]
                print(f"| {name} | {r['points']} | {r['cpu']:.3f} | {r['wall']:.3f} | {ratio:.1f} | {r['load']:.1f} |")
            print(f"agreement with NLvib below the first energy maximum (max relative frequency difference): "
                  f"HB {agree_hb:.1e} (nnm's HB at NLvib's energies), shooting {agree_sh:.1e} (interpolated, "
                  f"Newmark's error included)")
            print(f"nnm HB events: {events(b_hb)}; shooting events: {events(b_sh)}")
            for name, ev in extra_events.items():
                print(f"{name}: events {ev}")
            results[case] = dict(rows=rows, agreement_hb=agree_hb, agreement_shooting=agree_sh,
                                 events_hb=[(e["kind"], e["energy"]) for e in b_hb.events],
                                 events_shooting=[(e["kind"], e["energy"]) for e in b_sh.events])
            if args.dense_check:
                results[case]["dense_check"] = dense_check(model, H, E, f, b_hb, args.hb_period_steps[0])
    if args.json:
        for case in results.values():
            for r in case["rows"].values():
                r.pop("mat", None)
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
