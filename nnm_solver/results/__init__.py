"""What a computation returns: ``Point`` and ``Branch`` (columns, status, orbits rebuilt on demand),
the typed method settings that rebuild an orbit (``settings``), the stop statuses (``stops``) and
the frequency-energy plots (``plotting``).

Layer: imports ``nnm_solver.orbits`` and the layers below it.
"""
from .branch import STATUSES, Branch, Point
from .plotting import EVENT_MARKERS, plot_atlas, plot_fep
from .settings import HarmonicBalanceSettings, MethodSettings, ShootingSettings
from .tongues import TongueRecord
from .stops import STOP_STATUSES

__all__ = ["Branch", "Point", "STATUSES", "STOP_STATUSES", "MethodSettings", "ShootingSettings",
           "HarmonicBalanceSettings", "TongueRecord", "plot_fep", "plot_atlas", "EVENT_MARKERS"]
