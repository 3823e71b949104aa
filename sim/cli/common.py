"""What the simulation's command handlers (sim/cli_*.py) share: outputs checked, worker pools, interruptions."""

from __future__ import annotations

import argparse
import os
import signal
import sys
from pathlib import Path

from mantaray.outputs import OutputError


def output(parser: argparse.ArgumentParser, check, *args):
    """An output path checked before any work (mantaray.outputs); a bad one is a usage error."""
    try:
        return check(*args)
    except OutputError as exc:
        parser.error(str(exc))


def plant_for_settings(parser: argparse.ArgumentParser, settings, given: str | None) -> str:
    from ..model.plant import plant_for

    try:
        return plant_for(settings, given)
    except ValueError as exc:
        parser.error(str(exc))


def check_ray(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """--executor and --ray-address, before any work: Ray (and Ray Client, for a ray:// address) installed, the
    cluster's address answering; else one line and exit status 2."""
    from ..evaluation.executors import RayUnavailable, check_ray

    if args.ray_address and args.executor != "ray":
        parser.error("--ray-address needs --executor ray")
    if args.executor == "ray":
        try:
            check_ray(args.ray_address)
        except RayUnavailable as exc:
            parser.exit(2, f"{parser.prog}: {exc}\n")


def worker_pool(parser: argparse.ArgumentParser, args: argparse.Namespace):
    """The worker pool --executor asks for (checked by check_ray): this machine's processes (--jobs), or Ray (a
    cluster at --ray-address); a cluster that answers but not as Ray does is one line and exit status 2."""
    from ..evaluation.executors import LocalPool, RayPool, RayUnavailable

    if args.executor == "ray":
        try:
            return RayPool(args.jobs, args.ray_address)
        except RayUnavailable as exc:
            parser.exit(2, f"{parser.prog}: {exc}\n")
    return LocalPool(workers(args.jobs))


def candidates(study, out: Path, candidates: int, label: str):
    """The progress of a search toward `candidates`, saying so when it continues a study that holds some already."""
    from ..evaluation.progress import Progress
    from ..search.study import finished

    done = len(finished(study))
    if 0 < done < candidates:
        print(f"continuing {out / 'study.db'}: {done} of {candidates} candidates already evaluated", file=sys.stderr)
    return Progress(max(candidates, done), initial=done, unit="candidate", label=label, line_every_s=0)


def fidelity(parser: argparse.ArgumentParser, text: str):
    """A fidelity argument (fast, reference, RESOLUTION:TIMESTEP); a bad one is a usage error."""
    from ..evaluation.fidelity import parse_fidelity

    try:
        return parse_fidelity(text)
    except ValueError as exc:
        parser.error(str(exc))


def interruptible() -> None:
    """A long run ends as on Ctrl-C (what it did is kept, the same command continues it) on SIGINT, also when
    started in the background, where SIGINT comes ignored, and on SIGTERM (a stopped session's kill)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _interrupt)


def _interrupt(signum, frame) -> None:
    """SIGTERM as Ctrl-C."""
    raise KeyboardInterrupt


def workers(jobs: int | None) -> int:
    """--jobs as given, else every core."""
    return jobs or os.cpu_count() or 1


def load_results(parser: argparse.ArgumentParser, given: str, command: str):
    """The results file at given (or results.jsonl in the folder given), read whatever its protocol; its warnings
    printed; a missing or unreadable one is a usage error."""
    from ..evaluation.results_file import ResultsFile

    path = Path(given)
    path = path / "results.jsonl" if path.is_dir() else path
    if not path.exists():
        parser.error(f"no heatmap results at {given}")
    try:
        results = ResultsFile.load(path)
    except ValueError as exc:
        parser.error(str(exc))
    for warning in results.warnings():
        print(f"mantaray sim {command}: warning: {warning}", file=sys.stderr)
    return results
