"""mantaray sim tune: a tiny search end to end (settings the firmware takes, both scores, the figure), resumed after an
interruption; the search space against the schema."""

from __future__ import annotations

import json
import math
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mantaray.host.controller_settings import ControllerSettings, SettingsError
from mantaray.host.session import controller_axes
from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.sim.evaluation.executors import LocalPool
from mantaray.sim.search import tune as T

TINY = [
    "--controller",
    "scheduled",
    "--cells-per-stratum",
    "1",
    "--trials-per-cell",
    "1",
    "--duration",
    "1",
    "--final-trials",
    "1",
    "--final-cells",
    "2",
    "--jobs",
    "1",
    "--resolution",
    "11",
    "--timestep",
    "0.002",
]  # a cheap mesh: these test the mechanics, not the physics


def _tune(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "tune", *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=900,
    )


def _completed(db) -> int:
    with sqlite3.connect(db) as con:
        return con.execute("SELECT COUNT(*) FROM trials WHERE state = 'COMPLETE'").fetchone()[0]


@pytest.mark.parametrize("per_axis", [False, True])
@pytest.mark.parametrize("controller", list(T.SPACE))
def test_every_knob_is_a_setting_of_its_controller_within_the_schemas_bounds(controller, per_axis):
    for knob in T.knobs(controller, per_axis):
        for value in (knob.low, knob.high):
            for scale in (1.0, 180.0 / math.pi):  # a plant reading the paper's gains per radian
                T.settings_of(controller, {knob.key: value}, scale)  # SettingsError if the schema refuses it
    boot = T.settings_of(controller, T.boot_values(controller, per_axis))
    assert boot == T.settings_of(controller, T.boot_values(controller))  # per axis or not, the same start
    assert {k.rsplit(".", 1)[0] for k, _ in boot.values if k.startswith("pid.")} == {
        f"pid.{a.name.lower()}" for a in controller_axes(controller)
    }


def test_a_tiny_tuning_run_is_interrupted_then_continued_and_writes_what_the_rig_takes(tmp_path):
    out = tmp_path / "tune"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mantaray.cli", "sim", "tune", *TINY, "--candidates", "40", "--out", str(out)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline:  # interrupt once two candidates are in
        try:
            if (out / "study.db").exists() and _completed(out / "study.db") >= 2:
                break
        except sqlite3.OperationalError:  # the file exists before Optuna has made its tables
            pass
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 130 and "the same command continues" in err and "Traceback" not in err, err
    before = _completed(out / "study.db")
    assert 2 <= before < 40 and (out / "report.json").exists()
    again = _tune(*TINY, "--candidates", str(before + 1), "--out", str(out), "--json")
    assert again.returncode == 0, again.stderr
    assert "continuing" in again.stderr
    # The paper's Manhattan runs on the sample once, before the candidates (their ETA counts them only).
    assert "first the paper's Manhattan" in err and "first the paper's Manhattan" not in again.stderr
    report = json.loads(again.stdout)
    assert report["candidates"] == before + 1
    assert set(report["baseline_on_the_sample"]) >= {"success", "reached", "fell_off"}  # the paper's Manhattan
    final = report["final_check"]
    assert final["seed"] == 2026 and final["trials"] == 4 and {"score", "reach_score"} <= set(final)
    # its maps under both rules; the report's paths are from its own folder, so a copy of the folder keeps them
    assert (
        final["figures"] == ["final/heatmap.png", "final/heatmap_reach.png"]
        and final["results"] == "final/results.jsonl"
    )
    assert all((out / f).stat().st_size > 0 for f in final["figures"]) and (out / "final" / "cells.csv").exists()
    settings = ControllerSettings.load(out / "settings.toml")
    assert settings.controller == "scheduled" and dict(settings.values) == report["best"]["settings"]
    assert settings.plant == "paper" and set(report["best"]["knobs"]) == {k.key for k in T.SPACE["scheduled"]}
    assert (out / "history.png").stat().st_size > 0
    other = _tune(*TINY, "--candidates", str(before + 1), "--final-seed", "2027", "--out", str(out))
    assert other.returncode == 2 and "other --final options" in other.stderr and "Traceback" not in other.stderr
    with_it = subprocess.run(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "run",
            "--settings",
            str(out / "settings.toml"),
            "--duration",
            "0.5",
            "--json",
            "--out",
            str(tmp_path / "run"),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    ran = json.loads(with_it.stdout)  # 0.5 s from the default start is too short to get there: exit 1
    assert with_it.returncode == 1 and not ran["success"] and ran["controller"] == "scheduled", with_it.stderr


def test_a_final_check_on_the_searchs_own_seed_is_refused(tmp_path):
    proc = _tune(*TINY, "--seed", "5", "--final-seed", "5", "--out", str(tmp_path / "t"))
    assert proc.returncode == 2 and "--final-seed must differ from --seed" in proc.stderr
    assert not (tmp_path / "t").exists()


def test_the_scheduled_controllers_first_candidate_is_the_papers_manhattan_on_every_plant():
    """Its boot values (the paper's gains read as the plant reads them, the neutral schedule) score the baseline."""
    for plant in ("paper", "polyester"):
        evidence = T.TuningEvidence(
            controller="scheduled",
            plant=plant,
            cells_per_stratum=1,
            trials_per_cell=1,
            duration_s=2.0,
            seed=4,
            resolution=11,
            timestep_s=0.002,
        )
        with LocalPool(1) as pool:
            _, first = evidence.evaluate(T.boot_values("scheduled"), pool)
            assert first == evidence.baseline(pool), plant


def test_the_boot_values_are_the_controllers_untuned_settings():
    boot = T.boot_values("manhattan")
    assert (
        boot["pid.*.kp"] == m.PID_DEFAULTS[m.Axis.X]["kp"] and boot["configure.tilt_limit"] == m.Configure().tilt_limit
    )


def test_per_axis_the_pids_get_their_own_gains_scaled_as_the_plant_reads_them():
    scale = 180.0 / math.pi
    settings = T.settings_of("scheduled", {"pid.x.kp": 20.0, "pid.y.kp": 40.0, "pid.x.integral_limit": 10.0}, scale)
    assert settings.get("pid.x.kp") == pytest.approx(20.0 * scale) and settings.get("pid.y.kp") == pytest.approx(
        40.0 * scale
    )
    assert (
        settings.get("pid.x.integral_limit") == 10.0 and settings.get("pid.y.integral_limit") is None
    )  # [deg]: no gain


def test_a_per_axis_search_searches_x_and_y_apart_and_is_its_own_study(tmp_path):
    out = tmp_path / "t"
    tiny = [*TINY, "--final-trials", "0", "--out", str(out)]
    run = _tune(*tiny, "--per-axis", "--candidates", "2", "--json")
    assert run.returncode == 0, run.stderr
    knobs = json.loads(run.stdout)["best"]["knobs"]
    assert {"pid.x.kp", "pid.y.kp", "pid.x.kd", "pid.y.kd"} <= set(knobs) and "pid.*.kp" not in knobs
    shared = _tune(*tiny, "--candidates", "3")  # the same folder without --per-axis: another search
    assert shared.returncode == 2 and "another configuration (searched differ)" in shared.stderr, shared.stderr


@pytest.mark.parametrize("per_axis", [False, True])
@pytest.mark.parametrize("controller", list(T.SPACE))
def test_a_start_from_settings_gives_back_the_knobs_that_made_them(controller, per_axis):
    """start_values inverts settings_of for any candidate, on a plant that reads the gains as given or per radian."""
    space = T.knobs(controller, per_axis)

    @given(
        st.lists(st.floats(0.0, 1.0), min_size=len(space), max_size=len(space)), st.sampled_from([1.0, 180 / math.pi])
    )
    def check(fractions, scale):
        values = {k.key: k.low + f * (k.high - k.low) for k, f in zip(space, fractions, strict=True)}
        settings = T.settings_of(controller, values, scale)
        back, clipped = T.start_values(settings, per_axis, scale)
        assert back.keys() == values.keys() and clipped == []
        assert all(back[k] == pytest.approx(v, rel=1e-12, abs=1e-12) for k, v in values.items()), (values, back)

    check()


def test_a_start_from_runs_what_the_file_runs_and_says_what_it_clips():
    """A setting the file leaves out is the firmware's boot value (on a plant that reads the gains per radian, the
    boot gains are far below the paper's as it reads them); one beyond its knob's range is clipped, and named."""
    start, clipped = T.start_values(ControllerSettings("cascade", (("configure_cascade.position_gain", 50.0),)))
    assert start == {**T.boot_values("cascade"), "configure_cascade.position_gain": 30.0}
    assert clipped == ["configure_cascade.position_gain"]
    scale = 180 / math.pi
    start, clipped = T.start_values(ControllerSettings("scheduled"), gain_scale=scale)
    assert start["pid.*.ki"] == pytest.approx(m.PID_DEFAULTS[m.Axis.X]["ki"] / scale) and clipped == ["pid.*.kp"]
    assert T.settings_of("scheduled", start, scale).get("pid.x.ki") == pytest.approx(m.PID_DEFAULTS[m.Axis.X]["ki"])


def test_a_start_from_pids_that_differ_needs_a_search_per_axis():
    apart = ControllerSettings("cascade", (("pid.vx.kp", 123.0),))  # vy keeps its boot kp
    with pytest.raises(SettingsError, match="differ in kp"):
        T.start_values(apart)
    start, _ = T.start_values(apart, per_axis=True)
    assert start["pid.vx.kp"] == 123.0 and start["pid.vy.kp"] == m.PID_DEFAULTS[m.Axis.VY]["kp"]


def test_a_search_started_from_settings_tries_them_second_and_refuses_them_for_a_study_begun_without(tmp_path):
    evidence = T.TuningEvidence(controller="cascade", cells_per_stratum=1, trials_per_cell=1, duration_s=1.0)
    start, _ = T.start_values(
        ControllerSettings("cascade", (("pid.vx.kp", 123.0), ("pid.vy.kp", 123.0), ("configure.tilt_limit", 20.0)))
    )
    study = T.open_tuning(tmp_path / "a.db", evidence, start=start)
    assert [t.system_attrs["fixed_params"] for t in study.trials] == [T.boot_values("cascade"), start]
    assert T.open_tuning(tmp_path / "a.db", evidence, start=start).trials == study.trials  # the same start: continues
    T.open_tuning(tmp_path / "b.db", evidence)
    with pytest.raises(T.StartMismatch, match="a start is for a new study"):
        T.open_tuning(tmp_path / "b.db", evidence, start=start)


def test_a_start_from_file_for_another_controller_or_plant_is_a_usage_error(tmp_path):
    for text, says in (
        ('controller = "scheduled"\n', "sets up the scheduled controller"),
        ('controller = "cascade"\nplant = "polyester"\n', "gains for the polyester plant"),
        ('controller = "cascade"\n[pid.x]\nkp = 1.0\n', "pid.x"),
        ('controller = "cascade"\n[pid.vx]\nkp = 1.0\n', "differ in kp"),
    ):
        path = tmp_path / "start.toml"
        path.write_text(text)
        proc = _tune(*TINY, "--controller", "cascade", "--start-from", str(path), "--out", str(tmp_path / "t"))
        assert proc.returncode == 2 and says in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
        assert not (tmp_path / "t").exists()


# ------------------------------------------------------------------------------------------- pruned searches
class _ByGain:
    """A pool that scores trials by the candidate's kp alone, with no physics: a trial succeeds (and reaches) when kp
    is near 30 deg/m, most of the time, and rarely otherwise, drawn from the trial's seed; it counts what it ran."""

    def __init__(self) -> None:
        self.trials = 0

    def map(self, jobs):
        out = []
        for experiment, trial in jobs:
            kp = dict(experiment.settings)["pid.x.kp"]
            good = abs(math.log(kp / 30.0)) < 0.4
            luck = (trial.seed % 100) / 100
            won = luck < (0.8 if good else 0.1)
            out.append({"cell": trial.cell, "success": won, "reached": won, "fell_off": not won})
        self.trials += len(jobs)
        return out


def test_the_rungs_are_nested_stratified_samples_that_end_at_the_whole_sample():
    from mantaray.sim.evaluation import findings as F

    evidence = T.TuningEvidence(cells_per_stratum=6, seed=31)
    assert evidence.rungs() == [1, 2, 4, 6]
    previous: set[int] = set()
    for k in evidence.rungs():
        cells = set(F.stratified_sample(20, 6, 31, first=k))
        assert previous <= cells and len(cells) == k * len(F.STRATA)
        previous = cells
    assert previous == set(F.stratified_sample(20, 6, 31))


def test_a_pruned_search_stops_hopeless_candidates_early_and_keeps_the_good_one(tmp_path):
    from mantaray.sim.search import study as S

    evidence = T.TuningEvidence(
        controller="manhattan", plant="polyester", cells_per_stratum=4, trials_per_cell=3, prune=True
    )
    study = T.open_tuning(tmp_path / "study.db", evidence)
    pool = _ByGain()
    S.run_study(study, evidence, T.knobs("manhattan"), {}, 30, pool)
    full = 4 * 5 * 3  # the whole sample's trials
    finished, completed = S.finished(study), S.completed(study)
    assert len(finished) == 30 and 0 < len(completed) < 30  # some stopped, and --candidates counts them
    pruned = [t for t in finished if t not in completed]
    assert all(t.user_attrs["details"]["trials"] < full for t in pruned)
    assert pool.trials == sum(t.user_attrs["details"]["trials"] for t in finished) < 30 * full
    best = S.best_trial(study)
    assert abs(math.log(best.user_attrs["values"]["pid.*.kp"] / 30.0)) < 0.4  # the good region's candidate
    report = T.write_report(study, evidence, tmp_path, None)
    assert report["pruned"] == len(pruned) and report["trials_run"] == pool.trials


def test_replaying_an_unpruned_search_through_the_pruner_runs_what_the_pruned_search_runs(tmp_path):
    """The same random draws, searched once pruned and once in full: the replay of the full one stops the same
    candidates after the same trials, and scores the completed ones as the pruned search did."""
    import optuna

    from mantaray.sim.search import study as S

    runs = {}
    for prune in (True, False):
        evidence = T.TuningEvidence(
            controller="manhattan", plant="polyester", cells_per_stratum=4, trials_per_cell=3, prune=prune
        )
        study = T.open_tuning(tmp_path / f"prune{prune}.db", evidence)
        study.sampler = optuna.samplers.RandomSampler(seed=5)
        S.run_study(study, evidence, T.knobs("manhattan"), {}, 24, _ByGain())
        runs[prune] = (evidence, S.finished(study))
    evidence, pruned_search = runs[True]
    replayed = T.replay_pruned(evidence, runs[False][1])
    assert [r["number"] for r in replayed] == [t.number for t in pruned_search]
    assert [r["trials"] for r in replayed] == [t.user_attrs["details"]["trials"] for t in pruned_search]
    stopped = [t.state == optuna.trial.TrialState.PRUNED for t in pruned_search]
    assert [r["misses"] is None for r in replayed] == stopped and 0 < sum(stopped) < 24
    assert [r["misses"] for r in replayed if r["misses"] is not None] == pytest.approx(
        [t.values[0] for t in pruned_search if t.state == optuna.trial.TrialState.COMPLETE]
    )


class _ByGainAndMesh(_ByGain):
    """As _ByGain, but on a 15 x 15 mesh the good gain is 45 deg/m: a cheaper fidelity that ranks candidates wrongly."""

    def map(self, jobs):
        out = []
        for experiment, trial in jobs:
            kp = dict(experiment.settings)["pid.x.kp"]
            good = abs(math.log(kp / (45.0 if experiment.resolution == 15 else 30.0))) < 0.4
            won = (trial.seed % 100) / 100 < (0.8 if good else 0.1)
            out.append({"cell": trial.cell, "success": won, "reached": won, "fell_off": not won})
        self.trials += len(jobs)
        return out


def test_confirming_the_best_candidates_at_a_finer_fidelity_takes_the_best_there_and_resumes(tmp_path):
    from mantaray.sim.model.rig import Fidelity
    from mantaray.sim.search import study as S

    evidence = T.TuningEvidence(
        controller="manhattan",
        plant="polyester",
        cells_per_stratum=1,
        trials_per_cell=4,
        resolution=11,
        timestep_s=0.002,
    )  # screened on a cheap mesh
    study = T.open_tuning(tmp_path / "study.db", evidence)
    pool = _ByGainAndMesh()
    S.run_study(study, evidence, T.knobs("manhattan"), {}, 16, pool)
    finer = Fidelity(15, 0.001)
    confirmation = T.confirm(study, evidence, finer, 6, pool)
    assert confirmation["candidates"] == 6 and len(confirmation["scores"]) == 6
    scores = confirmation["scores"]
    best = confirmation["best"]["number"]
    assert scores[str(best)]["confirmed"] == min(v["confirmed"] for v in scores.values())
    assert T.confirmed_best(study).number == best  # the answer is the finer fidelity's
    from mantaray.sim.evaluation import findings as F

    screened = [v["screened"] for v in scores.values()]
    assert confirmation["rank_correlation"] == pytest.approx(
        F.rank_correlation(np.array(screened), np.array([v["confirmed"] for v in scores.values()])), nan_ok=True
    )
    ran = pool.trials
    assert T.confirm(study, evidence, finer, 6, pool)["scores"] == scores and pool.trials == ran  # kept, not rerun
    with pytest.raises(ValueError, match="confirmed at"):
        T.confirm(study, evidence, Fidelity(21, 0.001), 6, pool)
    with pytest.raises(ValueError, match="already ran at"):
        T.confirm(study, evidence, Fidelity(evidence.resolution, evidence.timestep_s), 6, pool)
    T.confirm(study, evidence, finer, 2, pool)  # fewer: the answer is the best of those two
    assert T.confirmed_best(study).number in {int(n) for n in list(scores)[:2]}
    settings = T.best_settings(study, evidence)
    assert dict(settings.values)["pid.x.kp"] == pytest.approx(
        T.settings_of("manhattan", T.confirmed_best(study).user_attrs["values"]).get("pid.x.kp")
    )


def test_the_command_confirms_at_the_finer_fidelity_and_runs_its_final_check_there(tmp_path):
    out = tmp_path / "tune"
    run = _tune(
        *TINY, "--candidates", "2", "--confirm", "2", "--confirm-at", "7:0.002", "--resolution", "5", "--out", str(out)
    )
    assert run.returncode == 0, run.stderr
    report = json.loads((out / "report.json").read_text())
    assert report["confirmation"]["candidates"] == 2 and report["confirmation"]["fidelity"] == "7 × 7, 2 ms"
    header = json.loads((out / "final" / "results.jsonl").read_text().split("\n", 1)[0])
    assert header["protocol"]["resolution"] == 7  # every final number at the finer fidelity
    unconfirmed = _tune(*TINY, "--candidates", "3", "--resolution", "5", "--out", str(out))
    assert unconfirmed.returncode == 2 and "--confirm-at 7:0.002" in unconfirmed.stderr, unconfirmed.stderr
    same = _tune(*TINY, "--confirm", "2", "--confirm-at", "11:0.002", "--out", str(tmp_path / "same"))
    assert same.returncode == 2 and "is the fidelity the search runs at" in same.stderr
    bad = _tune(*TINY, "--confirm", "2", "--confirm-at", "8:0.002", "--out", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "odd" in bad.stderr and "Traceback" not in bad.stderr
