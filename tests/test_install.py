"""`pip install .` (not editable) into a fresh virtual environment gives a working mantaray outside the checkout:
the wheel carries the native firmware (built by scikit-build-core from CMakeLists.txt) and every data file the
package reads, and what its commands import comes with it (the environment sees none of this machine's packages)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile

import pytest

from mantaray.paths import REPO


def _env() -> dict[str, str]:
    """This process's environment without what would point the installed package back at the checkout."""
    return {k: v for k, v in os.environ.items() if k not in ("MANTARAY_BUILD_DIR", "PYTHONPATH", "VIRTUAL_ENV")}


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A fresh virtual environment (python3 -m venv, no system site packages) with the wheel built from this checkout
    installed by its own pip, dependencies from the package index: (wheel, the environment's bin folder)."""
    root = tmp_path_factory.mktemp("install")
    venv = subprocess.run(
        [sys.executable, "-m", "venv", str(root / "venv")], capture_output=True, text=True, timeout=300
    )
    assert venv.returncode == 0, venv.stderr
    bin_dir = root / "venv" / "bin"
    pip = [str(bin_dir / "python"), "-m", "pip", "-q"]
    build = subprocess.run(
        [*pip, "wheel", "--no-deps", "-w", str(root / "dist"), str(REPO)],
        capture_output=True,
        text=True,
        timeout=900,
        env=_env(),
    )
    assert build.returncode == 0, build.stderr
    (wheel,) = (root / "dist").glob("mantaray-*.whl")
    install = subprocess.run([*pip, "install", str(wheel)], capture_output=True, text=True, timeout=900, env=_env())
    assert install.returncode == 0, install.stderr
    return wheel, bin_dir


def _run_installed(bin_dir, program: str, *args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(bin_dir / program), *args], capture_output=True, text=True, timeout=300, cwd=cwd, env=_env()
    )


def test_the_wheel_carries_the_native_firmware_and_the_data_files(installed):
    wheel, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in (
        "mantaray/native/libmantaray_capi.so",
        "mantaray/native/mantaray-vmcu",
        "mantaray/protocol/schema.toml",
        "mantaray/protocol/rig.toml",
        "mantaray/protocol/rig.py",
        "mantaray/protocol/boards.py",
        "mantaray/protocol/rigs/array_2x2.toml",
        "mantaray/native/mantaray-vmcu-array_2x2",
        "mantaray/native/libmantaray_capi_array_2x2.so",
        "mantaray/sim/model/plant.toml",
        "mantaray/sim/model/assets/bunny.obj",
        "mantaray/protocol/conformance/plugin.py",
    ):
        assert name in names, name
    assert not any("__pycache__" in n for n in names)


def test_the_installed_package_runs_the_main_job_outside_the_checkout(installed, tmp_path):
    _, bin_dir = installed
    where = _run_installed(
        bin_dir,
        "python",
        "-c",
        "import mantaray.paths as p, mantaray.sim.trial.bridge as b; "
        "print(p.native_artifact('libmantaray_capi.so')); print(b.__file__)",
        cwd=tmp_path,
    )
    assert where.returncode == 0, where.stderr
    venv = str(bin_dir.parent)
    assert all(line.startswith(venv) for line in where.stdout.split())  # nothing from the checkout
    vmcu = _run_installed(bin_dir, "mantaray", "vmcu", "--identify-only", cwd=tmp_path)
    assert vmcu.returncode == 0 and "matches this host" in vmcu.stdout, vmcu.stderr
    run = _run_installed(
        bin_dir, "mantaray", "sim", "run", "--duration", "0.5", "--json", "--out", str(tmp_path / "out"), cwd=tmp_path
    )
    result = json.loads(run.stdout.splitlines()[-1])
    assert run.returncode == 1 and not result["success"], run.stderr  # 0.10 m short after 0.5 s: a result, exit 1
    assert result["camera_frames"] == 7 and (tmp_path / "out").is_dir()


def test_the_installed_conformance_command_runs_its_suite_on_a_virtual_mcu(installed, tmp_path):
    _, bin_dir = installed
    usage = _run_installed(bin_dir, "mantaray", "conformance", "--help", cwd=tmp_path)
    assert usage.returncode == 0 and "--port" in usage.stdout, usage.stderr
    suite = _run_installed(bin_dir, "mantaray", "conformance", cwd=tmp_path)
    assert suite.returncode == 0, suite.stdout[-2000:] + suite.stderr
    assert " passed" in suite.stdout.splitlines()[-1] and "failed" not in suite.stdout.splitlines()[-1]
