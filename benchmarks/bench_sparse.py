"""Sparse factorisations of the full aircraft's stiffness K (64,446 DOFs): SuperLU against CHOLMOD (cholespy,
scikit-sparse), PARDISO and QDLDL.

    python benchmarks/bench_sparse.py                 # every solver installed, one BLAS thread, medians of 3
    python benchmarks/bench_sparse.py --threads 2     # the threaded libraries on both cores
    python benchmarks/bench_sparse.py --quick         # one repetition

The matrix: ``paris_aircraft.build_paris(ParisParams())``'s K (the unreduced FE model of examples/build_paris_full.py,
symmetric positive definite: the airframe stands on its gear springs).  Solvers, each in a process of its own (so
that its memory and its thread count are its own):

- ``superlu``: ``SparseSolver(K, backend="superlu")``, scipy's splu with its default COLAMD column ordering (what
  SparseSolver did for the Ritz basis, model/ritz.py, before CHOLMOD);
- ``superlu-nd``: the same with ``xyz=nodes``, the nodes' geometric nested dissection and symmetric-mode LU (what
  nnm_fem.modes and Craig-Bampton used);
- ``cholespy``: CHOLMOD's simplicial Cholesky with nested dissection in cholespy's self-contained wheel (a main
  dependency: what ``SparseSolver`` uses without scikit-sparse);
- ``cholmod``: scikit-sparse's CHOLMOD supernodal Cholesky with its default ordering (AMD, METIS tried), the
  library ``SparseSolver`` uses first when it is installed (``pip install nnm[sparse]``);
- ``pardiso``: MKL PARDISO through pypardiso, real symmetric positive definite (mtype 2, upper triangle);
- ``qdldl``: the qdldl wheel's L D L^T (AMD ordering; one right-hand side at a time).

Printed per solver: the time of the factorisation (ordering included), of one solve with a single right-hand side
(what ARPACK's Lanczos does at every step) and with 8 (medians), the factor's nonzeros, the memory the process holds
after the factorisations above what it held before (the last factor) and its peak above that (ru_maxrss; "nan" when
the factorisation stayed below the peak that loading the matrix had already reached), and the accuracy: the
largest relative residual ||K x - b|| / ||b|| over the 8 columns, the componentwise backward error
max |K x - b| / (|K| |x| + |b|), and the largest difference to the SuperLU-ND solution relative to its norm.  The
load average is printed at the start, after each solver and at the end.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SOLVERS = ("superlu", "superlu-nd", "cholespy", "cholmod", "pardiso", "qdldl")


def rss_mb():
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def peak_mb():
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def factorise(name, K, xyz):
    """(solve function, factor nonzeros) of one solver."""
    import numpy as np
    import scipy.sparse as sp

    from nnm_solver.model.sparse import SparseSolver
    if name in ("superlu", "superlu-nd"):
        s = SparseSolver(K, xyz=xyz if name == "superlu-nd" else None, backend="superlu")
        return s.solve, int(s.lu.L.nnz + s.lu.U.nnz)
    if name == "cholespy":
        s = SparseSolver(K, backend="cholespy")
        return s.solve, None
    if name == "cholmod":
        from sksparse.cholmod import cholesky
        f = cholesky(sp.csc_matrix(K))
        return f.solve_A, None                    # nonzeros: f.L() below, once (it copies the factor)
    if name == "qdldl":
        import qdldl
        f = qdldl.Solver(sp.triu(K, format="csc"))

        def solve(b):
            b = np.asarray(b, dtype=np.float64)
            return f.solve(b) if b.ndim == 1 else np.column_stack([f.solve(c) for c in b.T])
        return solve, None
    if name == "pardiso":
        import pypardiso
        A = sp.triu(K, format="csr").astype(np.float64)
        A.sort_indices()
        ps = pypardiso.PyPardisoSolver(mtype=2)
        ps.factorize(A)

        def solve(b):
            return ps.solve(A, np.asarray(b, dtype=np.float64))
        solve.free = lambda: ps.free_memory(everything=True)
        return solve, int(ps.get_iparm(18))
    raise ValueError(name)


def worker(name, npz, reps):
    import numpy as np
    import scipy.sparse as sp

    data = np.load(npz)
    K = sp.csc_matrix((data["data"], data["indices"], data["indptr"]), shape=tuple(data["shape"]))
    xyz = data["xyz"]
    rng = np.random.default_rng(0)
    b = rng.standard_normal((K.shape[0], 8))
    base, peak_before = rss_mb(), peak_mb()
    t_fact, solve, nnz = [], None, None
    for _ in range(reps):
        if solve is not None and hasattr(solve, "free"):
            solve.free()                           # PARDISO keeps its memory until told (no destructor)
        solve = None
        t = time.perf_counter()
        solve, nnz = factorise(name, K, xyz)
        t_fact.append(time.perf_counter() - t)
    peak, held = peak_mb(), rss_mb() - base
    t_solve, x = [], None
    for _ in range(reps):
        t = time.perf_counter()
        x = solve(b)
        t_solve.append(time.perf_counter() - t)
    if name == "cholmod":
        from sksparse.cholmod import cholesky
        nnz = int(cholesky(K).L().nnz)
    r = K @ x - b
    res = np.linalg.norm(r, axis=0) / np.linalg.norm(b, axis=0)
    berr = np.max(np.abs(r) / (abs(K) @ np.abs(x) + np.abs(b)))     # componentwise backward error (Oettli-Prager)
    t_one = []
    for _ in range(reps):
        t = time.perf_counter()
        solve(b[:, 0])
        t_one.append(time.perf_counter() - t)
    out = dict(name=name, factor_s=statistics.median(t_fact), factor_all=t_fact, solve8_s=statistics.median(t_solve),
               nnz_factor=nnz, peak_mb=peak - base if peak > peak_before else float("nan"), held_mb=held,
               residual=float(res.max()), backward=float(berr), solve1_s=statistics.median(t_one))
    np.save(npz.replace(".npz", f".{name}.npy"), x)
    print(json.dumps(out))


def aircraft_K():
    sys.path.insert(0, str(ROOT / "examples"))
    from paris_aircraft import ParisParams, build_paris
    ac = build_paris(ParisParams())
    return ac.K, ac.fe.nodes


def available(name):
    import importlib.util
    mod = {"cholespy": "cholespy", "cholmod": "sksparse", "pardiso": "pypardiso", "qdldl": "qdldl"}.get(name)
    return mod is None or importlib.util.find_spec(mod) is not None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one repetition")
    ap.add_argument("--threads", type=int, default=1, help="BLAS / MKL / OpenMP threads of each solver (default 1)")
    ap.add_argument("--solvers", default=",".join(SOLVERS), help=f"comma-separated, of {', '.join(SOLVERS)}")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--npz", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    reps = 1 if args.quick else 3
    if args.worker:
        worker(args.worker, args.npz, reps)
        return 0
    import numpy as np
    import scipy.sparse as sp

    print(f"load average at the start {os.getloadavg()}", flush=True)
    t = time.perf_counter()
    K, xyz = aircraft_K()
    K = sp.csc_matrix(K)
    print(f"aircraft K: n = {K.shape[0]}, nnz = {K.nnz} (built in {time.perf_counter() - t:.1f} s); "
          f"{args.threads} thread(s) per solver, {'one run' if reps == 1 else f'medians of {reps}'}", flush=True)
    env = dict(os.environ, **{v: str(args.threads) for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                             "MKL_NUM_THREADS")})
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        npz = os.path.join(tmp, "K.npz")
        np.savez(npz, data=K.data, indices=K.indices, indptr=K.indptr, shape=np.array(K.shape), xyz=xyz)
        for name in args.solvers.split(","):
            if not available(name):
                print(f"{name}: not installed, skipped", flush=True)
                continue
            cmd = [sys.executable, __file__, "--worker", name, "--npz", npz] + (["--quick"] if args.quick else [])
            p = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=ROOT)
            if p.returncode:
                print(f"{name}: failed\n{p.stderr[-2000:]}", flush=True)
                continue
            row = json.loads(p.stdout.strip().splitlines()[-1])
            rows.append(row)
            print(f"{name}: factorisation {row['factor_s']:.2f} s, solve x8 {row['solve8_s']:.3f} s "
                  f"(load {os.getloadavg()[0]:.2f})", flush=True)
        ref = os.path.join(tmp, "K.superlu-nd.npy")
        xref = np.load(ref) if os.path.exists(ref) else None
        for row in rows:
            x = np.load(os.path.join(tmp, f"K.{row['name']}.npy"))
            row["diff"] = float(np.max(np.linalg.norm(x - xref, axis=0) / np.linalg.norm(xref, axis=0))) \
                if xref is not None else float("nan")
    print(f"\n| solver | factorisation (s) | solve, 1 rhs (s) | solve, 8 rhs (s) | factor nonzeros | memory held (MB) "
          f"| peak (MB) | residual | backward error | vs SuperLU-ND |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        nnz = f"{r['nnz_factor'] / 1e6:.1f} M" if r["nnz_factor"] else "-"
        r["peak_mb"] = float("nan") if r["peak_mb"] is None else r["peak_mb"]
        print(f"| {r['name']} | {r['factor_s']:.2f} | {r['solve1_s']:.3f} | {r['solve8_s']:.3f} | {nnz} | "
              f"{r['held_mb']:.0f} | {r['peak_mb']:.0f} | {r['residual']:.1e} | {r['backward']:.1e} | {r['diff']:.1e} |")
    print(f"\nload average at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
