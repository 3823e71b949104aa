"""Progress of long runs: plain timestamped lines with an ETA when the output is not a terminal."""
from __future__ import annotations

import io
import re

from mantaray.sim.progress import Progress


def test_progress_to_a_log_prints_lines_with_the_count_and_what_is_left():
    out = io.StringIO()
    progress = Progress(4, initial=1, unit="candidate", label="calibrate", stream=out, line_every_s=0)
    progress.update(1, note="objectives 0.1")
    progress.update(2)
    progress.close()
    lines = out.getvalue().splitlines()
    assert len(lines) == 2
    assert re.match(r"\d\d:\d\d:\d\d calibrate: 2/4 candidates, about \d+ s left; objectives 0.1$", lines[0])
    assert "4/4 candidates" in lines[1]


def test_progress_lines_are_spaced_out_but_the_last_one_is_always_printed():
    out = io.StringIO()
    progress = Progress(50, unit="trial", stream=out, line_every_s=3600)
    for _ in range(50):
        progress.update()
    assert [line.split(" ", 1)[1] for line in out.getvalue().splitlines()][-1].startswith("50/50 trials")
    assert len(out.getvalue().splitlines()) == 2          # the first, then the last


def test_disabled_progress_prints_nothing():
    out = io.StringIO()
    progress = Progress(3, stream=out, enabled=False)
    progress.update(3)
    assert out.getvalue() == ""
