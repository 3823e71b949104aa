"""The heatmap evaluation: sampling of starts and targets, the success rule, resumption, executors, CLI end to end."""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.host.link import Link
from mantaray.host.transport import InProcessTransport, SerialTransport
from mantaray.host.vmcu import VirtualMcu
from mantaray.paths import REPO
from mantaray.sim.evaluation import executors as X
from mantaray.sim.evaluation import experiment as E
from mantaray.sim.evaluation import results_file as R
from mantaray.sim.evaluation import summary as S
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.bridge import Bridge, TrialSpec, is_success

MODULE = (0.5, 0.5)
SMALL = E.Experiment(
    cells=2, trials_per_cell=2, duration_s=0.5, resolution=11, timestep_s=0.002
)  # four cells, eight short trials, on a cheap mesh: these test the mechanics


# ------------------------------------------------------------------------------------------- sampling
@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), cells=st.integers(1, 40), data=st.data())
def test_targets_lie_in_their_cell_and_starts_on_the_workspace(seed, cells, data):
    experiment = E.Experiment(cells=cells, seed=seed)
    cell = data.draw(st.integers(0, cells**2 - 1))
    k = data.draw(st.integers(0, 50))
    trial = E.make_trial(experiment, MODULE, cell, k)
    x_lo, x_hi, y_lo, y_hi = E.cell_bounds(experiment, MODULE, cell)
    assert x_lo <= trial.target_m[0] <= x_hi and y_lo <= trial.target_m[1] <= y_hi
    assert all(abs(v) <= 0.25 for v in trial.start_m)
    assert trial == E.make_trial(experiment, MODULE, cell, k)  # from (seed, cell, k) alone


def test_cells_tile_the_workspace_in_x_then_y():
    experiment = E.Experiment()
    assert E.cell_bounds(experiment, MODULE, 0) == pytest.approx((-0.25, -0.225, -0.25, -0.225))
    assert E.cell_bounds(experiment, MODULE, 1) == pytest.approx((-0.225, -0.2, -0.25, -0.225))
    assert E.cell_bounds(experiment, MODULE, 20) == pytest.approx((-0.25, -0.225, -0.225, -0.2))
    assert E.cell_bounds(experiment, MODULE, 399) == pytest.approx((0.225, 0.25, 0.225, 0.25))


def test_starts_are_uniform_over_the_workspace_and_the_seed_decides_them():
    experiment = E.Experiment()  # the paper's 4,000 trials
    starts = np.array([t.start_m for t in E.trials(experiment)])
    assert len(starts) == 4000
    counts, _, _ = np.histogram2d(starts[:, 0], starts[:, 1], bins=4, range=[[-0.25, 0.25], [-0.25, 0.25]])
    assert counts.min() > 250 - 4 * np.sqrt(250) and counts.max() < 250 + 4 * np.sqrt(250)  # 16 bins of 250
    again = np.array([t.start_m for t in E.trials(E.Experiment())])
    other = np.array([t.start_m for t in E.trials(E.Experiment(seed=7))])
    assert np.array_equal(starts, again) and not np.array_equal(starts, other)


def test_a_subset_of_cells_draws_the_same_trials_as_the_full_run():
    full = {t.key: t for t in E.trials(E.Experiment())}
    subset = E.trials(E.Experiment(only_cells=(210, 3)))
    assert [t.key for t in subset] == [f"{c}:{k}" for c in (210, 3) for k in range(10)]
    assert all(full[t.key] == t for t in subset)


@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"cells": 0}, "cells per side"),
        ({"controller": "pid"}, "controller"),
        ({"object_name": "teapot"}, "object"),
        ({"tolerance_m": 0}, "tolerance"),
        ({"duration_s": -1}, "runtime"),
        ({"settings": (("pid.x.kd", float("nan")),)}, "kd"),
        ({"resolution": 14}, "odd"),
        ({"only_cells": (400,)}, "cell indices"),
        ({"timestep_s": 0.1}, "timestep"),
        # the schema's bounds (protocol/schema.toml), not retyped here: epsilon from 1 mm, alpha to 0.25 m, gains to 1e4
        ({"tolerance_m": 0.0005}, r"tolerance epsilon: 0.0005 m is outside 0.001..0.5 m"),
        ({"alpha_m": 0.3}, "noise_amplitude"),
        ({"settings": (("pid.x.kp", 2e4),)}, r"pid.x.kp: 20000 deg/m is outside 0..10000"),
        ({"only_cells": (1, 1)}, "must not repeat"),
        ({"seed": -1}, "seed"),
    ],
)
def test_a_bad_protocol_is_refused_with_a_reason(kwargs, needle):
    with pytest.raises(ValueError, match=needle):
        E.Experiment(**kwargs)


def test_a_results_header_with_gains_apart_from_the_settings_is_refused_and_a_null_one_read():
    """Headers written before --gains became settings keys: gains null (every committed file) reads as before; gains
    given were the paper's units, which a run today would not reproduce."""
    header = E.Experiment(cells=2).to_json()
    assert E.Experiment.from_json({**header, "gains": None}) == E.Experiment(cells=2)
    with pytest.raises(ValueError, match="paper's units"):
        E.Experiment.from_json({**header, "gains": [30.9, 26.78, 15.45, 26.5]})


# ------------------------------------------------------------------------------------------- success rule
def test_success_needs_the_end_within_tolerance_and_no_fall():
    assert is_success(False, 0.019, 0.02)
    assert not is_success(False, 0.02, 0.02)
    assert not is_success(True, 0.0, 0.02)  # within tolerance but fallen off: a failure


def _record(cell: int, k: int, success: bool, reached: bool = False, fell: bool = False) -> dict:
    return {
        "key": f"{cell}:{k}",
        "cell": cell,
        "k": k,
        "success": success,
        "reached": reached or success,
        "fell_off": fell,
    }


def test_summary_rates_score_and_regions():
    results = R.ResultsFile(path=None, experiment=E.Experiment(cells=2, trials_per_cell=10))
    for k in range(10):
        results.records[f"0:{k}"] = _record(0, k, success=True)  # cell 0: 100 %
        results.records[f"1:{k}"] = _record(1, k, success=k < 5, fell=k >= 8)  # cell 1: 50 %, 20 % fell
        results.records[f"2:{k}"] = _record(2, k, success=False, reached=k == 0)  # cell 2: 0 %, reached 10 %
    s = S.summarize(results)  # cell 3 never ran
    assert s.rates[0, 0] == 1.0 and s.rates[0, 1] == 0.5 and s.rates[1, 0] == 0.0 and np.isnan(s.rates[1, 1])
    assert s.fell_rates[0, 1] == pytest.approx(0.2) and s.reach_rates[1, 0] == pytest.approx(0.1)
    assert s.score == pytest.approx(1.5) and s.reach_score == pytest.approx(1.6) and s.trials == 30
    assert s.trials_per_cell.tolist() == [[10, 10], [10, 0]]
    assert s.region_cells == {"success": 1, "uncertain": 1, "failure": 1}
    assert s.region_area_m2("success") == pytest.approx(0.0625)  # a quarter of 0.25 m^2


# ------------------------------------------------------------------------------------------- results file, resumption
def test_an_interrupted_run_continues_where_it_stopped_and_loses_nothing(tmp_path):
    reference = R.ResultsFile.open(tmp_path / "whole.jsonl", SMALL)
    X.run(reference, X.run_local(SMALL, reference.missing(), jobs=1))

    path = tmp_path / "interrupted.jsonl"
    first = R.ResultsFile.open(path, SMALL)

    def interrupted():
        for i, record in enumerate(X.run_local(SMALL, first.missing(), jobs=1)):
            if i == 3:
                raise KeyboardInterrupt
            yield record

    with pytest.raises(KeyboardInterrupt):
        X.run(first, interrupted())
    with open(path, "a") as f:
        f.write('{"key": "3:1", "cell": 3, "k"')  # a line the interruption cut off
    again = R.ResultsFile.open(path, SMALL)
    assert len(again.records) == 3 and len(again.missing()) == 5
    X.run(again, X.run_local(SMALL, again.missing(), jobs=1))
    final = R.ResultsFile.load(path)
    assert len(final.records) == 8 and not R.ResultsFile.open(path, SMALL).missing()
    for key, record in reference.records.items():  # the same trials, the same outcomes, to the digit
        assert {k: v for k, v in final.records[key].items() if k not in R.WALL_CLOCK_FIELDS} == {
            k: v for k, v in record.items() if k not in R.WALL_CLOCK_FIELDS
        }
    assert len(path.read_text().splitlines()) == 9  # header + 8 trials: nothing twice, the cut line gone


def test_more_trials_or_cells_on_the_same_file_keep_the_trials_there_and_add_the_rest(tmp_path):
    path = tmp_path / "grown.jsonl"
    one_cell = dataclasses.replace(SMALL, trials_per_cell=1, only_cells=(2,))
    first = R.ResultsFile.open(path, one_cell)
    X.run(first, X.run_local(one_cell, first.missing(), jobs=1))
    (kept,) = first.records.values()
    grown = R.ResultsFile.open(path, SMALL)
    assert grown.records == first.records and len(grown.missing()) == 7
    assert R.ResultsFile.load(path).experiment == SMALL  # the header names the larger run now
    X.run(grown, X.run_local(SMALL, grown.missing(), jobs=1))
    final = R.ResultsFile.load(path)
    assert len(final.records) == 8 and final.records[kept["key"]] == kept
    with pytest.raises(E.ExperimentMismatch, match="trials_per_cell"):  # fewer trials would drop some: refused
        R.ResultsFile.open(path, one_cell)


def test_a_results_file_of_other_options_is_not_continued(tmp_path):
    R.ResultsFile.open(tmp_path / "r.jsonl", SMALL)
    with pytest.raises(E.ExperimentMismatch, match="duration_s"):
        R.ResultsFile.open(tmp_path / "r.jsonl", E.Experiment(cells=2, trials_per_cell=2, duration_s=1.0))
    (tmp_path / "other.jsonl").write_text("not json\n")
    with pytest.raises(ValueError, match="not a heatmap results file"):
        R.ResultsFile.open(tmp_path / "other.jsonl", SMALL)


def _synthetic_file(path: Path, experiment: E.Experiment, lines: list[str]) -> None:
    """A results file of this protocol with these trial lines (no simulation)."""
    R.ResultsFile.open(path, experiment)
    with open(path, "a") as f:
        f.write("".join(line + "\n" for line in lines))


def _line(cell: int, k: int, **fields) -> str:
    record = {
        "key": f"{cell}:{k}",
        "cell": cell,
        "k": k,
        "success": True,
        "reached": True,
        "fell_off": False,
        "target_m": [0.0, 0.0],
        **fields,
    }
    return json.dumps(record)


@pytest.mark.parametrize(
    "bad, why",
    [
        ("{}", "no 'key' field"),
        ('{"key": "1:0", "cell": 1', "not JSON"),
        ("[1, 2]", "a JSON list"),
        (_line(1, 0, success=7), "success must be true or false, got 7"),
        (json.dumps({**json.loads(_line(1, 0)), "cell": "1"}), "cell must be a whole number, got '1'"),
        (_line(9, 0), "trial 9:0 is not one of this run's"),
        (_line(1, 0, key="0:0"), "does not match"),
        (_line(0, 0), "repeats trial 0:0"),
    ],
)
def test_a_bad_line_in_the_middle_is_named_kept_aside_and_loses_no_later_trial(tmp_path, bad, why):
    path = tmp_path / "results.jsonl"
    _synthetic_file(path, SMALL, [_line(0, 0), bad, _line(2, 1), _line(3, 0)])
    loaded = R.ResultsFile.load(path)
    assert sorted(loaded.records) == ["0:0", "2:1", "3:0"]  # the trials after the bad line still count
    assert [line for line, _ in loaded.rejected] == [3]
    assert why in loaded.rejected[0][1] and "line 3" in loaded.warnings()[0]
    continued = R.ResultsFile.open(path, SMALL)  # continuing moves the line aside, never drops it
    assert sorted(continued.records) == ["0:0", "2:1", "3:0"] and len(continued.missing()) == 5
    assert (tmp_path / "results.jsonl.rejected").read_text() == bad + "\n"
    assert len(path.read_text().splitlines()) == 4 and R.ResultsFile.load(path).rejected == []  # header + 3


def test_a_header_cut_off_as_the_run_began_starts_the_run_afresh(tmp_path):
    path = tmp_path / "results.jsonl"
    R.ResultsFile.open(path, SMALL)
    header = path.read_bytes()
    for cut in (0, 5, len(header) // 2, len(header) - 1):  # every way the first write can be cut
        path.write_bytes(header[:cut])
        with pytest.raises(ValueError, match="no complete header line"):
            R.ResultsFile.load(path)
        again = R.ResultsFile.open(path, SMALL)
        assert again.records == {} and path.read_bytes() == header
    path.write_bytes(b"something else entirely")  # not ours: refused, not overwritten
    with pytest.raises(ValueError, match="not a heatmap results file"):
        R.ResultsFile.open(path, SMALL)
    assert path.read_bytes() == b"something else entirely"


_HOLD = (
    "import json, sys; from mantaray.sim.evaluation import experiment as E, results_file as R; "
    "R.ResultsFile.open(sys.argv[1], E.Experiment.from_json(json.loads(sys.argv[2]))); print('open', flush=True); "
    "sys.stdin.read()"
)  # a run that holds a results file until it is killed


def test_a_results_file_is_continued_by_one_process_at_a_time_and_a_killed_ones_lock_is_gone(tmp_path):
    path = tmp_path / "results.jsonl"
    holder = subprocess.Popen(
        [sys.executable, "-c", _HOLD, str(path), json.dumps(SMALL.to_json())],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline() == "open\n"
        before = path.read_bytes()
        with pytest.raises(R.ResultsFileBusy, match=f"PID {holder.pid}: "):
            R.ResultsFile.open(path, SMALL)
        second = _cli(
            "heatmap",
            "--cells",
            "2",
            "--trials",
            "2",
            "--duration",
            "0.5",
            "--resolution",
            "11",
            "--timestep",
            "0.002",
            "--jobs",
            "1",
            "--out",
            str(tmp_path),
        )
        assert second.returncode == 2
        (line,) = second.stderr.splitlines()
        assert line.startswith(f"mantaray sim heatmap: {path} is being continued by another run (PID {holder.pid}: ")
        assert path.read_bytes() == before
    finally:
        holder.kill()  # as a run killed mid-way: the kernel drops its lock, its file stays
        holder.wait()
    lock_file = path.with_name("results.jsonl.lock")
    assert lock_file.exists()
    after = subprocess.run(
        [sys.executable, "-c", _HOLD, str(path), json.dumps(SMALL.to_json())],
        input="",
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert after.stdout == "open\n" and not lock_file.exists()  # taken, and removed by a run that ends
    assert not R.ResultsFile.open(path, SMALL).records
    other = R.ResultsFile.open(tmp_path / "other.jsonl", SMALL)  # one process holds several files, and one twice
    assert R.ResultsFile.open(path, SMALL).missing() == other.missing()


def _compare(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "compare", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_compare_refuses_runs_that_measure_success_differently_and_warns_of_incomplete_ones(tmp_path):
    full = [_line(c, k, success=c % 2 == 0) for c in range(4) for k in range(2)]
    _synthetic_file(tmp_path / "a.jsonl", SMALL, full)
    _synthetic_file(tmp_path / "b.jsonl", dataclasses.replace(SMALL, controller="euclidean"), full[:5])
    _synthetic_file(tmp_path / "t1.jsonl", dataclasses.replace(SMALL, duration_s=1.0), full)
    _synthetic_file(
        tmp_path / "none.jsonl",
        dataclasses.replace(SMALL, controller="euclidean"),
        [_line(c, k, success=False, reached=False) for c in range(4) for k in range(2)],
    )
    ok = _compare("a.jsonl", "b.jsonl", "--out", "d.png", cwd=tmp_path)
    assert ok.returncode == 0 and "b.jsonl is incomplete (3 of 8 trials not run)" in ok.stderr, ok.stderr
    assert (tmp_path / "d.png").stat().st_size > 0
    zero = _compare("a.jsonl", "none.jsonl", "--out", "z.png", cwd=tmp_path)
    assert zero.returncode == 0 and "difference +2.0;" in zero.stdout and "%" not in zero.stdout  # no x / 0
    for args, needle in [
        (("a.jsonl", "t1.jsonl", "--out", "d.png"), "duration_s 0.5 against 1.0"),
        (("a.jsonl", "b.jsonl", "--out", "d.txt"), "the file type must be one of .png, .pdf, .svg"),
    ]:
        bad = _compare(*args, cwd=tmp_path)
        assert bad.returncode == 2 and needle in bad.stderr and "Traceback" not in bad.stderr, bad.stderr
    assert not (tmp_path / "d.txt").exists()


# ------------------------------------------------------------------------------------------- the in-process core
def test_in_process_core_gives_the_same_commands_as_the_virtual_mcu_over_the_pty():
    spec = TrialSpec((0.08, -0.06), (-0.05, 0.04), duration_s=3.0, alpha_m=0.03, seed=11)
    with VirtualMcu(clock="sim") as vmcu:
        over_pty = Bridge(Link(SerialTransport(vmcu.path)), Rig()).run(spec)
    in_process = Bridge(Link(InProcessTransport(simulated_clock=True)), Rig()).run(spec)
    assert len(over_pty.command_m) == 37 and np.all(np.isfinite(over_pty.command_m))
    assert np.array_equal(over_pty.command_m, in_process.command_m)
    assert np.array_equal(over_pty.tilt_deg, in_process.tilt_deg)
    assert np.array_equal(over_pty.true_xy_m, in_process.true_xy_m)


def test_ray_runs_the_same_trials_as_local_processes():
    todo = E.trials(SMALL)
    local = {r["key"]: r for r in X.run_local(SMALL, todo, jobs=2)}
    on_ray = {r["key"]: r for r in X.run_ray(SMALL, todo, jobs=2, address=None)}
    assert local.keys() == on_ray.keys() == {t.key for t in todo}
    for key in local:
        assert local[key]["final_m"] == on_ray[key]["final_m"] and local[key]["success"] == on_ray[key]["success"]


@pytest.mark.parametrize("offset_m", [0.01, 0.05])  # within eps at the start; a short way off
def test_a_trial_stopped_at_reach_records_where_it_was_judged_in_strict_json(offset_m):
    experiment = E.Experiment(cells=2, trials_per_cell=1, duration_s=3.0, stop_when_reached=True)
    start = (0.02, -0.03)
    trial = E.Trial(cell=0, k=0, start_m=start, target_m=(start[0] + offset_m, start[1]), seed=5)
    record = json.loads(json.dumps(R.trial_record(trial, X.TrialRunner(experiment).result(trial)), allow_nan=False))
    assert record["reached"] and record["success"]
    error_m = np.hypot(*(np.subtract(record["final_m"], record["target_m"])))
    assert error_m == pytest.approx(record["final_error_m"], abs=2e-5) and error_m < experiment.tolerance_m


def _runner_kind_and_double(runner, x):
    return type(runner).__name__, 2 * x


@pytest.mark.parametrize("pool", ["local", "ray"])
def test_any_job_runs_on_the_pools_own_trial_runners_in_order_and_a_ray_the_pool_started_ends_with_it(pool):
    if pool == "ray":  # Ray's workers cannot import this test module: send the function by value
        from ray import cloudpickle

        cloudpickle.register_pickle_by_value(sys.modules[__name__])
    with X.LocalPool(2) if pool == "local" else X.RayPool(2, None) as workers:
        assert workers.map_calls(_runner_kind_and_double, [1, 2, 3, 4]) == [
            ("TrialRunner", 2 * x) for x in (1, 2, 3, 4)
        ]
    if pool == "ray":  # the Ray instance the pool started ends with it, not with this process
        import ray

        assert not ray.is_initialized()


# ------------------------------------------------------------------------------------------- CLI end to end
def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", *args], cwd=REPO, capture_output=True, text=True, timeout=600
    )


def test_reduced_heatmap_end_to_end_with_figures_and_difference_map(tmp_path):
    runs = {}
    for controller in ("manhattan", "euclidean"):
        out = tmp_path / controller
        proc = _cli(
            "heatmap",
            "--controller",
            controller,
            "--cells",
            "3",
            "--trials",
            "1",
            "--duration",
            "2",
            "--only-cells",
            "3,4,5",
            "--jobs",
            "2",
            "--json",
            "--out",
            str(out),
        )
        assert proc.returncode == 0, proc.stderr
        summary = json.loads(proc.stdout)
        assert summary["trials"] == 3 and summary["cells_run"] == 3
        assert sum(r["cells"] for r in summary["regions"].values()) == 3
        lines = (out / "results.jsonl").read_text().splitlines()
        assert len(lines) == 4
        for record in map(json.loads, lines[1:]):
            assert set(record) >= {"start_m", "target_m", "final_m", "success", "fell_off", "reached"}
        cells = (out / "cells.csv").read_text().splitlines()
        assert cells[0].startswith("cell,ix,iy") and len(cells) == 4
        assert (out / "heatmap.png").stat().st_size > 10_000 and (out / "heatmap_reach.png").stat().st_size > 10_000
        runs[controller] = summary
    again = _cli(
        "heatmap",
        "--cells",
        "3",
        "--trials",
        "1",
        "--duration",
        "2",
        "--only-cells",
        "3,4,5",
        "--json",
        "--out",
        str(tmp_path / "manhattan"),
    )
    assert again.returncode == 0 and "3 of 3 trials already done" in again.stderr
    proc = _cli("compare", str(tmp_path / "euclidean"), str(tmp_path / "manhattan"), "--out", str(tmp_path / "d.png"))
    assert proc.returncode == 0, proc.stderr
    assert "difference" in proc.stdout and (tmp_path / "d.png").stat().st_size > 10_000
    proc = _cli(
        "compare",
        str(tmp_path / "euclidean"),
        str(tmp_path / "manhattan"),
        "--reached",
        "--out",
        str(tmp_path / "r.png"),
    )
    assert proc.returncode == 0 and "within ε at any frame" in proc.stdout and (tmp_path / "r.png").exists()


def test_ctrl_c_on_a_parallel_run_says_how_to_continue_without_a_traceback(tmp_path):
    out = tmp_path / "run"
    # 160 trials of 10 s (minutes of work): far more than can finish between the first result and the signal
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "heatmap",
            "--cells",
            "4",
            "--trials",
            "10",
            "--duration",
            "10",
            "--jobs",
            "2",
            "--out",
            str(out),
        ],
        cwd=REPO,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        start_new_session=True,
    )
    deadline = time.monotonic() + 120
    while (
        time.monotonic() < deadline
        and len((out / "results.jsonl").read_text().splitlines() if (out / "results.jsonl").exists() else []) < 2
    ):
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "the same command continues the run" in stderr
    assert "Traceback" not in stderr, stderr
    assert 1 <= len((out / "results.jsonl").read_text().splitlines()) - 1 < 160  # stopped mid-run, trials kept


@pytest.mark.parametrize(
    "args, needle",
    [
        (("--cells", "0"), "cells per side"),
        (("--gains", "1,x,2"), "expected KP,KI,KD"),
        (("--resolution", "14"), "odd"),
        (("--jobs", "0"), "--jobs"),
        (("--only-cells", "a"), "expected cell indices"),
    ],
)
def test_heatmap_refuses_bad_input_in_one_line(args, needle):
    proc = _cli("heatmap", *args)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and needle in proc.stderr


def test_heatmap_refuses_to_mix_two_experiments_in_one_results_file(tmp_path):
    first = _cli("heatmap", "--cells", "1", "--trials", "1", "--duration", "0.2", "--jobs", "1", "--out", str(tmp_path))
    assert first.returncode == 0, first.stderr
    proc = _cli("heatmap", "--cells", "1", "--trials", "1", "--duration", "0.3", "--jobs", "1", "--out", str(tmp_path))
    assert proc.returncode == 2 and "duration_s" in proc.stderr and "Traceback" not in proc.stderr


def test_a_results_file_of_a_plant_whose_values_changed_is_not_continued(tmp_path):
    path = tmp_path / "results.jsonl"
    R.ResultsFile.open(path, SMALL)
    header = json.loads(path.read_text().splitlines()[0])
    assert header["plant_values"]["fabric.size_m"] == SMALL.plant_model().values["fabric.size_m"]
    header["plant_values"]["fabric.size_m"] = 0.51  # as if sim/model/plant.toml had been refitted since
    path.write_text(json.dumps(header) + "\n")
    with pytest.raises(E.ExperimentMismatch, match="fabric.size_m differ"):
        R.ResultsFile.open(path, SMALL)


def test_a_physics_that_cannot_be_integrated_ends_the_run_in_one_line_naming_the_parameter(tmp_path):
    """A 10 ms step on a 21 x 21 sheet diverges while the sheet settles: the command says which constraint is too
    stiff for the step, keeps the results file, and prints no traceback."""
    out = tmp_path / "unstable"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "heatmap",
            "--cells",
            "1",
            "--trials",
            "1",
            "--duration",
            "0.5",
            "--resolution",
            "21",
            "--timestep",
            "0.01",
            "--jobs",
            "1",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 1
    assert "fabric.edge_solref[0]" in run.stderr and "Traceback" not in run.stderr, run.stderr
    assert (out / "results.jsonl").exists()


def test_a_gzipped_results_file_opens_for_comparison_but_is_not_continued(tmp_path):
    import gzip

    experiment = E.Experiment(cells=2, trials_per_cell=1, duration_s=0.5)
    plain = tmp_path / "results.jsonl"
    R.ResultsFile.open(plain, experiment)
    packed = tmp_path / "results.jsonl.gz"
    packed.write_bytes(gzip.compress(plain.read_bytes()))
    assert R.ResultsFile.load(packed).experiment == experiment
    with pytest.raises(ValueError, match="gunzip it first"):
        R.ResultsFile.open(packed, experiment)
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "compare",
            str(packed),
            str(plain),
            "--out",
            str(tmp_path / "d.png"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr


def test_a_results_header_without_its_protocol_says_so(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_text(json.dumps({"format": R.RESULTS_FORMAT}) + "\n")
    with pytest.raises(ValueError, match="names no protocol"):
        R.ResultsFile.load(path)
