"""The structure: M x'' + K x + f_nl(x) = 0 as data (SI units).

``Model`` (M, K dense or sparse, the nonlinear elements, labels, display mesh, energy, linear modes),
the elements and their force laws (``elements``, ``laws``, ``element_set``: each element defined once),
``ModalSystem`` (the model in mass-normalised modal coordinates), the k3 scaling law, variants of a
model, Craig-Bampton reduction and the MAC, the sparse factorisation.

Layer: imports only ``nnm_solver.errors`` and ``nnm_solver.jit``.
"""
from .coupled import PolynomialStiffness
from .element_set import ElementSet
from .elements import CubicSpring, PiecewiseLinearSpring, PolynomialSpring, check_element
from .mesh import DisplayMesh
from .model import MAX_DENSE_DOF, Model
from .modal import ModalSystem, modal_system
from .reduction import craig_bampton, mac, mass_mac
from .ritz import sparse_modes
from .scaling import cubic_scaling
from .variants import Variant, variant_grid

__all__ = ["Model", "MAX_DENSE_DOF", "CubicSpring", "PolynomialSpring", "PiecewiseLinearSpring", "PolynomialStiffness",
           "ElementSet",
           "check_element", "DisplayMesh", "ModalSystem", "modal_system", "craig_bampton", "mac", "mass_mac",
           "cubic_scaling", "Variant", "variant_grid", "sparse_modes"]
