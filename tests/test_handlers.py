"""Command handlers stay short: each reads as its command's steps, the work in named helpers (issue 42, item 7); the
simulation's settle their arguments into one frozen request instead of writing back into them (item 4)."""

from __future__ import annotations

import ast
import dataclasses

import pytest

from mantaray.paths import REPO

MAX_LINES = 45  # a handler's length, its signature and docstring included


def _handlers():
    """(file, name, lines) of every command handler: a host or top-level cmd_* function, a sim/cli/*.py run()."""
    files = [*(REPO / "host").glob("cli*.py"), REPO / "mantaray" / "cli.py", *(REPO / "sim" / "cli").glob("*.py")]
    for path in files:
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.FunctionDef) and (
                node.name.startswith("cmd_") or (path.parent == REPO / "sim" / "cli" and node.name == "run")
            ):
                assert node.end_lineno is not None
                yield path.relative_to(REPO), node.name, node.end_lineno - node.lineno + 1


def test_the_handlers_are_found():
    names = {(str(path), name) for path, name, _ in _handlers()}
    assert ("host/cli.py", "cmd_rig") in names and ("sim/cli/heatmap.py", "run") in names and len(names) >= 15


def test_no_command_handler_is_over_45_lines():
    long = [f"{path}:{name} ({lines} lines)" for path, name, lines in _handlers() if lines > MAX_LINES]
    assert not long, f"handlers over {MAX_LINES} lines: {', '.join(long)}"


SETTINGS = "docs/results/tune/sphere_cascade/settings.toml"  # it names its controller (cascade) and plant (paper)


def test_sim_run_and_heatmap_settle_their_defaults_in_a_request_and_leave_the_arguments_as_parsed(tmp_path):
    from mantaray.cli import build_parser
    from mantaray.sim.cli import heatmap, run

    for argv, build in (
        (["sim", "run", "--settings", SETTINGS, "--out", str(tmp_path)], run._trial),
        (["sim", "heatmap", "--settings", SETTINGS, "--cells", "2", "--trials", "1"], heatmap._experiment),
    ):
        parser = build_parser(argv)
        args = parser.parse_args(argv)
        parsed = dict(vars(args))
        request = build(args, parser)
        assert vars(args) == parsed, argv[1]
        assert (request.controller, request.plant) == ("cascade", "paper"), argv[1]
        with pytest.raises(dataclasses.FrozenInstanceError):
            request.controller = "manhattan"
