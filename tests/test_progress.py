"""Progress of long runs: plain timestamped lines with an ETA when the output is not a terminal."""

from __future__ import annotations

import io
import re

from mantaray.sim.evaluation.progress import Progress


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
    assert len(out.getvalue().splitlines()) == 2  # the first, then the last


def test_disabled_progress_prints_nothing():
    out = io.StringIO()
    progress = Progress(3, stream=out, enabled=False)
    progress.update(3)
    assert out.getvalue() == ""


def test_a_quantity_such_as_simulated_time_prints_with_its_own_units():
    out = io.StringIO()
    progress = Progress(2.0, unit="sim s", units="simulated s", label="sim run", stream=out, line_every_s=0)
    for t_s in (0.5, 1.25, 2.0):
        progress.update(t_s - progress.done)
    lines = out.getvalue().splitlines()
    assert [line.split(" ", 1)[1].split(",")[0] for line in lines] == [
        "sim run: 0.5/2.0 simulated s",
        "sim run: 1.2/2.0 simulated s",
        "sim run: 2.0/2.0 simulated s",
    ]


def test_sim_run_prints_progress_lines_when_its_output_goes_to_a_log(tmp_path):
    import subprocess
    import sys

    run = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "run", "--duration", "0.5", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 1, run.stderr  # 0.5 s is too short to get there: a result
    assert re.search(r"^\d\d:\d\d:\d\d sim run: 0\.5/0\.5 simulated s", run.stderr, re.MULTILINE), run.stderr
    assert run.stdout.startswith("NOT WITHIN ε AT T: sphere, manhattan, polyester plant"), run.stdout  # the result
