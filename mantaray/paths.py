"""Where the natively built firmware artifacts live (the virtual MCU and its C library)."""
from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


class NotBuilt(FileNotFoundError):
    """A native artifact is missing: the firmware has not been built."""


def build_dir() -> Path:
    """MANTARAY_BUILD_DIR if set, else build/ in the repository."""
    return Path(os.environ.get("MANTARAY_BUILD_DIR", REPO / "build"))


def native_artifact(name: str) -> Path:
    path = build_dir() / name
    if not path.exists():
        raise NotBuilt(f"{path} does not exist; build the firmware first: "
                       f"cmake -S {REPO} -B {build_dir()} -G Ninja && ninja -C {build_dir()}")
    return path
