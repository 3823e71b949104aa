"""Where the natively built firmware artifacts live (the virtual MCU and its C library): a checkout's build, or the
installed package's own."""

from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent  # the checkout, when this runs from one
PACKAGED = Path(__file__).resolve().parent / "native"  # what `pip install .` built into the package


class NotBuilt(FileNotFoundError):
    """A native artifact is missing: the firmware has not been built."""


def build_dir() -> Path:
    """MANTARAY_BUILD_DIR if set, else build/ in the repository."""
    return Path(os.environ.get("MANTARAY_BUILD_DIR", REPO / "build"))


def native_artifact(name: str) -> Path:
    """The artifact in the build folder (MANTARAY_BUILD_DIR, else the checkout's build/: a developer's freshest),
    else the one the installed package carries."""
    for path in (build_dir() / name, PACKAGED / name):
        if path.exists():
            return path
    raise NotBuilt(
        f"{build_dir() / name} does not exist and the installed package carries none; build the firmware "
        f"first: cmake -S {REPO} -B {build_dir()} -G Ninja && ninja -C {build_dir()} (or pip install .)"
    )
