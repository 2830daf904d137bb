"""nnm_viewer: explore nonlinear normal modes in the browser (viser + trimesh).

Run ``nnm-view FILE.h5`` and open the printed address.  Modules: ``app`` (CLI, server),
``controls`` (one session per tab: controls and drawing), ``scene`` (mesh, camera, the
clickable FEP), ``fep`` (FEP image and energy mapping), ``animation``/``glb`` (orbit as a
GLB with morph targets), ``info`` (point information), ``state``/``worker`` (shared
branches, background jobs).
"""
