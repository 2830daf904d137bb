"""Files: the nnm HDF5 schema (``io``: the model; ``branch_io``: its branches; ``h5file``: atomic writes and one-line
file errors; ``sweep_groups``: a sweep's branch names and variants), FE model imports
(``importers/``, one module per format) and exports to the test lab (``exports``: CSV, UFF).

Layer: imports ``nnm_solver.results`` and the layers below it.
"""
from .exports import (Backbone, amplitude_backbone, export_backbone_csv, export_csv, export_uff,
                      export_uff_orbit)
from .io import load_extra, load_model, save_model, store_ritz_basis
from .branch_io import load_branches, save_branch

__all__ = ["load_model", "save_model", "load_branches", "save_branch", "load_extra", "export_csv", "export_uff",
           "export_uff_orbit", "amplitude_backbone", "export_backbone_csv", "Backbone", "store_ritz_basis"]
