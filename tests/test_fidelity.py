"""The fidelity gate: its paired tests on drawn outcomes, the runs it refuses to pair, the start shift of its noise
floor, the model identity that keeps results files apart, and the command end to end on a tiny sample."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.sim.evaluation import equivalence as Q
from mantaray.sim.evaluation import experiment as E
from mantaray.sim.evaluation import fidelity as G
from mantaray.sim.evaluation import findings as F
from mantaray.sim.evaluation import paired as P
from mantaray.sim.evaluation import results_file as R

MODULE = (0.5, 0.5)


# ------------------------------------------------------------------------------------------- paired statistics
@settings(max_examples=200, deadline=None)
@given(outcomes=st.lists(st.tuples(st.booleans(), st.booleans()), max_size=60))
def test_mcnemar_counts_discordant_pairs_and_its_p_is_symmetric_and_a_probability(outcomes):
    a = [x for x, _ in outcomes]
    b = [y for _, y in outcomes]
    d = P.discordance(a, b)
    assert d.only_a == sum(x and not y for x, y in outcomes) and d.only_b == sum(y and not x for x, y in outcomes)
    assert d.pairs == len(outcomes)
    assert 0 < d.p_two_sided <= 1
    assert P.discordance(b, a).p_two_sided == pytest.approx(d.p_two_sided)  # the test does not favour either run
    assert d.p_more_in_a + P.discordance(b, a).p_more_in_a >= 1 - 1e-12  # the two one-sided tails cover everything


@settings(max_examples=100, deadline=None)
@given(n=st.integers(1, 80), data=st.data())
def test_binomial_tail_is_the_sum_of_the_fair_binomial_and_falls_with_k(n, data):
    k = data.draw(st.integers(0, n))
    exact = sum(math.comb(n, i) for i in range(k, n + 1)) / 2**n
    assert P.binomial_tail(k, n) == pytest.approx(exact)
    assert P.binomial_tail(k + 1, n) <= P.binomial_tail(k, n)


def test_mcnemar_finds_a_one_sided_split_and_not_an_even_one():
    assert P.Discordance(100, 20, 2).p_two_sided < 1e-3  # 20 against 2: a bias
    assert P.Discordance(100, 11, 11).p_two_sided == 1.0
    assert P.Discordance(100, 0, 0).p_two_sided == 1.0


def test_bootstrap_interval_holds_the_mean_and_covers_a_true_shift_as_often_as_its_level_says():
    rng = np.random.default_rng(7)
    missed = 0
    for _ in range(100):
        shift = rng.uniform(-1, 1)
        d = shift + rng.normal(0, 0.1, 400)
        ci = P.mean_interval(d, level=0.95, seed=int(rng.integers(1 << 31)))
        assert ci.low <= ci.mean <= ci.high
        missed += not ci.low <= shift <= ci.high
    assert missed <= 12  # 5 expected of 100 at a 95 % level


def test_bootstrap_of_nothing_is_nan_and_a_bad_level_is_refused():
    assert math.isnan(P.mean_interval([]).mean)
    few = P.mean_interval([0.01, 0.02, 0.005, 0.03, 0.01], level=0.995)  # one-signed, but only five
    assert few.n == 5 and few.mean == pytest.approx(0.015) and math.isnan(few.low) and math.isnan(few.high)
    with pytest.raises(ValueError, match="level"):
        P.mean_interval([1.0], level=1.5)


# ------------------------------------------------------------------------------------------- equivalence
def test_an_interval_inside_the_margin_is_equivalent_outside_it_different_and_across_it_undecided():
    assert Q.Judged(100, 0.01, -0.03, 0.04, 0.05).status == Q.EQUIVALENT
    assert Q.Judged(100, 0.10, 0.06, 0.14, 0.05).status == Q.DIFFERENT
    assert Q.Judged(100, -0.10, -0.14, -0.05, 0.05).status == Q.DIFFERENT  # touching the margin from outside
    assert Q.Judged(100, 0.0, -0.05, 0.03, 0.05).status == Q.UNDECIDED  # touching it from inside is not inside
    open_ = Q.Judged(100, 0.02, -0.02, 0.06, 0.05)  # 0.02, half-width 0.04: equivalence needs 0.03
    assert open_.status == Q.UNDECIDED and open_.pairs_to_decide == math.ceil(100 * (0.04 / 0.03) ** 2)
    assert Q.Judged(100, 0.05, 0.0, 0.10, 0.05).pairs_to_decide == 200  # on the margin: twice the pairs
    assert Q.Judged(5, 0.05, math.nan, math.nan, 0.05).pairs_to_decide is None  # too few for an interval
    assert Q.Judged(0, math.nan, math.nan, math.nan, 0.05).status == Q.UNDECIDED


@settings(max_examples=200, deadline=None)
@given(pairs=st.lists(st.sampled_from([(0, 0), (1, 1), (1, 0), (0, 1)]), max_size=300))
def test_a_rate_difference_is_the_discordant_share_and_its_interval_is_the_mirror_of_the_swapped_one(pairs):
    d = [a - b for a, b in pairs]
    j, swapped = Q.mean_difference(d, 0.05), Q.mean_difference([-x for x in d], 0.05)
    if not pairs:
        assert j.n == 0 and j.status == Q.UNDECIDED
        return
    only_a, only_b = sum(a > b for a, b in pairs), sum(b > a for a, b in pairs)
    assert j.estimate == pytest.approx((only_a - only_b) / len(pairs))
    assert j.low < j.high  # the adjustment: an interval even where no pair is discordant
    assert (swapped.low, swapped.high) == pytest.approx((-j.high, -j.low))
    assert j.status == swapped.status


def _pairs(rng, n: int, delta: float, discordant: float = 0.2) -> np.ndarray:
    """n paired differences of a rate (candidate − finer: +1, 0, −1) whose true difference is delta: a share
    `discordant` of the pairs differ, (discordant + delta) / 2 of them in the candidate's favour."""
    u = rng.random(n)
    up = (discordant + delta) / 2
    return np.where(u < up, 1, np.where(u < discordant, -1, 0))


def test_a_true_difference_inside_the_margin_is_found_equivalent_and_never_different():
    rng = np.random.default_rng(SEEDS[0])
    said = [Q.mean_difference(_pairs(rng, 1000, 0.0), 0.05).status for _ in range(200)]
    assert said.count(Q.DIFFERENT) == 0 and said.count(Q.EQUIVALENT) >= 180  # 94 % expected


def test_a_true_difference_outside_the_margin_is_found_different_and_never_equivalent():
    rng = np.random.default_rng(SEEDS[1])
    said = [Q.mean_difference(_pairs(rng, 400, -0.12), 0.05).status for _ in range(200)]
    assert said.count(Q.EQUIVALENT) == 0 and said.count(Q.DIFFERENT) >= 180  # 95 % expected


@pytest.mark.parametrize("delta", [0.05, -0.05])
def test_a_true_difference_on_the_margin_is_called_equivalent_at_most_as_often_as_the_tests_5_percent(delta):
    """Two one-sided tests at 5 %: a rate that truly differs by the margin passes as equivalent in 5 % of samples."""
    rng = np.random.default_rng(SEEDS[2])
    said = [Q.mean_difference(_pairs(rng, 400, delta), 0.05).status for _ in range(400)]
    assert said.count(Q.EQUIVALENT) <= 32  # 20 expected; 32 is beyond its 99.5th percentile


def test_the_pairs_an_undecided_answer_asks_for_decide_it_on_the_same_outcomes_that_often():
    """An interval narrows as 1/√n: the same outcomes repeated to the projected count are decided, and repeated to
    fewer than half of it are not."""
    rng = np.random.default_rng(SEEDS[3])
    for _ in range(20):
        d = _pairs(rng, 80, float(rng.uniform(-0.03, 0.03)))
        j = Q.mean_difference(d, 0.05)
        if j.status != Q.UNDECIDED or abs(abs(j.estimate) - 0.05) < 0.005:
            continue  # decided already, or so near the margin that copies of it never are
        copies = math.ceil(j.pairs_to_decide / d.size)
        assert Q.mean_difference(np.tile(d, copies + 1), 0.05).status != Q.UNDECIDED
        if copies >= 4:
            assert Q.mean_difference(np.tile(d, copies // 3), 0.05).status == Q.UNDECIDED


def test_a_median_difference_interval_resamples_pairs_and_holds_the_difference():
    rng = np.random.default_rng(SEEDS[4])
    a = rng.normal(0.01, 0.005, 300)
    shifted = P.median_difference_interval(a + 0.004, a, level=0.9, seed=1)
    assert shifted.mean == pytest.approx(0.004) and shifted.low == pytest.approx(0.004)  # a constant shift: exact
    noisy = P.median_difference_interval(a + rng.normal(0, 0.002, 300), a, level=0.9, seed=1)
    assert noisy.low < noisy.mean < noisy.high
    few = P.median_difference_interval(a[:5], a[:5])
    assert few.n == 5 and math.isnan(few.low)
    with pytest.raises(ValueError, match="as many"):
        P.median_difference_interval(a[:5], a[:4])


# ------------------------------------------------------------------------------------------- the gate's verdict
def _results(
    tmp_path: Path, name: str, experiment: E.Experiment, outcomes: list[tuple[bool, bool, bool]], later_s: float = 0.0
):
    """A results file of protocol whose trials have the given (success, reached, fell_off), in trial order, and a
    time to reach and a final error drawn from the trial's seed (the same trial, the same draw), later_s later."""
    results = R.ResultsFile(tmp_path / f"{name}.jsonl", experiment)
    for trial, (success, reached, fell) in zip(
        E.trials(experiment), outcomes, strict=False
    ):  # fewer outcomes: an unfinished run
        draw = np.random.default_rng(trial.seed).random(2)
        results.records[trial.key] = {
            "key": trial.key,
            "cell": trial.cell,
            "k": trial.k,
            "success": success,
            "reached": reached,
            "fell_off": fell,
            "target_m": list(trial.target_m),
            "time_to_reach_s": 1.0 + 8.0 * draw[0] + later_s if reached else None,
            "final_error_m": (0.02 if success else 0.05) * draw[1],
        }
    return results


def _sample_runs(
    tmp_path, finer_outcomes, candidate_outcomes, floor_outcomes, later_s=0.0, label="manhattan", **changes
):
    sample = G.GateSample(cells_per_stratum=8, trials_per_cell=len(finer_outcomes) // 40, arms=(G.Arm(label, label),))
    arm = sample.arms[0]
    finer = sample.experiment(arm, G.FIDELITIES["reference"])
    candidate = dataclasses.replace(sample.experiment(arm, G.FIDELITIES["fast"]), **changes)
    floor = sample.experiment(arm, G.FIDELITIES["reference"], G.REPEATABILITY_M)
    return [
        G.Runs(
            label,
            _results(tmp_path, f"{label}_candidate", candidate, candidate_outcomes, later_s),
            _results(tmp_path, f"{label}_finer", finer, finer_outcomes),
            (_results(tmp_path, f"{label}_floor", floor, floor_outcomes),),
        )
    ]


def _draw(rng, n, p_reach):
    reached = rng.random(n) < p_reach
    fell = ~reached & (rng.random(n) < 0.5)
    success = reached & (rng.random(n) < 0.5)
    return list(zip(success, reached, fell, strict=True))


def _flip(outcomes, rng, share):
    """The outcomes with each trial redrawn with probability share (a perturbation's scatter, no bias)."""
    redrawn = _draw(rng, len(outcomes), 0.5)
    return [r if rng.random() < share else o for o, r in zip(outcomes, redrawn, strict=True)]


SEEDS = [int(s) for s in np.random.default_rng(2026).integers(0, 2**32, 60)]  # the drawn samples below


def test_a_candidate_that_scatters_without_bias_keeps_the_answers_on_a_large_sample(tmp_path):
    kept = 0
    for seed in SEEDS[:10]:
        rng = np.random.default_rng(seed)
        finer = _draw(rng, 1000, 0.5)
        report = G.compare(_sample_runs(tmp_path, finer, _flip(finer, rng, 0.05), _flip(finer, rng, 0.05)))
        assert report["pairs"] == 1000 and report["complete"] and report["verdict"] != G.CHANGES
        kept += report["verdict"] == G.KEEPS
    assert kept >= 8


def test_a_candidate_that_falls_off_more_changes_the_answers_and_says_which(tmp_path):
    for seed in SEEDS[:10]:
        rng = np.random.default_rng(seed)
        finer = _draw(rng, 400, 0.5)
        candidate = [(False, False, True) if rng.random() < 0.3 else o for o in finer]  # a third more falls
        report = G.compare(_sample_runs(tmp_path, finer, candidate, _flip(finer, rng, 0.05)))
        assert report["verdict"] == G.CHANGES
        assert any(c.startswith("manhattan: fell off") for c in report["changed"])


def test_a_candidate_that_reaches_later_changes_the_answers_through_its_time_to_reach_alone(tmp_path):
    rng = np.random.default_rng(SEEDS[5])
    finer = _draw(rng, 400, 0.5)
    report = G.compare(_sample_runs(tmp_path, finer, finer, _flip(finer, rng, 0.05), later_s=0.8))
    assert report["verdict"] == G.CHANGES
    (changed,) = report["changed"]
    assert changed.startswith("manhattan: mean time to reach [s] (both reached): +0.8 [")


def test_a_small_sample_is_undecided_and_asks_for_pairs_that_the_sample_can_grow_to(tmp_path):
    rng = np.random.default_rng(SEEDS[6])
    finer = _draw(rng, 40, 0.5)
    report = G.compare(_sample_runs(tmp_path, finer, _flip(finer, rng, 0.1), finer))
    assert report["verdict"] == G.UNDECIDED and report["undecided"] and not report["changed"]
    needed = report["pairs_to_decide"]
    assert needed > 40
    sample = G.GateSample(cells_per_stratum=8, trials_per_cell=1)
    more = G.grown(sample, needed, 1000)
    assert more.trials_per_cell == min(math.ceil(needed / 40), 25) and more.cells() == sample.cells()
    assert G.grown(sample, needed, 40).startswith(f"about {needed} pairs")  # --max-pairs already held


def test_the_contrast_of_two_controllers_is_the_difference_of_their_differences(tmp_path):
    """A candidate that lifts both controllers' reach alike keeps their contrast; one that lifts one alone does
    not, though each controller's own difference may still be within the margin."""
    rng = np.random.default_rng(SEEDS[7])
    base = [_draw(rng, 1000, 0.5) for _ in range(2)]

    def lifted(outcomes, share):
        return [(s, True, False) if not r and rng.random() < share else (s, r, f) for s, r, f in outcomes]

    def runs(share_a, share_b):
        return _sample_runs(tmp_path, base[0], lifted(base[0], share_a), base[0], label="manhattan") + _sample_runs(
            tmp_path, base[1], lifted(base[1], share_b), base[1], label="euclidean"
        )

    alike = G.compare(runs(0.08, 0.08))["contrasts"]["manhattan − euclidean"]["reached"]
    apart = G.compare(runs(0.16, 0.0))
    one = apart["contrasts"]["manhattan − euclidean"]["reached"]
    arms = apart["per_arm"]
    assert alike["difference"]["status"] == Q.EQUIVALENT
    assert one["difference"]["status"] == Q.DIFFERENT
    assert one["difference"]["estimate"] == pytest.approx(
        arms["manhattan"]["reached"]["difference"]["estimate"] - arms["euclidean"]["reached"]["difference"]["estimate"]
    )
    assert one["finer"] == pytest.approx(arms["manhattan"]["reached"]["finer"] - arms["euclidean"]["reached"]["finer"])


def test_a_candidate_that_moves_only_the_corners_is_seen_in_the_corners_zone(tmp_path):
    rng = np.random.default_rng(SEEDS[8])
    finer = _draw(rng, 1000, 0.5)
    runs = _sample_runs(tmp_path, finer, finer, finer)
    candidate = runs[0].candidate
    for record in candidate.records.values():  # every trial whose target is in a corner falls off
        if F.stratum(*F.cell_centre(record["cell"], 20)) == "corners":
            record.update(fell_off=True, reached=False, success=False, time_to_reach_s=None)
    report = G.compare(runs)
    zones = report["zones"]["manhattan"]
    assert list(zones) == list(F.STRATA) and sum(z["pairs"] for z in zones.values()) == 1000
    assert zones["corners"]["fell_off"]["low"] > 0.2  # the corners' falls, plain
    assert zones["centre"]["fell_off"]["low"] < 0 < zones["centre"]["fell_off"]["high"]
    assert report["per_arm"]["manhattan"]["fell_off"]["difference"]["estimate"] == pytest.approx(
        zones["corners"]["pairs"] / 1000 * (1 - zones["corners"]["fell_off"]["finer"])
    )


def test_flips_are_counted_against_each_floor_and_left_out_of_the_verdict(tmp_path):
    rng = np.random.default_rng(SEEDS[9])
    finer = _draw(rng, 1000, 0.5)
    candidate = _flip(finer, rng, 0.05)
    report = G.compare(_sample_runs(tmp_path, finer, candidate, finer))  # a floor that flips nothing
    (row,) = report["flips"]["manhattan"]
    assert row["shift_m"] == G.REPEATABILITY_M and row["pairs"] == 1000
    assert row["reached"]["floor"] == 0
    assert row["reached"]["candidate"] == sum(c[1] != f[1] for c, f in zip(candidate, finer, strict=True))
    assert row["reached"]["p"] < 0.01 and report["verdict"] != G.CHANGES  # more flips than the floor: not a verdict


def test_an_unfinished_sample_has_no_verdict(tmp_path):
    rng = np.random.default_rng(3)
    finer = _draw(rng, 200, 0.5)
    runs = _sample_runs(tmp_path, finer, finer[:150], finer)
    report = G.compare(runs)
    assert report["pairs"] == 150 and report["verdict"] is None and not report["complete"]
    assert "**Incomplete**" in G.report_markdown(
        {**report, "candidate": "c", "finer": "f", "sample_text": "s", "command": "mantaray"}
    )


@pytest.mark.parametrize(
    "field, value",
    [("object_name", "cube"), ("plant", "paper"), ("seed", 5), ("controller", "euclidean"), ("duration_s", 5.0)],
)
def test_the_gate_refuses_runs_of_other_trials_and_names_the_field(tmp_path, field, value):
    finer = _draw(np.random.default_rng(0), 200, 0.5)
    runs = _sample_runs(tmp_path, finer, finer, finer, **{field: value})
    with pytest.raises(G.GateMismatch, match=field):
        G.compare(runs)


def test_the_gate_refuses_a_floor_that_moved_nothing(tmp_path):
    finer = _draw(np.random.default_rng(0), 200, 0.5)
    run = _sample_runs(tmp_path, finer, finer, finer)[0]
    same = R.ResultsFile(tmp_path / "same.jsonl", run.finer.experiment, dict(run.finer.records))
    with pytest.raises(G.GateMismatch, match="moves no start"):
        G.compare([dataclasses.replace(run, floors=(same,))])


# ------------------------------------------------------------------------------------------- fidelities, arms, shift
def test_fidelities_parse_by_name_or_resolution_and_step_and_refuse_the_rest():
    assert G.parse_fidelity("fast") == G.Fidelity(11, 0.002)
    assert G.parse_fidelity("21:0.0005") == G.Fidelity(21, 0.0005)
    for bad in ("15", "15:x", "14:0.001", "15:0.5", "slow"):
        with pytest.raises(ValueError):
            G.parse_fidelity(bad)


def test_finer_is_six_vertices_a_side_more_at_half_the_step_of_the_fidelity_before_it():
    assert G.parse_fidelity("finer", G.Fidelity(15, 0.0005)) == G.Fidelity(21, 0.00025)
    assert G.parse_fidelity("finer", G.parse_fidelity("fast")) == G.Fidelity(17, 0.001)
    with pytest.raises(ValueError, match="give that fidelity before it"):
        G.parse_fidelity("finer")


def test_an_arm_is_a_controller_or_a_settings_file_and_nothing_else(tmp_path):
    assert G.Arm.parse("Euclidean") == G.Arm("euclidean", "euclidean")
    tuned = G.Arm.parse(str(Path(__file__).resolve().parents[1] / "docs/results/tune/sphere_cascade/settings.toml"))
    assert tuned.controller == "cascade" and tuned.settings and tuned.label.startswith("cascade-")
    with pytest.raises(ValueError, match="neither"):
        G.Arm.parse(str(tmp_path / "missing.toml"))
    with pytest.raises(ValueError, match="tuned for the paper plant"):
        G.GateSample(plant="polyester", arms=(tuned,))
    with pytest.raises(ValueError, match="each controller once"):
        G.GateSample(arms=(G.Arm.parse("manhattan"), G.Arm.parse("manhattan")))


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**31), cell=st.integers(0, 399), k=st.integers(0, 20), shift=st.floats(1e-6, 0.01))
def test_a_start_shift_moves_the_start_that_far_and_changes_nothing_else(seed, cell, k, shift):
    plain = E.Experiment(seed=seed)
    moved = E.make_trial(dataclasses.replace(plain, start_shift_m=shift), MODULE, cell, k)
    trial = E.make_trial(plain, MODULE, cell, k)
    assert (moved.cell, moved.k, moved.target_m, moved.seed) == (trial.cell, trial.k, trial.target_m, trial.seed)
    distance = math.dist(moved.start_m, trial.start_m)
    assert distance <= shift + 1e-12
    assert all(abs(v) <= 0.25 for v in moved.start_m)
    if all(abs(v) <= 0.25 - shift for v in trial.start_m):  # away from the workspace's edge: the full shift
        assert distance == pytest.approx(shift)


def test_results_files_written_before_the_start_shift_existed_read_as_unshifted():
    data = E.Experiment().to_json()
    del data["start_shift_m"]
    assert E.Experiment.from_json(data) == E.Experiment()


# ------------------------------------------------------------------------------------------- model identity
def _written(tmp_path) -> tuple[E.Experiment, Path, dict]:
    """A new results file's protocol, path and header, to be edited and written back with _rewrite."""
    experiment = E.Experiment(cells=2, trials_per_cell=1, duration_s=0.5)
    path = tmp_path / "results.jsonl"
    R.ResultsFile.open(path, experiment)
    return experiment, path, json.loads(path.read_text().split("\n", 1)[0])


def _rewrite(path: Path, header: dict) -> None:
    path.write_text(json.dumps(header) + "\n" + path.read_text().split("\n", 1)[1])


def test_a_results_file_of_another_model_is_not_continued_and_says_how_to_start_again(tmp_path):
    experiment, path, stored = _written(tmp_path)
    stored["model"]["mjcf_sha1"] = "0" * 16  # as if the generator had changed since
    _rewrite(path, stored)
    with pytest.raises(E.ExperimentMismatch, match="Start it again"):
        R.ResultsFile.open(path, experiment)
    del stored["model"]  # written before files recorded their model
    _rewrite(path, stored)
    with pytest.raises(E.ExperimentMismatch, match="before results files recorded"):
        R.ResultsFile.open(path, experiment)
    assert R.ResultsFile.load(path).experiment == experiment  # still read for figures and comparisons


def test_a_results_file_written_before_a_parameter_was_declared_continues_as_run_at_its_value(tmp_path):
    """sim/model/plant.toml: a parameter is added with the value that reproduces the model before it."""
    experiment, path, stored = _written(tmp_path)
    del stored["plant_values"]["fabric.stretch"]  # as a file written before it was declared
    _rewrite(path, stored)
    assert R.ResultsFile.open(path, experiment).plant_values["fabric.stretch"] == "edges"
    stored["plant_values"]["fabric.stretch"] = "threads"  # but a value it did record is held to
    _rewrite(path, stored)
    with pytest.raises(E.ExperimentMismatch, match="fabric.stretch differ"):
        R.ResultsFile.open(path, experiment)


# ------------------------------------------------------------------------------------------- the command
def _gate(tmp_path, *extra):
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "fidelity",
            "--candidate",
            "5:0.002",
            "--finer",
            "7:0.002",
            "--cells-per-stratum",
            "1",
            "--trials-per-cell",
            "1",
            "--duration",
            "0.5",
            "--trials-dir",
            str(tmp_path / "trials"),
            "--out",
            str(tmp_path / "gate"),
            "--jobs",
            "1",
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_command_runs_the_three_runs_writes_its_report_and_resumes_without_rerunning(tmp_path):
    first = _gate(tmp_path, "--controller", "manhattan")
    assert first.returncode in (0, 1, 3), first.stderr
    files = sorted((tmp_path / "trials").iterdir())
    assert [f.name.split("seed77_")[1] for f in files] == ["5x5_2ms.jsonl", "7x7_2ms.jsonl", "7x7_2ms_moved2mm.jsonl"]
    report = json.loads((tmp_path / "gate" / "report.json").read_text())
    assert report["pairs"] == 5 and report["verdict"] in (G.KEEPS, G.CHANGES, G.UNDECIDED)
    page = (tmp_path / "gate" / "report.md").read_text()
    assert "## Per controller" in page and "## Per zone" in page and "| manhattan | 2 mm | 5 |" in page
    before = {f: f.read_bytes() for f in files}
    again = _gate(tmp_path, "--controller", "manhattan")
    assert again.returncode == first.returncode
    assert {f: f.read_bytes() for f in files} == before  # nothing ran twice
    assert json.loads((tmp_path / "gate" / "report.json").read_text())["per_arm"] == report["per_arm"]


def test_report_only_judges_what_is_there_and_writes_no_run(tmp_path):
    done = _gate(tmp_path, "--controller", "manhattan", "--report-only")
    assert done.returncode == 3 and "incomplete (0 of 5" in done.stdout, done.stderr
    assert not (tmp_path / "trials").exists() or not list((tmp_path / "trials").iterdir())


def test_until_decided_grows_the_sample_to_its_most_pairs_and_says_so(tmp_path):
    grown = _gate(tmp_path, "--controller", "manhattan", "--until-decided", "--max-pairs", "10")
    assert grown.returncode == 3 and "growing the sample to 2 trials per cell (10 pairs)" in grown.stderr
    assert "and it stays so" in grown.stderr and "Traceback" not in grown.stderr, grown.stderr
    report = json.loads((tmp_path / "gate" / "report.json").read_text())
    assert report["pairs"] == 10 and report["verdict"] == G.UNDECIDED and report["complete"]
    assert "x 2 trials" in report["sample_text"]


def test_the_command_says_what_is_wrong_with_its_input_in_one_line(tmp_path):
    for extra, said in (
        (("--candidate", "14:0.002"), "odd"),
        (("--controller", "nonsense"), "neither"),
        (("--shift", "0.5"), "start shift"),
        (("--shift", "0"), "must move every start"),
        (("--candidate", "7:0.002"), "nothing to compare"),
        (("--set", "fabric.stretch=wool"), "fabric.stretch must be one of edges, threads"),
        (("--set", "fabric.stretch"), "expected KEY=VALUE"),
        (("--shift", "0.002", "--shift", "0.002"), "each shift once"),
        (("--runs", "only.jsonl"), "--runs takes"),
        (("--max-pairs", "0"), "--max-pairs"),
        (("--candidate-only", "--until-decided"), "not allowed with argument"),
        (("--candidate-only",), "run the gate without it first"),
    ):
        run = _gate(tmp_path, *extra)
        assert run.returncode == 2 and said in run.stderr and "Traceback" not in run.stderr, run.stderr


def test_values_fixed_over_the_plant_go_into_every_run_and_name_its_trials_apart(tmp_path):
    fixed = (("fabric.stretch", "threads"),)
    sample = G.GateSample(plant_set=fixed, arms=(G.Arm("manhattan", "manhattan"),))
    plain = G.GateSample(arms=(G.Arm("manhattan", "manhattan"),))
    fidelity = G.parse_fidelity("15:0.001")
    arm = sample.arms[0]
    assert sample.experiment(arm, fidelity).plant_model().rig().fabric.stretch == "threads"
    assert plain.experiment(arm, fidelity).plant_model().rig().fabric.stretch == "edges"
    assert sample.results_path(tmp_path, arm, fidelity) != plain.results_path(tmp_path, arm, fidelity)
    assert "fabric.stretch=threads" in sample.results_path(tmp_path, arm, fidelity).name
    assert sample.plant_label == "polyester with fabric.stretch=threads"


class _Stop(Exception):
    pass


def _gate_stopped_after(tmp_path, records: int):
    """(sample, runs) of a 5 x 5 against 7 x 7 gate with a 0.1 mm floor, stopped once `records` trials finished."""
    sample = G.GateSample(
        arms=(G.Arm("manhattan", "manhattan"),), cells_per_stratum=2, trials_per_cell=2, duration_s=0.2
    )
    runs = G.open_runs(sample, G.parse_fidelity("5:0.002"), G.parse_fidelity("7:0.002"), tmp_path, (1e-4,))
    seen = []

    def stop(record):
        seen.append(record)
        if len(seen) == records:
            raise _Stop

    with pytest.raises(_Stop):
        G.run_missing(sample, runs, 1, on_record=stop)
    return sample, runs


def test_a_gate_stopped_part_way_holds_the_same_stratified_trials_in_each_run(tmp_path):
    sample, runs = _gate_stopped_after(tmp_path, 6)  # two positions of the run order, in each of the three runs
    files = [R.ResultsFile.open(f.path, f.experiment) for f in runs[0].files()]
    keys = [set(f.records) for f in files]
    assert keys[0] == keys[1] == keys[2] and len(keys[0]) == 2  # the same two trials in each run
    drawn = list(F.stratified_draw(E.Experiment.cells, 2, sample.seed).values())
    assert keys[0] == {f"{drawn[0][0]}:0", f"{drawn[1][0]}:0"}  # the first drawn cell of two strata, first trial


def test_candidate_only_runs_the_candidate_on_the_trials_the_finer_run_holds_and_leaves_it_untouched(tmp_path):
    """A second candidate judged on a finer run stopped part way: it runs only those trials, reads the finer run and
    its floor without holding them (a gate adding to them may run beside), and writes nothing to them."""
    import fcntl

    sample, runs = _gate_stopped_after(tmp_path, 9)  # three positions of the run order, in each of the three runs
    finer = G.parse_fidelity("7:0.002")
    held = {f.path: f.path.read_bytes() for f in (runs[0].finer, *runs[0].floors)}
    R._release(os.getpid())  # as if the first gate were another process ...
    R._HELD.clear()
    locks = [open(path.with_name(path.name + ".lock"), "w") for path in held]
    for lock in locks:  # ... that holds its runs still
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    other = G.open_runs(sample, G.parse_fidelity("5:0.001"), finer, tmp_path, (1e-4,), candidate_only=True)
    assert G.missing_trials(other, candidate_only=True) == 3
    G.run_missing(sample, other, 1, candidate_only=True)
    assert set(other[0].candidate.records) == set(runs[0].finer.records) and len(runs[0].finer.records) == 3
    assert {path: path.read_bytes() for path in held} == held
    report = G.compare(other)
    assert report["pairs"] == 3 and report["verdict"] is None  # the sample is not complete: no verdict
    for lock in locks:
        lock.close()


def test_candidate_only_refuses_a_finer_run_that_does_not_exist_or_is_another_one(tmp_path):
    sample = G.GateSample(arms=(G.Arm("manhattan", "manhattan"),), cells_per_stratum=1, trials_per_cell=1)
    candidate, finer = G.parse_fidelity("5:0.001"), G.parse_fidelity("7:0.002")
    with pytest.raises(ValueError, match="run the gate without it first"):
        G.open_runs(sample, candidate, finer, tmp_path, (1e-4,), candidate_only=True)
    longer = dataclasses.replace(sample, duration_s=5.0)
    for shift_m in (0.0, 1e-4):  # a finer run and floor of another duration lie where this sample's would
        R.ResultsFile.open(
            sample.results_path(tmp_path, sample.arms[0], finer, shift_m),
            longer.experiment(sample.arms[0], finer, shift_m),
        )
    with pytest.raises(E.ExperimentMismatch, match="duration_s"):
        G.open_runs(sample, candidate, finer, tmp_path, (1e-4,), candidate_only=True)


def test_a_runner_keeps_the_models_a_gate_alternates_loaded_once_each():
    """A gate's trials alternate two meshes on each worker: each model is loaded once, not once a trial."""
    from mantaray.sim.evaluation.executors import TrialRunner

    sample = G.GateSample(arms=(G.Arm("manhattan", "manhattan"),), duration_s=0.2)
    coarse, fine = (sample.experiment(sample.arms[0], G.parse_fidelity(f)) for f in ("5:0.002", "7:0.002"))
    runner = TrialRunner()
    first = runner._bridge(coarse), runner._bridge(fine)
    again = runner._bridge(coarse), runner._bridge(fine)
    assert first[0] is again[0] and first[1] is again[1] and first[0] is not first[1]
    assert (first[0].rig.fabric.resolution, first[1].rig.fabric.resolution) == (5, 7)


def test_an_interrupted_gate_reports_the_trials_paired_so_far_without_a_verdict(tmp_path):
    import signal
    import time

    args = [sys.executable, "-m", "mantaray.cli", "sim", "fidelity", "--candidate", "5:0.002", "--finer", "7:0.002"]
    args += ["--cells-per-stratum", "2", "--trials-per-cell", "2", "--duration", "10", "--controller", "manhattan"]
    args += ["--trials-dir", str(tmp_path / "trials"), "--out", str(tmp_path / "gate"), "--jobs", "1"]
    gate = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:  # interrupt once the three runs hold a few trials between them
        time.sleep(0.2)
        if sum(p.read_text().count("\n") - 1 for p in (tmp_path / "trials").glob("*.jsonl")) >= 4:
            break
    gate.send_signal(signal.SIGINT)
    out, err = gate.communicate(timeout=120)
    assert gate.returncode == 130 and "Traceback" not in err, err
    report = json.loads((tmp_path / "gate" / "report.json").read_text())
    assert report["verdict"] is None and 1 <= report["pairs"] < report["expected_pairs"] == 20
    assert "**Incomplete**" in (tmp_path / "gate" / "report.md").read_text()
    assert f"the report of the {report['pairs']} paired so far" in err
