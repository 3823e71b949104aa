"""A rig's AVR board image: where scripts/avr_build.py puts it (the one rule), and building it before it is used."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from mantaray.paths import REPO
from mantaray.protocol.rig import RigDescription

BUILD_SCRIPT = REPO / "scripts" / "avr_build.py"
BUILD_TIMEOUT_S = 900  # [s] a build from nothing of the Mega's image takes minutes on 2 cores


class AvrBuildError(Exception):
    """The board image could not be built; the message is the build's own."""


def build_dir(env: str) -> Path:
    """scripts/avr_build.py's output for a PlatformIO environment: build/avr for the Uno's, build/avr-ENV for
    another."""
    return REPO / "build" / ("avr" if env == "uno" else f"avr-{env}")


def elf_path(description: RigDescription) -> Path:
    """The rig's board image, built or not."""
    return build_dir(description.pio_env) / "firmware.elf"


def ensure_elf(description: RigDescription) -> Path:
    """Bring the rig's board image up to date (scripts/avr_build.py rebuilds only what changed) and return it."""
    build = subprocess.run(
        [sys.executable, str(BUILD_SCRIPT), "--env", description.pio_env],
        capture_output=True,
        text=True,
        timeout=BUILD_TIMEOUT_S,
    )
    if build.returncode != 0:
        raise AvrBuildError(build.stderr.strip() or f"{BUILD_SCRIPT.name} exited {build.returncode}")
    return elf_path(description)
