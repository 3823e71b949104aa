"""The overhead camera as a position sensor: ArUco (or a colour blob) -> object (x, y) [m] in the fabric frame.

The four corner markers define the fabric frame. Without a camera calibration the tracker fits the
homography from the image to the corner markers' plane (z = 0 of the fabric frame, at the carriages'
reference height z0) and corrects the object's marker for its height above that plane with the camera
straight above camera_xy_m at camera_height_m. With a calibration (camera matrix and distortion) it
solves the camera's full pose from the corner markers and intersects the ray through the object's
marker with the plane of the marker's height. Either way nothing is guessed: a frame without all four
corner markers, or without the object, is reported as such (Observation.status).

Several objects are told apart by their markers' ids (MarkerLayout.object_ids) or by their colours (one BlobColour
each), so an object keeps its place in Observation.objects from frame to frame; Presence says when one is lost and
when it is found again.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .markers import MarkerLayout, dictionary

OK = "ok"
NO_FRAME = "no fabric frame"  # fewer than the four corner markers, and no earlier frame fit to reuse
NO_OBJECT = "object not seen"


@dataclass(frozen=True)
class Calibration:
    """A pinhole camera: intrinsics K (3 x 3) [px] and OpenCV's distortion coefficients."""

    camera_matrix: np.ndarray
    distortion: np.ndarray

    @classmethod
    def load(cls, path: str | Path) -> Calibration:
        with np.load(path) as data:
            return cls(data["camera_matrix"], data["distortion"])

    def save(self, path: str | Path) -> None:
        np.savez(path, camera_matrix=self.camera_matrix, distortion=self.distortion)


@dataclass(frozen=True)
class ObjectSeen:
    """Where one tracked object was in one frame."""

    xy_m: tuple[float, float] | None  # [m] in the fabric frame; None: not seen in this frame
    pixel: tuple[float, float] | None = None  # [px] where it was found in the image (x right, y down)


@dataclass(frozen=True)
class Observation:
    """One camera frame's verdict: every tracked object's (x, y) [m] in the fabric frame, or why there is none.

    status is the frame's verdict on the first (or only) object, whose place xy_m and pixel give: OK, NO_FRAME (no
    object measured at all) or NO_OBJECT. objects holds every tracked object in the order of the layout's
    object_ids (or of the blob colours); it is empty when the frame gave no fabric frame."""

    capture_time_s: float  # [s] when the frame was captured (monotonic clock or video time)
    status: str  # OK, NO_FRAME or NO_OBJECT
    objects: tuple[ObjectSeen, ...] = ()
    corners_seen: tuple[int, ...] = ()  # which corner markers (0..3) this frame showed
    reused_frame_fit: bool = False  # the fabric frame came from an earlier image (a corner was hidden)

    @property
    def xy_m(self) -> tuple[float, float] | None:
        return self.objects[0].xy_m if self.objects else None

    @property
    def pixel(self) -> tuple[float, float] | None:
        return self.objects[0].pixel if self.objects else None

    @property
    def visible(self) -> bool:
        return self.status == OK


@dataclass
class BlobColour:
    """A marker-less object (the egg): the largest blob within an HSV range (OpenCV's H 0..179, S, V 0..255)."""

    hsv_low: tuple[int, int, int]
    hsv_high: tuple[int, int, int]
    min_area_px: int = 30


@dataclass
class Tracker:
    """Finds the fabric frame and the object in BGR or grey images. Reuse one per camera: it keeps the last
    fabric-frame fit so that a frame with a corner marker hidden (a hand, the object) still measures, flagged."""

    layout: MarkerLayout = field(default_factory=MarkerLayout)
    marker_height_m: float = 0.0  # [m] object marker (or blob) above the corner markers' plane
    camera_height_m: float = 1.0  # [m] camera above that plane (homography mode's parallax)
    camera_xy_m: tuple[float, float] = (0.0, 0.0)  # [m] the point the camera stands above
    calibration: Calibration | None = None
    blobs: tuple[BlobColour, ...] = ()  # track colour blobs, one colour an object, instead of the objects' markers
    max_frame_age_s: float = 5.0  # [s] how long a fabric-frame fit may be reused

    def __post_init__(self) -> None:
        import cv2

        params = cv2.aruco.DetectorParameters()
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
        self._detector = cv2.aruco.ArucoDetector(dictionary(self.layout), params)
        self._fit: tuple | None = None  # (image -> plane homography, or (rvec, tvec)), fit time [s]

    # ------------------------------------------------------------------------------------------- frames
    def observe(self, image: np.ndarray, capture_time_s: float | None = None) -> Observation:
        import cv2

        t = time.monotonic() if capture_time_s is None else capture_time_s
        grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        corners, ids, _ = self._detector.detectMarkers(grey)
        found = {int(i): c.reshape(4, 2) for i, c in zip(ids.ravel(), corners, strict=True)} if ids is not None else {}
        seen = tuple(k for k, marker_id in enumerate(self.layout.corner_ids) if marker_id in found)
        reused = False
        if len(seen) == 4:
            self._fit = (self._fit_frame(np.array([found[i] for i in self.layout.corner_ids])), t)
        elif self._fit is not None and t - self._fit[1] <= self.max_frame_age_s:
            reused = True
        else:
            return Observation(t, NO_FRAME, corners_seen=seen)
        if self.blobs:
            points = [self._blob_centre(image, blob) for blob in self.blobs]
        else:
            points = [None if i not in found else found[i].mean(axis=0) for i in self.layout.object_ids]
        objects = tuple(ObjectSeen(None) if p is None else self._seen_at(p) for p in points)
        return Observation(t, OK if objects[0].xy_m is not None else NO_OBJECT, objects, seen, reused)

    def object_names(self) -> list[str]:
        """What each tracked object is called in messages, in Observation.objects' order."""
        if self.blobs:
            return [f"object {k} (colour blob {k})" for k in range(len(self.blobs))]
        return [f"object {k} (marker {i})" for k, i in enumerate(self.layout.object_ids)]

    def _seen_at(self, pixel: np.ndarray) -> ObjectSeen:
        x, y = self._to_fabric(pixel)
        return ObjectSeen((float(x), float(y)), (float(pixel[0]), float(pixel[1])))

    def _fit_frame(self, image_corners: np.ndarray):
        import cv2

        plane = self.layout.corner_points_m().reshape(-1, 2)
        pixels = image_corners.reshape(-1, 2).astype(np.float64)
        if self.calibration is None:
            homography, _ = cv2.findHomography(pixels, plane, 0)
            return homography
        objects = np.hstack([plane, np.zeros((len(plane), 1))])
        ok, rvec, tvec = cv2.solvePnP(
            objects, pixels, self.calibration.camera_matrix, self.calibration.distortion, flags=cv2.SOLVEPNP_ITERATIVE
        )
        if not ok:
            raise RuntimeError("solvePnP failed on the four corner markers")
        return rvec, tvec

    def projection(self, height_m: float = 0.0):
        """The last fitted image's projection of points height_m [m] above the corner markers' plane: a function of
        (k, 2) points [m] in the fabric frame giving (k, 2) pixels, what the view draws the target and epsilon with
        at the tracked marker's height; None before any image showed the four corner markers. The function keeps
        the fit it was made from."""
        import cv2

        if self._fit is None:
            return None
        fit = self._fit[0]
        if self.calibration is None:
            to_image = np.linalg.inv(fit)
            c, h, camera_m = np.asarray(self.camera_xy_m), height_m, self.camera_height_m

            def project(points_m: np.ndarray) -> np.ndarray:
                # the plane point the camera sees behind a point h above it (the inverse of _to_fabric's parallax)
                plane = c + (np.asarray(points_m, dtype=np.float64).reshape(-1, 2) - c) * camera_m / (camera_m - h)
                return cv2.perspectiveTransform(plane.reshape(-1, 1, 2), to_image).reshape(-1, 2)

            return project
        rvec, tvec = fit
        matrix, distortion = self.calibration.camera_matrix, self.calibration.distortion

        def project_calibrated(points_m: np.ndarray) -> np.ndarray:
            plane = np.asarray(points_m, dtype=np.float64).reshape(-1, 2)
            objects = np.hstack([plane, np.full((len(plane), 1), height_m)])
            return cv2.projectPoints(objects, rvec, tvec, matrix, distortion)[0].reshape(-1, 2)

        return project_calibrated

    def _to_fabric(self, pixel: np.ndarray) -> tuple[float, float]:
        import cv2

        assert self._fit is not None  # observe() calls this only after a fit
        fit = self._fit[0]
        h = self.marker_height_m
        if self.calibration is None:
            p = cv2.perspectiveTransform(pixel.reshape(1, 1, 2).astype(np.float64), fit).reshape(2)
            c = np.asarray(self.camera_xy_m)
            return tuple(c + (p - c) * (self.camera_height_m - h) / self.camera_height_m)
        rvec, tvec = fit
        rotation, _ = cv2.Rodrigues(rvec)
        ray_cam = cv2.undistortPoints(
            pixel.reshape(1, 1, 2).astype(np.float64), self.calibration.camera_matrix, self.calibration.distortion
        ).reshape(2)
        direction = rotation.T @ np.array([ray_cam[0], ray_cam[1], 1.0])  # in the fabric frame
        centre = (-rotation.T @ tvec).ravel()  # the camera, fabric frame
        s = (h - centre[2]) / direction[2]
        point = centre + s * direction
        return float(point[0]), float(point[1])

    @staticmethod
    def _blob_centre(image: np.ndarray, blob: BlobColour) -> np.ndarray | None:
        import cv2

        if image.ndim == 2:
            raise ValueError("colour-blob tracking needs colour (BGR) images")
        hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
        mask = cv2.inRange(hsv, np.array(blob.hsv_low), np.array(blob.hsv_high))
        count, _, stats, centroids = cv2.connectedComponentsWithStats(mask)
        if count <= 1:
            return None
        best = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
        if stats[best, cv2.CC_STAT_AREA] < blob.min_area_px:
            return None
        return centroids[best]


@dataclass
class Presence:
    """Which tracked objects are seen, frame after frame: an object is lost once not seen for lost_after_s since
    it last was (a marker that flickers for a frame or two is not), and found again at the first frame that sees it
    after that. A frame without the fabric frame says nothing of the objects."""

    names: Sequence[str]  # the objects, in Observation.objects' order (Tracker.object_names)
    # [s] shorter than the firmware's deadman (0.5 s by default), so the loss is said before the board levels
    lost_after_s: float = 0.3
    _last_seen_s: list = field(default_factory=list)  # [s] per object: the last frame that saw it (None: none yet)
    _lost: list = field(default_factory=list)  # per object: reported lost and not found since
    _first_s: float | None = None  # [s] the first frame's time: what "not seen yet" counts from

    def __post_init__(self) -> None:
        self._last_seen_s = [None] * len(self.names)
        self._lost = [False] * len(self.names)

    def update(self, t_s: float, observation: Observation) -> list[str]:
        """The frame's changes at run time t_s [s], one line each: '<name> lost at T s (last seen at S s)',
        '<name> found again at T s, after D s unseen'."""
        if not observation.objects:
            return []
        if self._first_s is None:
            self._first_s = t_s
        lines = []
        for k, (name, seen) in enumerate(zip(self.names, observation.objects, strict=True)):
            last = self._last_seen_s[k]
            since = self._first_s if last is None else last
            if seen.xy_m is not None:
                if self._lost[k]:
                    again = "" if last is None else "again "
                    lines.append(f"{name} found {again}at {t_s:.2f} s, after {t_s - since:.2f} s unseen")
                self._last_seen_s[k], self._lost[k] = t_s, False
            elif not self._lost[k] and t_s - since >= self.lost_after_s:
                self._lost[k] = True
                when = "not seen since the run began" if last is None else f"last seen at {last:.2f} s"
                lines.append(f"{name} lost at {t_s:.2f} s ({when})")
        return lines

    def lost(self) -> list[int]:
        """The objects lost now (their places in Observation.objects)."""
        return [k for k, lost in enumerate(self._lost) if lost]


class FrameSource:
    """Frames from a camera index or a video file, each with its capture time [s] (monotonic, or the video's)."""

    def __init__(self, source: str | int, width: int = 1280, height: int = 720) -> None:
        import cv2

        self.is_file = not (isinstance(source, int) or str(source).isdigit())
        self._capture = cv2.VideoCapture(str(source) if self.is_file else int(source))
        if not self._capture.isOpened():
            kind = "video file" if self.is_file else "camera"
            raise OSError(f"cannot open {kind} {source!r}")
        if not self.is_file:
            self._capture.set(cv2.CAP_PROP_FRAME_WIDTH, width)
            self._capture.set(cv2.CAP_PROP_FRAME_HEIGHT, height)

    def read(self) -> tuple[np.ndarray, float] | None:
        """(BGR image, capture time [s]), or None at the end of a file or when the camera stops."""
        import cv2

        ok, image = self._capture.read()
        if not ok:
            return None
        if self.is_file:
            return image, self._capture.get(cv2.CAP_PROP_POS_MSEC) / 1000.0
        return image, time.monotonic()

    def close(self) -> None:
        self._capture.release()
