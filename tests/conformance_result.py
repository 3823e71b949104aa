"""Judging a run of the conformance suite: it passed, against the clock it names, and skipped only the other clock's tests."""

from __future__ import annotations

import re
import subprocess

OTHER = {"simulated": "wall", "wall": "simulated"}


def assert_suite_passed(result: subprocess.CompletedProcess, clock: str) -> None:
    """The run (with pytest's -rs) passed, ran against a firmware with this clock, and every skip is a test for the
    other clock: a test that skipped for any other reason would hide a failure behind "N passed"."""
    out = result.stdout
    summary = out.strip().splitlines()[-1] if out.strip() else ""
    assert result.returncode == 0, f"conformance suite failed ({clock} clock):\n{out[-6000:]}\n{result.stderr}"
    assert re.search(r"\d+ passed", summary) and not re.search(r"\d+ (failed|errors?|xfailed|xpassed)\b", summary), (
        summary
    )
    assert f"clock {clock}" in out  # the suite really ran against a firmware with that clock
    skipped = re.search(r"(\d+) skipped", summary)
    reasons = re.findall(r"^SKIPPED \[(\d+)\] [^:]+:\d+: (.*)$", out, flags=re.MULTILINE)
    expected = f"needs a firmware with the {OTHER[clock]} clock; this one has the {clock} clock"
    assert all(reason == expected for _, reason in reasons), reasons
    assert sum(int(n) for n, _ in reasons) == (int(skipped.group(1)) if skipped else 0), (summary, reasons)
