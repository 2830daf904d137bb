"""Time integration of the model's modal equations with the exact sensitivity of the discrete map.

``INTEGRATORS`` / ``get_integrator`` (registry: the only place a scheme is picked), Newmark average
acceleration (``newmark``, its exact monodromy ``newmark_monodromy``, the half-period map kept as
diagonal + low rank ``lowrank``) and Gauss-Legendre collocation (``gauss``, ``gauss_monodromy``).

Layer: imports ``nnm_solver.model`` and the base modules (errors, jit, threads).
"""
from . import gauss, newmark
from .registry import INTEGRATORS, Integrator, get_integrator, record_orbit

__all__ = ["INTEGRATORS", "Integrator", "get_integrator", "record_orbit", "gauss", "newmark"]
