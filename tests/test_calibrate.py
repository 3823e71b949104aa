"""`mantaray sim calibrate`: the search space honours the declared ranges, a tiny search resumes after an interruption,
the log evidence recovers what wrote the log."""

from __future__ import annotations

import json
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import optuna
import pytest

from mantaray.host.link import Link
from mantaray.host.runlog import RunLogError, read_run_log
from mantaray.host.transport import InProcessTransport
from mantaray.paths import REPO
from mantaray.sim.evaluation.executors import LocalPool
from mantaray.sim.model import parameters as P
from mantaray.sim.model.plant import Plant
from mantaray.sim.search import calibrate as C
from mantaray.sim.search import logfit as L
from mantaray.sim.search import study as S
from mantaray.sim.trial.bridge import Bridge, TrialSpec

FAST = {"resolution": 11, "timestep_s": 0.002}
TINY = [
    "--params",
    "contact.rolling_damping_per_s,fabric.size_m",
    "--cells-per-stratum",
    "1",
    "--trials-per-cell",
    "1",
    "--duration",
    "0.6",
    "--jobs",
    "1",
    "--seed",
    "5",
    "--resolution",
    "11",
    "--timestep",
    "0.002",
]


def _cli(*args: str, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "calibrate", *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
        **kwargs,
    )


def test_every_searched_value_lies_in_its_declared_range():
    keys = C.searched(None, {})
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=3))
    for _ in range(200):
        trial = study.ask()
        for p in keys:
            value = S.suggest(trial, p)
            assert p.check(value) == value
        study.tell(trial, 0.0)


def test_fixed_values_leave_the_search_and_a_log_range_from_zero_starts_above_it():
    keys = C.searched(None, {"fabric.size_m": 0.55})
    assert "fabric.size_m" not in {p.key for p in keys}
    young = P.lookup("fabric.young_pa")
    assert young.low == 0 and young.search_bounds() == (young.high / 1e4, young.high)


def _study_rows(db) -> list[tuple[int, str]]:
    with sqlite3.connect(db) as con:
        return con.execute("select number, state from trials order by number").fetchall()


def _running_with_params(db) -> bool:
    """A candidate is in flight with all its values drawn (a trial row exists a moment before its parameters do,
    and they come one by one)."""
    searched = len(TINY[TINY.index("--params") + 1].split(","))
    with sqlite3.connect(db) as con:
        return (
            con.execute(
                "select count(*) from trial_params p join trials t on p.trial_id = t.trial_id where t.state = 'RUNNING'"
            ).fetchone()[0]
            >= searched
        )


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_a_tiny_search_is_interrupted_and_the_same_command_continues_it(tmp_path, stop):
    out = tmp_path / "cal"
    # 50 candidates: far more than can finish between the probe seeing one and the signal, even on a loaded machine;
    # the search's size is not part of its configuration, so the continuation asks for fewer
    proc = subprocess.Popen(
        [sys.executable, "-m", "mantaray.cli", "sim", "calibrate", *TINY, "--candidates", "50", "--out", str(out)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline:  # interrupt once the first candidate is in and the second runs
        try:
            states = [s for _, s in _study_rows(out / "study.db")] if (out / "study.db").exists() else []
            if states.count("COMPLETE") >= 1 and _running_with_params(out / "study.db"):
                break
        except sqlite3.OperationalError:  # the file exists before Optuna has made its tables
            pass
        time.sleep(0.2)
    proc.send_signal(stop)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "the same command continues" in err and "Traceback" not in err
    assert (out / "report.md").exists()
    before = [s for _, s in _study_rows(out / "study.db")].count("COMPLETE")
    assert 1 <= before < 50
    again = _cli(*TINY, "--candidates", str(before + 1), "--out", str(out), "--json")
    assert again.returncode == 0, again.stderr
    assert "continuing" in again.stderr
    report = json.loads(again.stdout)
    assert report["candidates"] == before + 1 and report["best"] is not None
    assert set(report["best"]["details"]["findings"]) == {"F1", "F2", "F3", "F4", "F5"}
    study = optuna.load_study(study_name=S.STUDY_NAME, storage=f"sqlite:///{out / 'study.db'}")
    failed = [t for t in study.trials if t.state == optuna.trial.TrialState.FAIL]
    done = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]
    assert failed and any(t.params == failed[0].params for t in done)  # the interrupted candidate ran again
    for t in done:
        for key, value in t.user_attrs["values"].items():
            P.lookup(key).check(value)
    assert (out / "pareto.png").exists() and "Best candidate" in (out / "report.md").read_text()


def test_a_study_with_other_options_is_refused_in_one_line(tmp_path):
    out = tmp_path / "cal"
    first = _cli(*TINY, "--candidates", "0", "--out", str(out))
    assert first.returncode == 0, first.stderr
    other = _cli(*TINY[:-2], "--seed", "6", "--candidates", "1", "--out", str(out))
    assert other.returncode == 2 and "another configuration" in other.stderr and "Traceback" not in other.stderr


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--set", "fabric.size_m=0.9"], "outside its declared range"),
        (["--params", "fabric.sizes"], "not a declared parameter"),
        (["--set", "reading.pid_unit=grad"], "must be one of deg, rad"),
        (["--params", "fabric.size_m", "--set", "fabric.size_m=0.55"], "nothing to search"),
        (["--log", "/nonexistent/run.jsonl"], "cannot read the rig log"),
        (["--trials-per-cell", "0"], "trials per cell"),
    ],
)
def test_bad_options_are_refused_in_one_line(args, needle):
    result = _cli(*args, "--candidates", "0", "--out", "/tmp/mantaray-never-written")
    assert result.returncode == 2 and needle in result.stderr and "Traceback" not in result.stderr


# ------------------------------------------------------------------------------------------- rig logs
HIDDEN = {"contact.rolling_damping_per_s": 2.0}


@pytest.fixture(scope="module")
def synthetic_log(tmp_path_factory):
    """A 4 s simulated run on a plant whose rolling damping is 2 /s, written as `mantaray rig` writes a run."""
    plant = Plant().set(HIDDEN)
    bridge = Bridge(Link(InProcessTransport(simulated_clock=True)), plant.rig(**FAST), plant.tracking())
    result = bridge.run(TrialSpec((0.06, -0.04), (-0.07, 0.05), duration_s=4.0, seed=3))
    return L.write_log(tmp_path_factory.mktemp("logs") / "run.jsonl", result, "sphere", "hidden"), result


def test_a_written_log_reads_back_as_the_trial_it_came_from(synthetic_log):
    path, result = synthetic_log
    run = read_run_log(path)
    assert np.allclose(run.t_s, result.t_s) and np.allclose(run.xy_m, result.measured_xy_m)
    assert np.allclose(run.command_m, result.command_m) and run.start_m == pytest.approx(tuple(result.true_xy_m[0]))


def test_replaying_a_log_on_its_own_plant_retraces_it_and_on_another_does_not(synthetic_log):
    path, _ = synthetic_log
    run = read_run_log(path)
    same = L.trajectory_error_m(L.replay(run, Plant().set(HIDDEN).rig(**FAST)), run.xy_m)
    other = L.trajectory_error_m(L.replay(run, Plant().rig(**FAST)), run.xy_m)
    assert same < 1e-6 and other > 1e-3  # the replay is exact: the same physics, the same commands


def test_a_log_fit_prefers_the_hidden_value(synthetic_log):
    path, _ = synthetic_log
    evidence = L.LogEvidence(logs=(str(path),), **FAST)  # the fidelity the log was written at
    with LocalPool(1) as pool:
        errors = {
            beta: evidence.evaluate({"contact.rolling_damping_per_s": beta}, pool)[0][0] for beta in (1.0, 2.0, 4.0)
        }
    assert min(errors, key=errors.get) == 2.0


def test_a_log_search_runs_end_to_end_from_the_command_line(synthetic_log, tmp_path):
    path, _ = synthetic_log
    result = _cli(
        "--log",
        str(path),
        "--params",
        "contact.rolling_damping_per_s",
        "--candidates",
        "3",
        "--jobs",
        "1",
        "--horizon",
        "1.5",
        "--out",
        str(tmp_path / "fit"),
        "--json",
    )
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["evidence"] == "log" and report["candidates"] == 3
    assert "run.jsonl" in report["best"]["details"]["errors_m"]


@pytest.mark.parametrize(
    "text, needle",
    [
        ("", "does not start with a config line"),
        ('{"kind": "config"}\nnot json\n{}\n', "is not JSON"),
        ('{"kind": "config"}\n', "no frame in which the object was seen"),
    ],
)
def test_a_file_that_is_not_a_rig_log_is_refused_with_a_reason(tmp_path, text, needle):
    path = tmp_path / "bad.jsonl"
    path.write_text(text)
    with pytest.raises(RunLogError, match=needle):
        read_run_log(path)


class _Toy:
    """Evidence without physics: the objective is |size - 0.55|; sizes above 0.58 'diverge'."""

    kind = "toy"
    seed = 1
    objective_names = ("distance",)
    penalty = (1.0,)

    def evaluate(self, values, pool):
        from mantaray.sim.model.model import SimulationUnstable

        if values["fabric.size_m"] > 0.58:
            raise SimulationUnstable("toy divergence")
        return (abs(values["fabric.size_m"] - 0.55),), {"passed": 0}


def _toy_study(path):
    evidence = _Toy()
    keys = C.searched(["fabric.size_m"], {})
    study = optuna.create_study(
        storage=f"sqlite:///{path}",
        study_name=S.STUDY_NAME,
        load_if_exists=True,
        sampler=optuna.samplers.RandomSampler(seed=2),
    )
    return study, evidence, keys


def test_an_unstable_candidate_scores_the_penalty_and_is_never_the_best(tmp_path):
    study, evidence, keys = _toy_study(tmp_path / "toy.db")
    S.run_study(study, evidence, keys, {}, 25, pool=None)
    done = S.completed(study)
    unstable = [t for t in done if "unstable" in t.user_attrs["details"]]
    assert unstable and all(t.values == [1.0] for t in unstable)
    assert all(t.user_attrs["values"]["fabric.size_m"] > 0.58 for t in unstable)
    best = S.best_trial(study)
    assert best.user_attrs["values"]["fabric.size_m"] <= 0.58 and best.values[0] == min(
        t.values[0] for t in done if t not in unstable
    )


def test_a_candidate_left_running_by_a_killed_search_is_queued_again(tmp_path):
    study, evidence, keys = _toy_study(tmp_path / "toy.db")
    orphan = study.ask()
    size = S.suggest(orphan, keys[0])  # the search was killed here: the trial stays RUNNING
    S.requeue_abandoned(study, {p.key for p in keys})
    assert study.trials[orphan.number].state == optuna.trial.TrialState.FAIL
    S.run_study(study, evidence, keys, {}, 1, pool=None)
    assert S.completed(study)[0].user_attrs["values"]["fabric.size_m"] == size


def test_a_candidate_killed_while_its_values_were_drawn_fails_and_is_not_queued(tmp_path):
    """Values drawn in part are no candidate: queued, they would run with the rest drawn afresh, as another one."""
    study, evidence, keys = _toy_study(tmp_path / "toy.db")
    orphan = study.ask()  # killed before its values were drawn
    S.requeue_abandoned(study, {p.key for p in keys})
    assert study.trials[orphan.number].state == optuna.trial.TrialState.FAIL
    assert not study.get_trials(states=(optuna.trial.TrialState.WAITING,))


def test_an_interrupted_candidate_is_evaluated_first_when_the_search_continues(tmp_path):
    study, evidence, keys = _toy_study(tmp_path / "toy.db")

    class Interrupting(_Toy):
        calls = 0

        def evaluate(self, values, pool):
            Interrupting.calls += 1
            if Interrupting.calls == 2:
                self.interrupted = values
                raise KeyboardInterrupt
            return super().evaluate(values, pool)

    flaky = Interrupting()
    with pytest.raises(KeyboardInterrupt):
        S.run_study(study, flaky, keys, {}, 5, pool=None)
    assert len(S.completed(study)) == 1
    S.run_study(study, _Toy(), keys, {}, 2, pool=None)
    assert S.completed(study)[1].user_attrs["values"] == flaky.interrupted


def test_a_candidate_scores_the_same_on_two_worker_processes_as_in_this_one():
    evidence = C.FindingsEvidence(cells_per_stratum=1, trials_per_cell=1, duration_s=0.5, seed=3)
    values = {"contact.rolling_damping_per_s": 3.0, "reading.success_rule": "end"}
    with LocalPool(1) as here, LocalPool(2) as workers:
        assert evidence.evaluate(values, here) == evidence.evaluate(values, workers)


def test_a_log_replays_exactly_with_camera_latency(tmp_path):
    plant = Plant().set({"tracking.latency_s": 0.03})
    bridge = Bridge(Link(InProcessTransport(simulated_clock=True)), plant.rig(**FAST), plant.tracking())
    result = bridge.run(TrialSpec((0.03, 0.05), (-0.05, -0.02), duration_s=2.0, seed=2))
    run = read_run_log(L.write_log(tmp_path / "late.jsonl", result, "sphere", "latency"))
    assert L.trajectory_error_m(L.replay(run, plant.rig(**FAST), latency_s=0.03), run.xy_m) < 1e-6
    assert L.trajectory_error_m(L.replay(run, plant.rig(**FAST), latency_s=0.0), run.xy_m) > 1e-5


def test_logs_of_another_object_or_a_bad_horizon_are_refused(synthetic_log):
    path, _ = synthetic_log
    with pytest.raises(RunLogError, match="pass --object sphere"):
        L.check_logs([str(path)], "cube", None)
    with pytest.raises(RunLogError, match="--horizon must be a positive"):
        L.check_logs([str(path)], "sphere", 0.0)
    L.check_logs([str(path)], "sphere", 2.0)
