"""Write the unreduced Paris-like aircraft FE model (64,446 DOFs, sparse M and K) as an nnm HDF5 model file.

    python examples/build_paris_full.py                        # -> paris_full.h5 (about 30 s)
    python examples/build_paris_full.py --store-basis           # and the Ritz basis of mode 20 at H = 9 (+ ~2 min)
    python examples/build_paris_full.py --out F.h5 --no-check   # without the comparison with assets/paris.h5

The same FE model as examples/build_paris.py builds before its Craig-Bampton reduction
(``paris_aircraft.build_paris(ParisParams())``), with the same four softening cubic springs k3 = -1e13 N/m^3 on the
relative vertical displacement across each tip-tank attachment (there on the reduced model's retained DOFs
6 (2a) + 2 and 6 (2a + 1) + 2, here on the full model's DOFs ``ac.retained_dofs`` at those places), the same display
mesh (every second skin node) with a sparse displacement map (each vertex moves with its node: one 1 per row; a
dense map would be 3V x 64,446 float32), DOF labels ``node <node> <ux..rz>`` and labels of the modes in 0-100 Hz.
The file opens in ``nnm-solve`` (condensed harmonic balance: ``--method hb --condensed``; the model is too large for
the dense eigensolution the other methods need) and ``nnm-view`` (its lowest 48 linear modes).

Unless --no-check, the modes in 0-100 Hz are compared with the shipped Craig-Bampton model's (assets/paris.h5):
frequencies and the MAC of the shapes at the 48 retained DOFs (the first 48 coordinates of the reduced model are
those DOFs), so that a mode number means the same mode in both files; the table goes to /extra/full_vs_reduced.

--store-basis also computes the condensed harmonic balance's Ritz basis for --mode and --harmonics
(nnm_solver/model/ritz.py: the modes below 2 H f_mode plus the springs' residual fields) and stores it in the file
(``nnm_solver.store_ritz_basis``, 330 MB), so that a branch of that mode, or of any mode whose cutoff it covers,
starts without the Lanczos.
"""
from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):   # as build_paris.py: one BLAS thread
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402

import nnm_solver  # noqa: E402
from build_paris import EIG_TOL, K3, display_mesh  # noqa: E402
from nnm_fem import DOF_NAMES, modes  # noqa: E402
from paris_aircraft import ATTACHMENT_NAMES, BUILDER_VERSION, ParisParams, build_paris  # noqa: E402
from paris_aircraft.labels import label_modes  # noqa: E402
from paris_aircraft.tuning import TABLE2_HZ  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
REDUCED = ROOT / "assets" / "paris.h5"


def full_springs(ac, k3=K3):
    """The four cubic springs on the full model's DOFs: the reduced model's CubicSpring(6 (2a) + 2, 6 (2a + 1) + 2)
    at the retained DOFs it stands for (wing side uz, tank side uz of attachment a)."""
    r = ac.retained_dofs
    return [nnm_solver.CubicSpring(dof=int(r[6 * (2 * a) + 2]), other=int(r[6 * (2 * a + 1) + 2]), k3=k3)
            for a in range(4)]


def full_model(ac, stride=2, mode_labels=None, info=None):
    """The nnm Model of the unreduced aircraft ``ac`` (sparse M, K, the springs, the sparse display mesh)."""
    n = ac.fe.n_dof
    identity = sp.identity(n, dtype=np.float32, format="csr")       # each vertex moves with its node
    mesh = display_mesh(ac, identity, stride)
    dof_labels = [f"node {i} {DOF_NAMES[c]}" for i in range(ac.fe.n_nodes) for c in range(6)]
    return nnm_solver.Model(sp.csr_matrix(ac.M), sp.csr_matrix(ac.K), full_springs(ac), dof_labels=dof_labels,
                            mode_labels=mode_labels, mesh=mesh, name="Paris-like aircraft (full FE model)",
                            info=info or {})


def compare_with_reduced(ac, f_full, V_full, path=REDUCED):
    """The full model's modes against the reduced model's (file ``path``): for every full mode k the reduced mode
    of largest MAC at the retained DOFs, its frequency and the MAC; None without the file."""
    if not Path(path).exists():
        return None
    red = nnm_solver.load_model(path)
    f_red, Phi_red = red.linear_modes()
    nb = len(ac.retained_dofs)
    a = V_full[ac.retained_dofs]                                    # (48, modes)
    b = Phi_red[:nb, :len(f_full) + 10]                             # the reduced model's first 48 coordinates
    Mac = nnm_solver.mac(a, b)
    pair = np.argmax(Mac, axis=1)
    return dict(full_hz=f_full, reduced_hz=f_red[pair], pair=pair.astype(np.int64) + 1,
                mac_retained=Mac[np.arange(len(f_full)), pair], freq_error=f_red[pair] / f_full - 1.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="paris_full.h5", help="output file (default paris_full.h5 in this folder)")
    ap.add_argument("--stride", type=int, default=2, help="display mesh: every STRIDE-th skin node (default 2)")
    ap.add_argument("--fmax", type=float, default=100.0, help="modes labelled and compared up to FMAX Hz")
    ap.add_argument("--no-check", action="store_true", help="no comparison with the reduced model, no labels")
    ap.add_argument("--store-basis", action="store_true", help="store the Ritz basis of --mode at --harmonics")
    ap.add_argument("--mode", type=int, default=20, help="mode of the stored basis (default 20)")
    ap.add_argument("--harmonics", type=int, default=9, help="highest harmonic of the stored basis (default 9)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    load_start = os.getloadavg()
    params = ParisParams()
    ac = build_paris(params)
    n = ac.fe.n_dof
    print(f"full FE model: {ac.fe.n_nodes} nodes, {n} DOF, K nnz {ac.K.nnz}, mass {ac.fe.total_mass(ac.M):.1f} kg, "
          f"built in {ac.build_seconds:.1f} s", flush=True)
    labels, extra = None, {}
    if not args.no_check:
        t = time.perf_counter()
        n_eig = 60
        while True:
            f_full, V_full = modes(ac.K, ac.M, n_eig, sigma=-1.0, xyz=ac.fe.nodes, tol=EIG_TOL)
            if f_full[-1] > args.fmax or n_eig > 400:
                break
            n_eig = int(n_eig * 1.5)
        keep = f_full <= args.fmax
        f_full, V_full = f_full[keep], V_full[:, keep]
        labels, _ = label_modes(ac, V_full)
        print(f"{len(f_full)} modes in 0-{args.fmax:g} Hz ({time.perf_counter() - t:.1f} s)", flush=True)
        cmp = compare_with_reduced(ac, f_full, V_full)
        if cmp is not None:
            print(f"against {REDUCED.name} (548-DOF Craig-Bampton; MAC of the shapes at the 48 retained DOFs):")
            print(" mode   full Hz   reduced mode   reduced Hz   diff %   MAC(retained)   label")
            for k in range(len(f_full)):
                print(f" {k + 1:4d} {f_full[k]:9.4f} {cmp['pair'][k]:10d} {cmp['reduced_hz'][k]:13.4f} "
                      f"{100 * cmp['freq_error'][k]:8.4f} {cmp['mac_retained'][k]:12.6f}   {labels[k]}")
            same = bool(np.all(cmp["pair"] == np.arange(1, len(f_full) + 1)))
            print(f"same mode numbers in both models: {same}; max |diff| "
                  f"{100 * np.max(np.abs(cmp['freq_error'])):.4f} %, min MAC {cmp['mac_retained'].min():.6f}")
            extra["full_vs_reduced"] = dict(cmp, full_labels=list(labels), reduced_file=str(REDUCED.name))
    info = dict(builder_version=BUILDER_VERSION, full_dof=int(n), full_nodes=int(ac.fe.n_nodes),
                total_mass_kg=float(ac.fe.total_mass(ac.M)), axes="x aft from the nose, y to the right wing, z up",
                reduction="none: the full FE model (examples/build_paris_full.py)",
                nonlinearity="cubic springs k3=-1e13 N/m^3 on relative uz across each tip-tank attachment",
                springs="wing side uz - tank side uz of: " + "; ".join(ATTACHMENT_NAMES[2 * a] for a in range(4)))
    model = full_model(ac, args.stride, labels, info)
    prov = {k: (np.asarray(v, float) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(params).items()}
    extra["reference"] = {"table2_hz": TABLE2_HZ, "source": "seed paper Table 2"}
    extra["provenance"] = {"builder_version": BUILDER_VERSION, "params": prov,
                           "build_seconds": np.float64(time.perf_counter() - t_start),
                           "load_average_1_5_15_start": np.array(load_start), "python": platform.python_version(),
                           "numpy": np.__version__,
                           "command": " ".join(["examples/build_paris_full.py"] + sys.argv[1:])}
    out = Path(args.out)
    nnm_solver.save_model(out, model, extra=extra)
    mesh = model.mesh
    print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB: {n} DOFs, {mesh.vertices.shape[0]} display vertices, "
          f"{mesh.faces.shape[0]} faces, sparse map {mesh.displacement_map.nnz} entries) "
          f"in {time.perf_counter() - t_start:.1f} s", flush=True)
    if args.store_basis:
        t = time.perf_counter()
        stored = nnm_solver.store_ritz_basis(out, model, args.mode, args.harmonics)
        print(f"stored the Ritz basis of mode {args.mode} at H = {args.harmonics}: {stored['exact_modes']} modes below "
              f"{stored['cutoff_hz']:.1f} Hz + {stored['columns'] - stored['exact_modes']} residual vectors "
              f"({time.perf_counter() - t:.1f} s; file {out.stat().st_size / 1e6:.0f} MB)", flush=True)
    print(f"load average {load_start[0]:.2f} at the start, {os.getloadavg()[0]:.2f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
