"""Tools to read a computed NNM branch: harmonic content of its orbits (harmonics.py),
internal-resonance tongues (tongues.py), two backbones compared piece by piece between their jumps
(compare.py: ``compare_backbones(a, b)``), and the shapes of orbits and their MAC (shapes.py: ``mass_mac(model, a, b)``, the
mass-weighted MAC used everywhere).

Layer: imports ``nnm_solver.results`` and the layers below it.
"""
from .harmonics import (DISTORTION_FRACTION, RESONANCE_FRACTION, HarmonicContent, describe_orbit,
                        dominant_harmonic, harmonic_coefficients, harmonic_fractions, harmonic_shape, orbit_samples)
from .compare import BackboneComparison, BackbonePiece, backbone_pieces, compare_backbones
from .shapes import mac_orbits, mass_mac, orbit_shape
from .tongues import Tongue, find_tongues

__all__ = ["HarmonicContent", "Tongue", "harmonic_coefficients", "dominant_harmonic", "harmonic_fractions",
           "harmonic_shape", "orbit_samples", "describe_orbit", "find_tongues", "orbit_shape", "mac_orbits", "mass_mac",
           "RESONANCE_FRACTION", "DISTORTION_FRACTION", "BackbonePiece", "BackboneComparison", "backbone_pieces",
           "compare_backbones"]
