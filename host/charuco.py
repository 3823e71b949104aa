"""Camera calibration with a ChArUco board: the board to print, and the intrinsics from views of it."""

from __future__ import annotations

import numpy as np

from .markers import MarkerLayout, dictionary
from .tracker import Calibration

PRINT_DPI = 300  # [1/inch] the printable board's resolution


def charuco_board(squares: tuple[int, int], square_mm: float, marker_mm: float):
    """The board: squares (x, y) of square_mm [mm] with ArUco markers of marker_mm [mm] from the rig's dictionary."""
    import cv2

    return cv2.aruco.CharucoBoard(squares, square_mm / 1000, marker_mm / 1000, dictionary(MarkerLayout()))


def board_image(board, squares: tuple[int, int], square_mm: float) -> np.ndarray:
    """The board as a grey image at PRINT_DPI, to print at 100 %."""
    px_per_mm = PRINT_DPI / 25.4
    return board.generateImage((int(squares[0] * square_mm * px_per_mm), int(squares[1] * square_mm * px_per_mm)))


def calibrate_from_frames(board, frames, min_corners: int = 8) -> tuple[Calibration, float, int]:
    """(Calibration, RMS reprojection error [px], views used) from BGR or grey images of a ChArUco board."""
    import cv2

    detector = cv2.aruco.CharucoDetector(board)
    objects, images, size = [], [], None
    for image in frames:
        grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        size = grey.shape[::-1]
        corners, ids, _, _ = detector.detectBoard(grey)
        if ids is None or len(ids) < min_corners:
            continue
        obj, img = board.matchImagePoints(corners, ids)
        objects.append(obj)
        images.append(img)
    if len(objects) < 5:
        raise ValueError(f"only {len(objects)} frames showed the board well enough (at least 5 needed)")
    rms, k, dist, _, _ = cv2.calibrateCamera(objects, images, size, None, None)  # type: ignore[call-overload,arg-type]
    return Calibration(k, dist.ravel()), float(rms), len(objects)
