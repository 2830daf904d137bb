"""Parameter sweeps: branches (variant x mode) as Dask tasks (``dask_sweep``: ``sweep``), what a
sweep computes and its TOML file (``spec``), its output file (``sweep_files``) and progress
(``progress``).  Dask is imported only when a sweep runs.

Layer: imports ``nnm_solver.files``, ``driver`` and the layers below them.
"""
from ..files.sweep_groups import branch_name, parse_branch_name
from .dask_sweep import CONNECT_TIMEOUT, EVENT_INTERVAL, WORKER_ENV, sweep
from .progress import SweepProgress, reporter
from .spec import SweepSpec, as_variants, load_sweep_file, parse_modes
from .sweep_files import load_sweep, prepare_file

__all__ = ["sweep", "SweepProgress", "reporter", "load_sweep", "prepare_file", "branch_name", "parse_branch_name",
           "as_variants", "parse_modes", "SweepSpec", "load_sweep_file", "WORKER_ENV", "EVENT_INTERVAL",
           "CONNECT_TIMEOUT"]
