"""Runs the libFuzzer target fuzz_decoder briefly on a seed corpus made from protocol/vectors.json."""

from __future__ import annotations

import json
import os
import re
import subprocess
from pathlib import Path

import pytest

from mantaray.paths import REPO

RUNS = 20000  # [inputs] at most ...
MAX_TOTAL_TIME = 15  # [s] ... and at most this long, so the test stays well under 30 s
MAX_LEN = 512  # [bytes] per input: a few dozen frames, more than any vector


def fuzz_build_dir() -> Path:
    """MANTARAY_FUZZ_BUILD_DIR if set, else build-fuzz/ in the repository."""
    return Path(os.environ.get("MANTARAY_FUZZ_BUILD_DIR", REPO / "build-fuzz"))


def write_seed_corpus(corpus: Path) -> int:
    """One file per vector's wire bytes, plus all of them back to back; returns the number of files."""
    vectors = json.loads((REPO / "protocol" / "vectors.json").read_text())["vectors"]
    corpus.mkdir(parents=True, exist_ok=True)
    everything = b""
    for i, vec in enumerate(vectors):
        wire = bytes.fromhex(vec["wire"])
        (corpus / f"vector_{i:02d}").write_bytes(wire)
        everything += wire
    (corpus / "all_vectors").write_bytes(everything)
    return len(vectors) + 1


def test_fuzz_decoder_runs_clean(tmp_path: Path) -> None:
    binary = fuzz_build_dir() / "fuzz_decoder"
    if not binary.exists():
        pytest.fail(
            f"{binary} does not exist; build the fuzzer with clang first: "
            f"CC=clang CXX=clang++ cmake -S {REPO} -B {binary.parent} -G Ninja && "
            f"ninja -C {binary.parent} fuzz_decoder (or set MANTARAY_FUZZ_BUILD_DIR)"
        )
    corpus = tmp_path / "corpus"
    seeds = write_seed_corpus(corpus)
    proc = subprocess.run(
        [
            str(binary),
            f"-runs={RUNS}",
            f"-max_total_time={MAX_TOTAL_TIME}",
            f"-max_len={MAX_LEN}",
            "-seed=1",
            "-timeout=10",
            "-print_final_stats=1",
            f"-artifact_prefix={tmp_path}/",
            str(corpus),
        ],
        capture_output=True,
        text=True,
        timeout=MAX_TOTAL_TIME + 45,
        cwd=tmp_path,
    )
    log = proc.stdout + proc.stderr
    crashes = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(("crash-", "leak-", "timeout-", "oom-")))
    assert proc.returncode == 0 and not crashes, (
        f"fuzz_decoder failed (exit {proc.returncode}, artifacts {crashes} in {tmp_path}):\n{log[-6000:]}"
    )
    assert "Done" in log, log[-3000:]
    # The seeds were all run and the fuzzer went on to mutate them.
    runs = re.search(r"stat::number_of_executed_units:\s*(\d+)", log)
    assert runs and int(runs.group(1)) > seeds, log[-3000:]
