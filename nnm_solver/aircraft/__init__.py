"""Paris-like aircraft: parametric FE builder, mode labelling, tuning (SI units).

Axes: x aft from the nose, y towards the right wing, z up.
"""
from .builder import ATTACHMENT_NAMES, BUILDER_VERSION, Aircraft, ParisParams, build_paris

__all__ = ["ATTACHMENT_NAMES", "BUILDER_VERSION", "Aircraft", "ParisParams", "build_paris"]
