"""The full 64,446-DOF aircraft's mode-20 backbone by condensed harmonic balance, against the 548-DOF Craig-Bampton model.

    python benchmarks/bench_full_aircraft.py                       # builds the full model, computes its Ritz basis
    python benchmarks/bench_full_aircraft.py --file paris_full.h5  # the file of examples/build_paris_full.py; with
                                                                   # its --store-basis: the stored-basis timing too
    python benchmarks/bench_full_aircraft.py --quick                # one repetition of the branches

Prints, with the machine's load (os.getloadavg), the process's CPU time and its peak memory at each stage: the time of the sparse factorisation (and its back
end), of the Ritz basis (the modes below 2 H f_20 by block Lanczos + the springs' residual fields, model/ritz.py) and
of the branch ``continue_nnm(model, 20, 30, method="hb", harmonics=9, condensed=True, floquet=False)`` on the full
model; the same branch from a basis stored in the file (``--file`` with /ritz_basis: a fresh read of the file, the
basis read from it, the branch; medians of 3); the Craig-Bampton model's (assets/paris.h5) branch the same way
(median of 3); that the two models' mode 20 is the same mode (frequency, MAC of the shapes at the 48 retained DOFs);
and the backbones side by side at common energies: frequency, drop from the linear frequency, and the difference.
"""
from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import nnm_solver as nnm  # noqa: E402
from nnm_solver.model import ritz  # noqa: E402
from nnm_solver.model.sparse import SparseSolver  # noqa: E402

ENERGIES = (0.1, 1.0, 3.0, 10.0, 30.0)
HB = dict(method="hb", harmonics=9, condensed=True, floquet=False)


def load():
    """The load average, the process's CPU time so far and its peak resident memory (ru_maxrss)."""
    import resource
    return (f"load {os.getloadavg()[0]:.2f}, CPU {time.process_time():.0f} s, peak "
            f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6:.2f} GB")


def timed(fn, reps):
    out, times = None, []
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return out, statistics.median(times), times


def backbone_at(branch, energies):
    """Frequency (Hz) at each energy on the branch: the first point at or beyond it, interpolated linearly in energy
    with the point before (the branch is followed from low energy up)."""
    E, f = np.asarray(branch.energy), np.asarray(branch.frequency_hz)
    out = []
    for e in energies:
        i = int(np.argmax(E >= e)) if np.any(E >= e) else -1
        if i <= 0:
            out.append(np.nan if i < 0 else f[0])
            continue
        w = (e - E[i - 1]) / (E[i] - E[i - 1])
        out.append(f[i - 1] + w * (f[i] - f[i - 1]))
    return np.array(out)


def label_at(branch, e):
    E = np.asarray(branch.energy)
    i = int(np.argmax(E >= e)) if np.any(E >= e) else len(E) - 1
    return str(branch.labels[i])


def full_model_built():
    from build_paris_full import full_model
    from paris_aircraft import ParisParams, build_paris
    t = time.perf_counter()
    ac = build_paris(ParisParams())
    model = full_model(ac)
    return model, ac.retained_dofs, time.perf_counter() - t


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--file", default=None, help="the full model's nnm file (examples/build_paris_full.py)")
    ap.add_argument("--quick", action="store_true", help="one repetition of the branches")
    ap.add_argument("--mode", type=int, default=20)
    ap.add_argument("--energy-max", type=float, default=30.0)
    args = ap.parse_args(argv)
    reps = 1 if args.quick else 3
    print(f"load average at the start {os.getloadavg()}", flush=True)
    t_all = time.perf_counter()
    if args.file:
        t = time.perf_counter()
        ritz._stored.clear()
        model = nnm.load_model(args.file)
        stored = bool(ritz._stored)
        ritz._stored.clear()                        # the first run below computes the basis
        retained = np.asarray(nnm.load_extra(ROOT / "assets" / "paris.h5", "craig_bampton")["retained_dofs"])
        print(f"full model read from {args.file}: {model.n} DOFs ({time.perf_counter() - t:.1f} s; stored basis: "
              f"{stored}; {load()})", flush=True)
    else:
        model, retained, t_build = full_model_built()
        stored = False
        print(f"full model built: {model.n} DOFs, K nnz {model.K.nnz} ({t_build:.1f} s; {load()})", flush=True)
    t = time.perf_counter()
    solver = SparseSolver(model.K_linear)
    print(f"sparse factorisation of K: {solver.backend}, {time.perf_counter() - t:.1f} s ({load()})", flush=True)
    del solver
    t = time.perf_counter()
    system = ritz.ritz_system(model, args.mode, HB["harmonics"])
    t_basis = time.perf_counter() - t
    print(f"Ritz basis: {system.exact_modes} modes below {system.cutoff_hz:.1f} Hz + "
          f"{len(system.omega2) - system.exact_modes} residual vectors, {t_basis:.1f} s ({load()})", flush=True)
    t = time.perf_counter()
    full = nnm.continue_nnm(model, args.mode, args.energy_max, **HB)
    t_branch = time.perf_counter() - t
    print(f"full-model branch: {len(full)} points, status {full.status}, {t_branch:.1f} s ({load()}); "
          f"basis + branch {t_basis + t_branch:.1f} s", flush=True)

    if args.file and stored:
        def from_file():
            ritz._stored.clear()
            ritz._cache.clear()
            m = nnm.load_model(args.file)
            return nnm.continue_nnm(m, args.mode, args.energy_max, **HB)
        again, t_stored, all_stored = timed(from_file, reps)
        same = float(np.max(np.abs(again.frequency_hz - full.frequency_hz))) if len(again) == len(full) else np.nan
        print(f"from the stored basis (read the file, read the basis, the branch): {t_stored:.1f} s median of "
              f"{[round(x, 1) for x in all_stored]} ({load()}); max frequency difference to the computed basis "
              f"{same:.1e} Hz", flush=True)

    reduced = nnm.load_model(ROOT / "assets" / "paris.h5")
    nnm.continue_nnm(reduced, args.mode, 0.1, **HB)          # compiled kernels warm
    cb, t_cb, all_cb = timed(lambda: (ritz._cache.clear(), nnm.continue_nnm(reduced, args.mode, args.energy_max,
                                                                              **HB))[1], reps)
    print(f"Craig-Bampton (548 DOF) branch: {len(cb)} points, {t_cb:.2f} s median of "
          f"{[round(x, 2) for x in all_cb]} ({load()})", flush=True)

    # the same mode? frequency and the MAC of the shapes at the retained DOFs (the reduced model's first 48)
    f_red, Phi_red = reduced.linear_modes()
    k = args.mode - 1
    f_full = np.sqrt(system.omega2[:system.exact_modes]) / (2 * np.pi)
    macs = nnm.mac(system.Phi[retained, :30], Phi_red[:len(retained), :30])
    pair = int(np.argmax(macs[k]))
    print(f"\nmode {args.mode}: full {f_full[k]:.5f} Hz, reduced {f_red[k]:.5f} Hz "
          f"({100 * (f_red[k] / f_full[k] - 1):+.4f} %), MAC at the {len(retained)} retained DOFs {macs[k, k]:.6f}; "
          f"best match of full mode {args.mode} in the reduced model: mode {pair + 1}; modes 1-30 paired in order: "
          f"{bool(np.all(np.argmax(macs, axis=1) == np.arange(30)))}")

    print("\n| E (J) | full (Hz) | Craig-Bampton (Hz) | CB - full | drop, full | drop, CB | labels (full / CB) |")
    print("|---|---|---|---|---|---|---|")
    f0_full, f0_cb = f_full[k], f_red[k]
    print(f"| 0 (linear) | {f0_full:.5f} | {f0_cb:.5f} | {100 * (f0_cb / f0_full - 1):+.4f} % | | | |")
    for e, ff, fc in zip(ENERGIES, backbone_at(full, ENERGIES), backbone_at(cb, ENERGIES)):
        print(f"| {e:g} | {ff:.5f} | {fc:.5f} | {100 * (fc / ff - 1):+.4f} % | {100 * (ff / f0_full - 1):+.3f} % | "
              f"{100 * (fc / f0_cb - 1):+.3f} % | {label_at(full, e)} / {label_at(cb, e)} |")
    print(f"\ntotal {time.perf_counter() - t_all:.1f} s; load average at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
