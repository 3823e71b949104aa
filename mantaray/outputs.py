"""Where the commands write: output folders and files checked before any work starts, so no result is lost late."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")  # what the figures are saved as (matplotlib)
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")  # what a printable image is saved as (OpenCV)


class OutputError(ValueError):
    """An output path that cannot be written; the message says which and why."""


def writable_dir(path: str | os.PathLike) -> Path:
    """The folder, created if missing, after proving a file can be written in it."""
    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".write-check-"):
            pass
    except OSError as exc:
        raise OutputError(f"cannot write into {folder}: {exc.strerror or exc}") from None
    return folder


def writable_file(path: str | os.PathLike, suffixes: tuple[str, ...] | None = None) -> Path:
    """The file's path once its folder is writable and its suffix is one of `suffixes` (when given)."""
    file = Path(path)
    if suffixes is not None and file.suffix.lower() not in suffixes:
        raise OutputError(
            f"{file}: the file type must be one of {', '.join(suffixes)}, got {file.suffix or 'no suffix'}"
        )
    if file.is_dir():
        raise OutputError(f"{file} is a folder; give a file name")
    writable_dir(file.parent)
    return file
