"""Where the FEP board sits in the 3D scene: a rectangle next to the model, facing the camera, and the map from
(energy J, frequency Hz) on the FEP to world positions (m)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BOARD_MARGINS", "BoardLayout", "board_layout"]

#: margins of the board picture around its plotting area (left, right, bottom, top), in fractions of the
#: plotting area's width (left, right) and height (bottom, top): the bottom one holds the tick labels, the
#: axis label and the legend (two columns, up to scene.BOARD_LEGEND_MAX entries), below the curves
BOARD_MARGINS = (0.17, 0.04, 0.6, 0.12)


@dataclass
class BoardLayout:
    """Placement of the in-scene FEP: a rectangle spanned by ``right`` (energy axis) and
    ``up`` (frequency axis) from ``origin`` (lower-left corner), sizes in m."""

    origin: np.ndarray
    right: np.ndarray
    up: np.ndarray
    width: float
    height: float
    normal: np.ndarray

    def to_world(self, energy, frequency, ranges):
        """World positions (N, 3) of FEP points (energy J, frequency Hz)."""
        (elo, ehi), (flo, fhi) = ranges
        u = (np.log10(np.maximum(np.asarray(energy, dtype=float), 1e-300)) - elo) / (ehi - elo)
        v = (np.asarray(frequency, dtype=float) - flo) / (fhi - flo)
        return (self.origin[None] + np.outer(u * self.width, self.right) + np.outer(v * self.height, self.up)
                + 0.02 * self.height * self.normal[None])

    def point_radius(self):
        return 0.016 * max(self.width, self.height)


def board_layout(bounds_min, bounds_max, view_dir, place="above"):
    """Place the FEP board next to a model with bounding box bounds_min/max (m), facing a camera
    that looks along ``view_dir`` (world, z up): above the model (``place="above"``, best for
    the tall viewport between the two side panels) or on the camera's right-hand side."""
    lo, hi = np.asarray(bounds_min, dtype=float), np.asarray(bounds_max, dtype=float)
    size = float(max(np.max(hi - lo), 1e-9))
    center = 0.5 * (lo + hi)
    f = np.asarray(view_dir, dtype=float).copy()
    if np.linalg.norm(np.cross(f, [0.0, 0.0, 1.0])) < 1e-9:
        f = np.array([0.0, 1.0, -0.5])
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)                      # the board faces the camera
    width, height = 1.0 * size, 0.7 * size
    if place == "above":
        half_up = 0.5 * float(np.abs(hi - lo) @ np.abs(up))
        # the picture's bottom margin (tick labels, axis label, legend) above the model
        origin = center + up * (half_up + 0.05 * size + (BOARD_MARGINS[2] + 0.02) * height) - right * 0.5 * width
    else:
        half_extent = 0.5 * float(np.abs(hi - lo) @ np.abs(right))
        origin = center + right * (half_extent + 0.15 * size) - up * 0.5 * height
    return BoardLayout(origin=origin, right=right, up=up, width=width, height=height, normal=-f)
