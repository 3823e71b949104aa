"""Committed trials: a run's results file kept gzipped in docs/results/, which a run starts from and writes back to."""

from __future__ import annotations

import gzip
from pathlib import Path

from .results_file import write_whole


def trials_in(results_path: Path) -> int:
    """How many trials a results file holds."""
    return trial_count(results_path.read_bytes()) if results_path.exists() else 0


def trial_count(text: bytes) -> int:
    """How many trials a results file's text holds: its lines after the header."""
    return max(len(text.splitlines()) - 1, 0)


def restore(results_path: Path, committed: Path) -> bool:
    """Start a run from its committed trials (docs/results/<run>.jsonl.gz) when out/ has none; whether it did."""
    if results_path.exists() or not committed.exists():
        return False
    results_path.parent.mkdir(parents=True, exist_ok=True)
    results_path.write_bytes(gzip.decompress(committed.read_bytes()))
    return True


def keep(results_path: Path, committed: Path) -> int:
    """Write every trial out/ holds back to docs/results/<run>.jsonl.gz (whole: an interruption leaves the old file
    or the new); returns how many trials it holds."""
    trials = results_path.read_bytes() if results_path.exists() else b""
    if trials and (not committed.exists() or gzip.decompress(committed.read_bytes()) != trials):
        committed.parent.mkdir(parents=True, exist_ok=True)
        write_whole(committed, gzip.compress(trials, mtime=0))
    return trial_count(trials)
