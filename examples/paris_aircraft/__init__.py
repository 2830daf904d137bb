"""Paris-like aircraft: parametric FE builder, mode labelling, tuning (SI units).

Axes: x aft from the nose, y towards the right wing, z up.
"""
from .builder import build_paris
from .params import ATTACHMENT_NAMES, BUILDER_VERSION, Aircraft, ParisParams

__all__ = ["ATTACHMENT_NAMES", "BUILDER_VERSION", "Aircraft", "ParisParams", "build_paris"]
