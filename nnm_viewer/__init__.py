"""nnm_viewer: explore nonlinear normal modes in the browser (viser + trimesh).

Run ``nnm-view FILE.h5`` (or ``nnm-view paris.h5`` / ``two_dof.h5``, the shipped examples, from
any folder) and open the printed address.  Modules: ``app`` (CLI, server), ``examples`` (the
shipped examples), ``warmup`` (the solver's kernels compiled in the background),
``controls`` (``Session``: one tab's state and callbacks), ``layout`` (its GUI handles),
``drawing`` (coalesced redraws, control panel), ``fep_view`` (branch list, clickable FEP,
sliders), ``point_view`` (picked orbit: animation, Point tab), ``scene`` (mesh, camera, the 3D
FEP board), ``fep`` (FEP image and energy mapping), ``animation``/``glb`` (orbit as a GLB with
morph targets), ``info`` (point information), ``state``/``worker`` (shared branches, background
jobs), ``demo`` (a 2-DOF demo file), ``browser`` (headless Chromium helpers), ``screenshot``
(docs images).
"""

import os as _os
import sys as _sys

# The viewer works on small dense problems (a few hundred DOFs) in an interactive server: BLAS
# thread pools only make them slower (measured: 548-DOF eigenproblem 0.1 s with one thread,
# 2-6 s with two on a busy machine).  Only effective when numpy is not imported yet, i.e. when
# the viewer is the program (nnm-view); an explicit setting by the user wins.
if "numpy" not in _sys.modules:
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        _os.environ.setdefault(_var, "1")
