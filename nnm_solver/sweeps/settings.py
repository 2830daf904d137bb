"""The sweep layer's settings: its intervals, timeouts and retries, written once.

``SWEEPS`` is the instance the code reads (``SWEEPS.connect_timeout``); ``EVENT_INTERVAL`` and ``CONNECT_TIMEOUT``
(nnm_solver.sweeps) stay importable as aliases of its fields.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SweepSettings", "SWEEPS"]


@dataclass(frozen=True)
class SweepSettings:
    """Intervals, timeouts and retries of a sweep on a Dask cluster (dask_sweep.py)."""

    #: least time (s) between two progress messages of one branch sent by a worker
    event_interval: float = 0.25
    #: seconds to wait for a scheduler given by address
    connect_timeout: float = 10.0
    #: a branch the cluster cancelled because its scattered model was lost (the worker holding its last copy died)
    #: is submitted again, with the model scattered anew, at most this many times
    lost_retries: int = 2


#: the sweep layer's settings (the defaults above, written once)
SWEEPS = SweepSettings()
