"""The camera's commands: `mantaray markers` (the printable marker sheet) and `calibrate-camera` (ChArUco intrinsics)."""

from __future__ import annotations

import argparse
import sys

from mantaray.arguments import number
from mantaray.outputs import IMAGE_SUFFIXES, OutputError, writable_file


# ------------------------------------------------------------------------------------------- markers
def cmd_markers(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Write a printable sheet of the rig's ArUco markers at true size (PDF or PNG; print at 100 %)."""
    from .marker_sheet import DPI_RANGE, write_marker_sheet

    if not DPI_RANGE[0] <= args.dpi <= DPI_RANGE[1]:
        parser.error(f"--dpi must be {DPI_RANGE[0]}..{DPI_RANGE[1]}, got {args.dpi}")
    try:
        out = writable_file(args.out, (".pdf", ".png"))
    except OutputError as exc:
        parser.error(str(exc))
    try:
        count = write_marker_sheet(out, args.dpi)
    except OutputError as exc:  # the write itself failed (a full disk): nothing is left at out
        print(f"mantaray markers: {exc}", file=sys.stderr)
        return 2
    print(f"{out}: {count} markers on A4 at true size" + (f", {args.dpi} dpi" if out.suffix == ".png" else ""))
    return 0


# ------------------------------------------------------------------------------------------- calibrate
def _squares(text: str) -> tuple[int, int]:
    try:
        nx, ny = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected squares like 7x5, got {text!r}") from None
    if nx < 2 or ny < 2:
        raise argparse.ArgumentTypeError(f"a ChArUco board needs at least 2 x 2 squares, got {text!r}")
    return nx, ny


def cmd_calibrate_camera(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Calibrate the camera with a ChArUco board: --board-out writes the board to print; then show it to the
    camera from several angles (or give a video of that) and the intrinsics go to --out (.npz)."""
    from .charuco import calibrate_from_frames, charuco_board

    _check_calibrate_arguments(args, parser)
    board = charuco_board(args.squares, args.square_mm, args.marker_mm)
    if args.board_out:
        _write_board(args, parser, board)
    if args.camera is None:
        return 0
    frames = _read_frames(args.camera, args.frames)
    try:
        calibration, rms, used = calibrate_from_frames(board, frames)
    except ValueError as exc:
        print(f"mantaray calibrate-camera: {exc}", file=sys.stderr)
        return 1
    calibration.save(args.out)
    k = calibration.camera_matrix
    print(
        f"{args.out}: fx {k[0, 0]:.1f} fy {k[1, 1]:.1f} cx {k[0, 2]:.1f} cy {k[1, 2]:.1f} px, "
        f"reprojection RMS {rms:.3f} px from {used} of {len(frames)} frames"
    )
    return 0


def _check_calibrate_arguments(args: argparse.Namespace, parser: argparse.ArgumentParser) -> None:
    """The board's sizes, something to do, and the outputs writable, before any work."""
    if not 0 < args.marker_mm < args.square_mm:
        parser.error(
            f"the marker ({args.marker_mm:g} mm) must be smaller than its square ({args.square_mm:g} mm) "
            f"and larger than 0"
        )
    if args.camera is None and not args.board_out:
        parser.error("give --camera (index or video file) to calibrate, or --board-out to print the board")
    try:
        if args.board_out:
            writable_file(args.board_out, IMAGE_SUFFIXES)
        if args.camera is not None:
            writable_file(args.out, (".npz",))
    except OutputError as exc:
        parser.error(str(exc))


def _write_board(args: argparse.Namespace, parser: argparse.ArgumentParser, board) -> None:
    import cv2

    from .charuco import PRINT_DPI, board_image

    if not cv2.imwrite(args.board_out, board_image(board, args.squares, args.square_mm)):
        parser.error(f"could not write {args.board_out!r} (an image: .png, .jpg, .tif ...)")
    print(f"{args.board_out}: {args.squares[0]} x {args.squares[1]} squares of {args.square_mm} mm at {PRINT_DPI} dpi")


def _read_frames(camera: str, most: int) -> list:
    """Up to `most` frames from the camera or video (fewer when a video ends first)."""
    from .tracker import FrameSource

    source = FrameSource(camera)
    frames: list = []
    while len(frames) < most and (grabbed := source.read()) is not None:
        frames.append(grabbed[0])
    source.close()
    return frames


# ------------------------------------------------------------------------------------------- parsers
def add_parsers(sub: argparse._SubParsersAction, fmt: type[argparse.HelpFormatter]) -> None:
    markers = sub.add_parser(
        "markers", help="a printable marker sheet at true size", description=cmd_markers.__doc__, formatter_class=fmt
    )
    markers.add_argument("--out", default="out/markers.pdf", help="the sheet: .pdf or .png")
    markers.add_argument("--dpi", type=int, default=300, help="resolution of a PNG sheet")
    markers.set_defaults(func=lambda args: cmd_markers(args, markers))

    calibrate = sub.add_parser(
        "calibrate-camera",
        help="camera calibration with a ChArUco board",
        description=cmd_calibrate_camera.__doc__,
        formatter_class=fmt,
    )
    calibrate.add_argument("--camera", help="camera index or video file showing the board")
    calibrate.add_argument("--out", default="out/camera.npz", help="the calibration (for mantaray rig --calibration)")
    calibrate.add_argument("--board-out", help="write the board to print (PNG at 300 dpi)")
    calibrate.add_argument(
        "--squares", type=_squares, default=(7, 5), metavar="NXxNY", help="board squares, at least 2 x 2"
    )
    calibrate.add_argument("--square-mm", type=number(0, above=True), default=30.0, help="square side [mm]")
    calibrate.add_argument("--marker-mm", type=number(0, above=True), default=22.0, help="marker side [mm]")
    calibrate.add_argument("--frames", type=number(1, integer=True), default=200, help="read at most this many frames")
    calibrate.set_defaults(func=lambda args: cmd_calibrate_camera(args, calibrate))
