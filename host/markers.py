"""The ArUco marker layout of the rig (dictionary, ids, sizes, where the corner markers sit) and marker images."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Corner markers sit outside the 0.5 m frame beside its corners (PROTOCOL.md §5 numbering: 0 (-x,-y), 1 (+x,-y),
# 2 (-x,+y), 3 (+x,+y)), in the plane of the carriages at the reference height z0: off the diagonals, where
# the corner posts would hide them from an overhead camera, and clear of the carriages.
CORNER_SIGNS = ((-1, -1), (1, -1), (-1, 1), (1, 1))


@dataclass(frozen=True)
class MarkerLayout:
    """What the tracker looks for and where: every length in metres, in the fabric frame."""

    dictionary: str = "DICT_4X4_50"  # cv2.aruco predefined dictionary
    corner_ids: tuple[int, int, int, int] = (0, 1, 2, 3)  # marker id at corner 0..3
    corner_offset_m: tuple[float, float] = (0.33, 0.20)  # [m] corner marker centres at (+-x, +-y)
    corner_size_m: float = 0.04  # [m] black square's side
    object_ids: tuple[int, ...] = (10,)  # the marker on each object's top, in the order of the run's objects
    object_size_m: float = 0.03  # [m] black square's side, on the object's top
    border_bits: int = 1  # ArUco's black border, in cells

    def __post_init__(self) -> None:
        """Every marker names one thing: object ids distinct, none a corner's, each in the dictionary."""
        ids = tuple(self.object_ids)
        size = int(self.dictionary.rsplit("_", 1)[-1])  # DICT_4X4_50: ids 0..49
        if not ids:
            raise ValueError("object_ids: at least one object's marker id")
        if len(set(ids)) != len(ids):
            twice = sorted({i for i in ids if ids.count(i) > 1})
            raise ValueError(
                f"object_ids: {', '.join(map(str, twice))} given to two objects; each object needs its own"
            )
        clash = sorted(set(ids) & set(self.corner_ids))
        if clash:
            raise ValueError(f"object_ids: {', '.join(map(str, clash))} is a corner marker's id ({self.corner_ids})")
        outside = [i for i in ids if not 0 <= i < size]
        if outside:
            raise ValueError(f"object_ids: {outside[0]} is not in {self.dictionary} (ids 0..{size - 1})")

    def corner_centres_m(self) -> np.ndarray:
        """(4, 2) centres of the corner markers in the fabric frame, corner 0..3."""
        ox, oy = self.corner_offset_m
        return np.array([(sx * ox, sy * oy) for sx, sy in CORNER_SIGNS])

    def corner_points_m(self) -> np.ndarray:
        """(4, 4, 2) the four corners of each corner marker, in ArUco's order (top-left, top-right,
        bottom-right, bottom-left of the marker image), the image's top towards +y, its right towards +x."""
        half = self.corner_size_m / 2
        square = np.array([(-half, half), (half, half), (half, -half), (-half, -half)])
        return self.corner_centres_m()[:, None, :] + square[None, :, :]


def dictionary(layout: MarkerLayout):
    import cv2

    return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, layout.dictionary))


def marker_image(layout: MarkerLayout, marker_id: int, pixels: int, quiet_cells: int = 1) -> np.ndarray:
    """A marker as a greyscale image `pixels` wide, with a white quiet zone of `quiet_cells` cells around it."""
    import cv2

    cells = dictionary(layout).markerSize + 2 * layout.border_bits
    inner = pixels * cells // (cells + 2 * quiet_cells)
    marker = cv2.aruco.generateImageMarker(dictionary(layout), marker_id, inner, borderBits=layout.border_bits)
    out = np.full((pixels, pixels), 255, np.uint8)
    offset = (pixels - inner) // 2
    out[offset : offset + inner, offset : offset + inner] = marker
    return out


def quiet_scale(layout: MarkerLayout, quiet_cells: int = 1) -> float:
    """Side of marker_image()'s whole image over the black square's side."""
    cells = dictionary(layout).markerSize + 2 * layout.border_bits
    return (cells + 2 * quiet_cells) / cells
