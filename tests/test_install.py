"""`pip install .` (not editable) gives a working mantaray outside the checkout: the wheel carries the native
firmware (built by scikit-build-core from CMakeLists.txt) and every data file the package reads."""
from __future__ import annotations

import json
import os
import site
import subprocess
import sys
import zipfile

import pytest

from mantaray.paths import REPO


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel built from this checkout and installed into a folder of its own: (wheel, site folder)."""
    root = tmp_path_factory.mktemp("install")
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(root / "dist"), str(REPO)], capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stderr
    (wheel,) = (root / "dist").glob("mantaray-*.whl")
    target = root / "site"
    install = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target),
                              str(wheel)], capture_output=True, text=True, timeout=300)
    assert install.returncode == 0, install.stderr
    return wheel, target


def _run_installed(target, *args: str, cwd) -> subprocess.CompletedProcess:
    """python -S: no site hooks, so the checkout's editable install cannot answer for the installed package; the
    dependencies come from this interpreter's site-packages, after the installed package."""
    env = {k: v for k, v in os.environ.items() if k not in ("MANTARAY_BUILD_DIR", "PYTHONPATH")}
    env["PYTHONPATH"] = os.pathsep.join([str(target), *site.getsitepackages()])
    return subprocess.run([sys.executable, "-S", *args], capture_output=True, text=True, timeout=300, cwd=cwd, env=env)


def test_the_wheel_carries_the_native_firmware_and_the_data_files(installed):
    wheel, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in ("mantaray/native/libmantaray_capi.so", "mantaray/native/mantaray-vmcu", "mantaray/protocol/schema.toml",
                 "mantaray/protocol/rig.toml", "mantaray/protocol/rig.py", "mantaray/sim/plant.toml",
                 "mantaray/sim/assets/bunny.obj", "mantaray/protocol/conformance/plugin.py"):
        assert name in names, name
    assert not any("__pycache__" in n for n in names)


def test_the_installed_package_runs_the_main_job_outside_the_checkout(installed, tmp_path):
    _, target = installed
    where = _run_installed(target, "-c", "import mantaray.paths as p, mantaray.sim.bridge as b; "
                           "print(p.native_artifact('libmantaray_capi.so')); print(b.__file__)", cwd=tmp_path)
    assert where.returncode == 0, where.stderr
    assert all(line.startswith(str(target)) for line in where.stdout.split())      # nothing from the checkout
    vmcu = _run_installed(target, "-m", "mantaray.cli", "vmcu", "--identify-only", cwd=tmp_path)
    assert vmcu.returncode == 0 and "matches this host" in vmcu.stdout, vmcu.stderr
    run = _run_installed(target, "-m", "mantaray.cli", "sim", "run", "--duration", "0.5", "--json", "--out",
                         str(tmp_path / "out"), cwd=tmp_path)
    result = json.loads(run.stdout.splitlines()[-1])
    assert run.returncode == 1 and not result["success"], run.stderr   # 0.10 m short after 0.5 s: a result, exit 1
    assert result["camera_frames"] == 7 and (tmp_path / "out").is_dir()
