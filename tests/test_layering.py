"""The packages' layering: the protocol needs nothing of ours, the host never needs the simulation (or MuJoCo)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from mantaray.paths import REPO

# package folder -> the mantaray packages its modules may import (besides itself); the conformance suite is a client
# of the protocol through the host's link. The top-level modules (mantaray/*.py: paths, outputs, plots, arguments)
# are the bottom layer every package may use, and import none of ours; mantaray/cli.py, the entry point, is the top.
ALLOWED = {
    "mantaray": set(),
    "protocol": set(),
    "protocol/conformance": {"protocol", "host"},
    "host": {"protocol"},
    "sim": {"protocol", "host"},
}
PACKAGE_OF = {"mantaray": "", "protocol": "protocol", "protocol/conformance": "protocol", "host": "host", "sim": "sim"}
ENTRY_POINT = "mantaray/cli.py"  # the command line: it builds every package's parsers, so it may import them all
BOTTOM = {f"mantaray.{path.stem}" for path in (REPO / "mantaray").glob("*.py")} - {"mantaray.__init__", "mantaray.cli"}
# sim/'s sub-packages along its flow (sim/README.md, Layout): each may import those before it, never one after
SIM_LAYERS = ("model", "trial", "evaluation", "search", "cli")


def _imports(path: Path) -> set[str]:
    """The absolute module names a file imports (relative imports are its own package)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


@pytest.mark.parametrize("folder", sorted(ALLOWED))
def test_each_package_imports_only_the_layers_below_it(folder):
    own = PACKAGE_OF[folder]
    offending = []
    for path in sorted((REPO / folder).rglob("*.py") if folder == "sim" else (REPO / folder).glob("*.py")):
        if path.relative_to(REPO).as_posix() == ENTRY_POINT:
            continue
        for name in _imports(path):
            parts = name.split(".")
            if parts[0] in ("mujoco", "ray", "optuna") and own != "sim":
                offending.append((path.name, name))
            if parts[0] == "mantaray" and len(parts) > 1 and name not in BOTTOM:
                if parts[1] != own and parts[1] not in ALLOWED[folder]:
                    offending.append((path.name, name))
    assert offending == []


def _resolved_imports(path: Path) -> set[str]:
    """The module names a file of sim/ imports, its relative imports made absolute (mantaray.sim.<layer>...)."""
    package = ["mantaray", *path.parent.relative_to(REPO).parts]
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            names.add(".".join([*base, *([node.module] if node.module else [])]))
    return names


def test_the_sim_layers_import_only_the_layers_before_them():
    layers = {name: i for i, name in enumerate(SIM_LAYERS)}
    assert {p.name for p in (REPO / "sim").iterdir() if p.is_dir() and (p / "__init__.py").exists()} == set(layers)
    offending = []
    for own in SIM_LAYERS:
        for path in sorted((REPO / "sim" / own).glob("*.py")):
            for name in _resolved_imports(path):
                parts = name.split(".")
                if parts[:2] == ["mantaray", "sim"] and len(parts) > 2 and layers.get(parts[2], -1) > layers[own]:
                    offending.append((f"{own}/{path.name}", name))
    assert offending == []


def test_the_entry_point_loads_the_packages_only_inside_the_commands_that_need_them():
    """mantaray/cli.py imports no package at module level: `mantaray --help` and a rig's command stay light."""
    tree = ast.parse((REPO / ENTRY_POINT).read_text())
    top = [node for node in tree.body if isinstance(node, (ast.Import, ast.ImportFrom))]
    assert not [
        node.module for node in top if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mantaray")
    ]


def test_the_rig_command_runs_without_loading_the_simulation(tmp_path):
    """The rig's figure and command line load no physics engine: what a rig owner without MuJoCo would run."""
    code = (
        "import sys, numpy as np\n"
        "from mantaray.cli import build_parser\n"
        "from mantaray.plots import path_phase_figure\n"
        "import mantaray.host.cli, mantaray.host.session, mantaray.host.tracker\n"
        "argv = ['rig', '--port', '/dev/null', '--camera', '0', '--target', '0,0']\n"
        "build_parser(argv).parse_args(argv)\n"
        "path_phase_figure(np.zeros((3, 2)), np.zeros((3, 2)), (0, 0), [(0.1, 0)], 0.02, 't', (0.5, 0.5), 26.6,"
        " sys.argv[1])\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'mujoco' or m.startswith('mantaray.sim')))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path / "figure.png")], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
