"""Bring your own model: a small FE model written in every format nnm imports (docs/byom.md).

The project's FE kit (nnm_fem) builds a clamped aluminium cantilever (3D Timoshenko beam elements,
6 DOFs per node) with a grounded cubic spring at its tip, the way a customer's FE code would hand it
over, and writes it as

* ``beam.h5``                      the nnm HDF5 original (the reference of the round-trip tests);
* ``beam_M.mtx``, ``beam_K.mtx``   MatrixMarket, + ``beam_dofs.txt`` (node, direction of each DOF)
                                   and ``beam_mtx.toml`` (description: matrices, spring, mesh);
* ``beam_MASS1.mtx``, ``beam_STIF1.mtx``  Abaqus ``*MATRIX OUTPUT`` (node/DOF labelled), +
                                   ``beam_abaqus.toml``; the same in mm-t-s units: ``beam_mm_*.mtx``,
                                   ``beam_abaqus_mm.toml`` (units = "mm-t-s");
* ``beam.mat``                     MATLAB v5 (M, K sparse, springs = [dof other k3] 1-based, labels);
* ``beam.msh`` / ``beam_mm.msh``   a Gmsh display surface (a ribbon along the beam, in m / mm),
                                   written by meshio.

    python examples/bring_your_own_model.py --out byom/
    nnm-solve byom/beam_mtx.toml --list-modes
    nnm-solve import byom/beam_mtx.toml --out byom/beam_mtx.h5
    nnm-solve byom/beam_mtx.h5 --mode 1 --energy-max 0.05 --csv byom/nnm1.csv --uff byom/nnm1.uff \\
        --backbone byom/backbone.csv --backbone-dof "node 7 uz"
    nnm-view byom/beam_mtx.h5

Node numbers are 1-based as in FE codes (node 1 is clamped, so it is in no DOF map); DOF indices
are 0-based as everywhere in nnm.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import scipy.io

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import nnm_solver as nnm  # noqa: E402
from nnm_fem import DOF_NAMES, FEModel  # noqa: E402
from nnm_solver.files.importers.abaqus import write_abaqus_matrix  # noqa: E402
from nnm_solver.files.importers.common import DofMap  # noqa: E402

E, G, RHO = 70e9, 26e9, 2700.0          # aluminium (Pa, Pa, kg/m^3)
LENGTH, ELEMENTS = 1.0, 6               # m
WIDTH, HEIGHT = 0.05, 0.02              # section (m): bending in z is the first mode
K3 = 1e9                                # N/m^3, grounded cubic spring at the tip, uz
TIP_NODE = ELEMENTS + 1                 # 1-based node number of the tip


def beam_model():
    """The cantilever as an nnm Model (SI, sparse M, K of the free DOFs, DOF labels 'node i dir')."""
    fe = FEModel()
    nodes = fe.add_nodes(np.outer(np.linspace(0.0, LENGTH, ELEMENTS + 1), [1.0, 0.0, 0.0]))
    A, Iy, Iz = WIDTH * HEIGHT, WIDTH * HEIGHT ** 3 / 12, HEIGHT * WIDTH ** 3 / 12
    fe.add_beams("beam", nodes[:-1], nodes[1:], [0.0, 1.0, 0.0], E, G, A, Iy, Iz, 0.2 * WIDTH * HEIGHT ** 3,
                 rho=RHO)
    K, M = fe.assemble()
    free = np.arange(6, fe.n_dof)                                   # node 1 (index 0) clamped
    dof_map = DofMap([(1 + j // 6, DOF_NAMES[j % 6]) for j in free])
    tip_uz = dof_map.index(TIP_NODE, "uz")
    model = nnm.Model(M[free][:, free].tocsr(), K[free][:, free].tocsr(), [nnm.CubicSpring(dof=tip_uz, k3=K3)],
                      dof_labels=dof_map.labels(), mesh=ribbon_mesh(fe.nodes, dof_map), name="cantilever",
                      info={"builder": "examples/bring_your_own_model.py"})
    return model, fe.nodes, dof_map


def ribbon(nodes_xyz, scale=1.0):
    """A quad ribbon along the beam axis: points (2 per node, file order) and quads."""
    N = len(nodes_xyz)
    pts = np.repeat(nodes_xyz, 2, axis=0) + np.tile([[0, -WIDTH / 2, 0], [0, WIDTH / 2, 0]], (N, 1))
    quads = np.array([[2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1] for i in range(N - 1)])
    return pts * scale, quads


def ribbon_node_numbers(N):
    """Model node of each ribbon point (1-based node numbers): [1, 1, 2, 2, ...]."""
    return [1 + i // 2 for i in range(2 * N)]


def ribbon_mesh(nodes_xyz, dof_map):
    pts, quads = ribbon(nodes_xyz)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    D = np.zeros((3 * len(pts), len(dof_map)))
    for p, node in enumerate(ribbon_node_numbers(len(nodes_xyz))):
        for c, d in enumerate(("ux", "uy", "uz")):
            j = dof_map.get(node, d)
            if j is not None:
                D[3 * p + c, j] = 1.0
    return nnm.DisplayMesh(pts, tris, D, part_ids=np.zeros(len(tris)), part_names=["beam"])


def _write_msh(path, pts, quads):
    import meshio
    meshio.write(path, meshio.Mesh(pts, [("quad", quads)]), file_format="gmsh", binary=False)


def _spring_table(node, k3):
    return f'[[springs]]\ntype = "cubic"\nnode = {node}\ndirection = "uz"\nk3 = {k3!r}\n'


def write_all(folder):
    """Write the beam in every route into ``folder``; returns {route: model file}."""
    import scipy.sparse as sp
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    model, xyz, dof_map = beam_model()
    nodes_list = ribbon_node_numbers(len(xyz))
    out = {"h5": folder / "beam.h5"}
    nnm.save_model(out["h5"], model)

    # MatrixMarket + a DOF map file + a Gmsh ribbon (m)
    scipy.io.mmwrite(folder / "beam_M.mtx", model.M, symmetry="symmetric", precision=17)
    scipy.io.mmwrite(folder / "beam_K.mtx", model.K, symmetry="symmetric", precision=17)
    (folder / "beam_dofs.txt").write_text("# node direction, one line per model DOF\n" +
                                          "".join(f"{n} {d}\n" for n, d in dof_map.entries))
    pts, quads = ribbon(xyz)
    _write_msh(folder / "beam.msh", pts, quads)
    out["matrixmarket"] = folder / "beam_mtx.toml"
    out["matrixmarket"].write_text(
        'name = "cantilever"\nunits = "SI"\n\n[matrices]\nformat = "matrixmarket"\nmass = "beam_M.mtx"\n'
        'stiffness = "beam_K.mtx"\ndof_map = "beam_dofs.txt"\n\n' + _spring_table(TIP_NODE, K3) +
        f'\n[mesh]\nfile = "beam.msh"\nnodes = {nodes_list}\n')

    # Abaqus *MATRIX OUTPUT (node/DOF labels), in SI ...
    write_abaqus_matrix(folder / "beam_MASS1.mtx", model.M, dof_map)
    write_abaqus_matrix(folder / "beam_STIF1.mtx", model.K, dof_map)
    out["abaqus"] = folder / "beam_abaqus.toml"
    out["abaqus"].write_text(
        'name = "cantilever"\n\n[matrices]\nformat = "abaqus"\nmass = "beam_MASS1.mtx"\n'
        'stiffness = "beam_STIF1.mtx"\n\n' + _spring_table(TIP_NODE, K3) +
        f'\n[mesh]\nfile = "beam.msh"\nnodes = {nodes_list}\n')
    # ... and in mm-t-s (length mm, mass t, force N, energy N mm), as Abaqus users often work
    L, mass = 1e-3, 1e3
    energy = mass * L ** 2
    S = sp.diags(np.where(dof_map.rotations(), 1.0, L))       # m (rad) per file unit of each DOF
    write_abaqus_matrix(folder / "beam_mm_MASS1.mtx", S @ model.M @ S / (mass * L ** 2), dof_map)
    write_abaqus_matrix(folder / "beam_mm_STIF1.mtx", S @ model.K @ S / energy, dof_map)
    pts_mm, _ = ribbon(xyz, scale=1e3)
    _write_msh(folder / "beam_mm.msh", pts_mm, quads)
    out["abaqus_mm"] = folder / "beam_abaqus_mm.toml"
    out["abaqus_mm"].write_text(
        'name = "cantilever"\nunits = "mm-t-s"\n\n[matrices]\nformat = "abaqus"\nmass = "beam_mm_MASS1.mtx"\n'
        'stiffness = "beam_mm_STIF1.mtx"\n\n' + _spring_table(TIP_NODE, K3 * L ** 4 / energy) +
        f'\n[mesh]\nfile = "beam_mm.msh"\nnodes = {nodes_list}\n')

    # MATLAB v5: springs [dof other k3] with 1-based DOF numbers
    tip = model.springs[0].dof
    scipy.io.savemat(folder / "beam.mat", {"M": model.M.tocsc(), "K": model.K.tocsc(),
                                           "springs": np.array([[tip + 1, 0, K3]]),
                                           "dof_labels": np.array(model.dof_labels, dtype=object)})
    out["matlab"] = folder / "beam.mat"
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="byom", help="folder for the files (default: byom)")
    args = p.parse_args(argv)
    files = write_all(args.out)
    for route, path in files.items():
        print(f"{route:>12}: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
