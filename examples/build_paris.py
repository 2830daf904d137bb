"""Build the Paris-like aircraft FE model, reduce it by Craig-Bampton and write assets/paris.h5.

    python examples/build_paris.py            # full model (> 50,000 DOF) -> assets/paris.h5
    python examples/build_paris.py --coarse   # small fast build -> paris_coarse.h5

Steps: parametric FE model (examples/paris_aircraft) -> full-model modes in 0-100 Hz with
labels from the model (strain energy by part, section motion, mirror symmetry) ->
Craig-Bampton with the 8 attachment nodes x 6 DOF retained first and the first 500
fixed-interface modes (548 DOF) -> validation (MAC, frequency error) -> 4 softening cubic
springs k3 = -1e13 N/m^3 on the relative vertical displacement across each tip-tank
attachment -> nnm HDF5 file with a display mesh.  Deterministic.
Axes: x aft from the nose, y towards the right wing, z up (ground at z = 0).
"""
from __future__ import annotations

import os

# One BLAS thread: the dense work here (Lanczos re-orthogonalisation, R^T M R) is memory-bound, and a
# multi-threaded BLAS competing with other processes on a 2-core machine is several times slower.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg as sla  # noqa: E402

import nnm_solver  # noqa: E402
from nnm_fem import DOF_NAMES, modes  # noqa: E402
from nnm_solver.analysis import mass_mac  # noqa: E402
from nnm_solver.reduction import craig_bampton  # noqa: E402
from paris_aircraft import ATTACHMENT_NAMES, BUILDER_VERSION, ParisParams, build_paris  # noqa: E402
from paris_aircraft.fingerprint import build_fingerprint  # noqa: E402
from paris_aircraft.labels import label_modes  # noqa: E402
from paris_aircraft.tuning import PAPER_MODE_NAMES, TABLE2_HZ  # noqa: E402

K3 = -1e13  # N/m^3, softening, per attachment (seed paper, section 4.1.3)
#: relative accuracy of the Lanczos eigenvalues (ARPACK tol; 0 = machine precision costs more restarts)
EIG_TOL = 1e-10


def display_mesh(ac, R, stride):
    """Triangle display mesh on a subset of the skin nodes; displacement map from R rows."""
    node_vertex = {}
    verts, faces, pids = [], [], []
    names = []
    for part, ids, periodic in ac.grids:
        if part not in names:
            names.append(part)
        S, Rn = ids.shape
        si = np.unique(np.r_[np.arange(0, S, stride), S - 1])
        if periodic:
            rs = max(1, stride)
            ri = np.arange(0, Rn, rs)
        else:
            ri = np.unique(np.r_[np.arange(0, Rn, stride), Rn - 1])
        sub = ids[np.ix_(si, ri)]
        if periodic:
            sub = np.concatenate([sub, sub[:, :1]], axis=1)
        vid = np.empty(sub.shape, np.int64)
        for idx, node in np.ndenumerate(sub):
            if node not in node_vertex:
                node_vertex[node] = len(verts)
                verts.append(node)
            vid[idx] = node_vertex[node]
        a, b, c, d = vid[:-1, :-1], vid[1:, :-1], vid[1:, 1:], vid[:-1, 1:]
        tri = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
        tri = tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])]
        faces.append(tri)
        pids.append(np.full(len(tri), names.index(part)))
    verts = np.asarray(verts)
    rows = (6 * verts[:, None] + np.arange(3)).ravel()
    return nnm_solver.DisplayMesh(vertices=ac.fe.nodes[verts], faces=np.concatenate(faces),
                                  displacement_map=R[rows].astype(np.float32),
                                  part_ids=np.concatenate(pids), part_names=names)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--coarse", action="store_true", help="coarse mesh and fewer CB modes (fast)")
    ap.add_argument("--out", default=None, help="output file (default assets/paris.h5, coarse: paris_coarse.h5)")
    ap.add_argument("--cb-modes", type=int, default=None, help="fixed-interface modes kept (default 500)")
    ap.add_argument("--fmax", type=float, default=100.0, help="validation band upper limit (Hz)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    load_start = os.getloadavg()
    mesh = 0.5 if args.coarse else 1.0
    n_cb = args.cb_modes or (200 if args.coarse else 500)
    out = Path(args.out or ("paris_coarse.h5" if args.coarse else Path(__file__).resolve().parents[1]
                            / "assets" / "paris.h5"))
    params = ParisParams(mesh=mesh)

    # ---------------------------------------------------------------- full model
    ac = build_paris(params)
    n_full = ac.fe.n_dof
    mass = ac.fe.total_mass(ac.M)
    print(f"full FE model: {ac.fe.n_nodes} nodes, {n_full} DOF, mass {mass:.1f} kg, "
          f"built in {ac.build_seconds:.1f} s", flush=True)
    t_assembly = time.perf_counter() - t_start
    t = time.perf_counter()
    n_eig = 60
    while True:
        f_full, V_full = modes(ac.K, ac.M, n_eig, sigma=-1.0, xyz=ac.fe.nodes, tol=EIG_TOL)
        if f_full[-1] > args.fmax or n_eig > 400:
            break
        n_eig = int(n_eig * 1.5)
    keep = f_full <= args.fmax
    f_full, V_full = f_full[keep], V_full[:, keep]
    labels_full, _ = label_modes(ac, V_full)
    t_full = time.perf_counter() - t
    print(f"full model: {len(f_full)} modes in 0-{args.fmax:g} Hz ({t_full:.1f} s)", flush=True)

    # ---------------------------------------------------------------- Craig-Bampton
    t = time.perf_counter()
    b = ac.retained_dofs
    Mr, Kr, R, fixed_hz = craig_bampton(ac.M, ac.K, b, n_cb, tol=EIG_TOL, xyz=ac.fe.nodes)
    t_cb = time.perf_counter() - t
    lam, Q = sla.eigh(Kr, Mr)
    f_red = np.sqrt(np.maximum(lam, 0)) / (2 * np.pi)
    print(f"Craig-Bampton: {len(b)} boundary DOF + {n_cb} fixed-interface modes "
          f"(up to {fixed_hz[-1]:.0f} Hz) = {Mr.shape[0]} DOF ({t_cb:.1f} s)", flush=True)
    nv = len(f_full)
    Phi_red = R @ Q[:, :nv + 10]                     # recovered physical displacements of the reduced modes
    Mac = mass_mac(ac.M, V_full, Phi_red)            # mass-weighted, on all DOFs of the full model
    pair = np.argmax(Mac, axis=1)
    mac_diag = Mac[np.arange(nv), pair]
    ferr = f_red[pair] / f_full - 1.0
    print(f"CB validation 0-{args.fmax:g} Hz: {nv} modes, min MAC {mac_diag.min():.6f}, "
          f"max |freq error| {100 * np.max(np.abs(ferr)):.4f} %, pairs in order: {np.all(pair == np.arange(nv))}")
    print(" mode   full Hz   reduced Hz   error %      MAC   label")
    for k in range(nv):
        print(f" {k + 1:4d} {f_full[k]:9.4f} {f_red[pair[k]]:11.4f} {100 * ferr[k]:9.4f} {mac_diag[k]:9.6f}   "
              f"{labels_full[k]}")

    # ---------------------------------------------------------------- labels, springs, mesh
    mode_labels = []
    for j in range(Mr.shape[0]):
        hit = np.flatnonzero(pair == j)
        mode_labels.append(labels_full[hit[0]] if len(hit) else f"mode {j + 1} ({f_red[j]:.1f} Hz, above validation band)")
    springs = [nnm_solver.CubicSpring(dof=6 * (2 * a) + 2, other=6 * (2 * a + 1) + 2, k3=K3) for a in range(4)]
    dof_labels = [f"{ATTACHMENT_NAMES[i]} {DOF_NAMES[c]}" for i in range(8) for c in range(6)]
    dof_labels += [f"CB mode {j + 1} ({fixed_hz[j]:.1f} Hz)" for j in range(n_cb)]
    mesh = display_mesh(ac, R, 1 if args.coarse else 2)

    print("\nfirst 24 modes of the reduced model vs the seed paper (Table 2)")
    print(" mode   model Hz   paper Hz   diff %   label")
    for k in range(24):
        print(f" {k + 1:4d} {f_red[k]:10.4f} {TABLE2_HZ[k]:10.4f} {100 * (f_red[k] / TABLE2_HZ[k] - 1):8.2f}   "
              f"{mode_labels[k]}")
    build_seconds = time.perf_counter() - t_start
    fingerprint = build_fingerprint(params, n_cb, K3)
    load = [load_start, os.getloadavg()]
    info = dict(builder_version=BUILDER_VERSION, builder_fingerprint=fingerprint, full_dof=int(n_full), full_nodes=int(ac.fe.n_nodes),
                total_mass_kg=float(mass), axes="x aft from the nose, y to the right wing, z up",
                reduction="Craig-Bampton: 8 attachment nodes x 6 DOF + fixed-interface modes",
                n_fixed_interface_modes=int(n_cb), nonlinearity="cubic springs k3=-1e13 N/m^3 on relative uz "
                "across each tip-tank attachment", build_seconds=float(build_seconds))
    model = nnm_solver.Model(Mr, Kr, springs, dof_labels=dof_labels, mode_labels=mode_labels, mesh=mesh,
                             name="Paris-like aircraft" + (" (coarse)" if args.coarse else ""), info=info)
    prov = {k: (np.asarray(v, float) if isinstance(v, tuple) else v)
            for k, v in dataclasses.asdict(params).items()}
    extra = {
        "craig_bampton": {"full_dof": np.int64(n_full), "full_hz": f_full, "reduced_hz": f_red[pair],
                          "mac": mac_diag, "freq_error": ferr, "pair": pair.astype(np.int64),
                          "fixed_interface_hz": fixed_hz, "full_labels": list(labels_full),
                          "band_hz": np.array([0.0, args.fmax]), "retained_dofs": b.astype(np.int64),
                          "seconds": np.float64(t_cb)},
        "reference": {"table2_hz": TABLE2_HZ, "source": "seed paper Table 2", "mode_names": list(PAPER_MODE_NAMES)},
        "provenance": {"builder_version": BUILDER_VERSION, "builder_fingerprint": fingerprint, "params": prov,
                       "build_seconds": np.float64(build_seconds), "eigen_tol": np.float64(EIG_TOL),
                       "stage_seconds": np.array([t_assembly, t_full, t_cb, build_seconds]),
                       "stage_names": ["assembly", "full-model modes and labels", "Craig-Bampton", "total"],
                       "load_average_1_5_15_start_end": np.array(load), "python": platform.python_version(),
                       "numpy": np.__version__, "command": " ".join(["examples/build_paris.py"] + sys.argv[1:])},
    }
    nnm_solver.save_model(out, model, extra=extra)
    size = out.stat().st_size / 1e6
    print(f"\nwrote {out} ({size:.1f} MB, {mesh.vertices.shape[0]} display vertices, "
          f"{mesh.faces.shape[0]} faces) in {time.perf_counter() - t_start:.1f} s total (assembly {t_assembly:.1f} s, "
          f"full-model modes {t_full:.1f} s, Craig-Bampton {t_cb:.1f} s; load average {load[0][0]:.2f} at the start, "
          f"{os.getloadavg()[0]:.2f} at the end)\nbuilder fingerprint {fingerprint}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
