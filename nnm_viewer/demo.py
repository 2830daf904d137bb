"""A tiny demo model for trying the viewer and for tests: the 2-DOF benchmark
(M = I, K = [[2, -1], [-1, 2]], cubic spring k3 on DOF 0) drawn as two boxes, box j
moving vertically with DOF j.

    python -m nnm_viewer.demo two_dof.h5 && nnm-view two_dof.h5
"""
from __future__ import annotations

import sys

import numpy as np

import nnm_solver

_BOX_FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                       [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


def two_box_model(k3=0.5):
    """The 2-DOF benchmark model with a mesh of two boxes (0.8 m cubes, 2 m apart)."""
    corners = np.array([[x, y, z] for x in (-0.4, 0.4) for y in (-0.4, 0.4) for z in (-0.4, 0.4)])
    vertices = np.concatenate([corners, corners + [2.0, 0.0, 0.0]])
    faces = np.concatenate([_BOX_FACES, _BOX_FACES + 8])
    D = np.zeros((3 * len(vertices), 2))
    for j in range(2):
        for c in range(8):
            D[3 * (8 * j + c) + 2, j] = 1.0
    mesh = nnm_solver.DisplayMesh(vertices=vertices, faces=faces, displacement_map=D,
                                  part_ids=np.repeat([0, 1], 12), part_names=["mass 1", "mass 2"])
    return nnm_solver.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]),
                            [nnm_solver.CubicSpring(dof=0, k3=k3)], dof_labels=["x1", "x2"],
                            mode_labels=["in phase", "out of phase"], mesh=mesh, name="2-DOF demo")


def write_demo_file(path, energy_max=10.0, modes=(1, 2), max_points=60):
    """Save the demo model and its NNM branches (computed now) to ``path``; returns the model."""
    model = two_box_model()
    nnm_solver.save_model(path, model)
    for mode in modes:
        branch = nnm_solver.continue_nnm(model, mode=mode, energy_max=energy_max, max_points=max_points)
        nnm_solver.save_branch(path, branch)
    return model


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m nnm_viewer.demo OUT.h5", file=sys.stderr)
        return 2
    write_demo_file(argv[0])
    print(f"wrote {argv[0]}: try  nnm-view {argv[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
