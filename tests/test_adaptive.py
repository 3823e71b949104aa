"""Adaptive heatmaps: the stopping rule on drawn outcomes, its rounds resumed part way, its twin of a full run, and
the command's run against the full run of the same seed."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.sim.evaluation import adaptive as A
from mantaray.sim.evaluation import experiment as E
from mantaray.sim.evaluation import results_file as R

N = 10


def _records(outcomes: dict[int, list[bool]]) -> dict[str, dict]:
    """Records of these outcomes, reached where they end within ε (as a run stopped when reached records them)."""
    return {
        f"{c}:{k}": {"cell": c, "k": k, "success": s, "reached": s}
        for c, o in outcomes.items()
        for k, s in enumerate(o)
    }


def _drawn_map(seed: int, cells: int = 60) -> dict[int, list[bool]]:
    """Cells of a map: mostly all-or-nothing, some middling, as heatmaps are."""
    rng = np.random.default_rng(seed)
    rates = rng.choice([0.0, 0.02, 0.5, 0.98, 1.0], size=cells, p=[0.35, 0.1, 0.15, 0.1, 0.3])
    return {c: list(rng.random(N) < p) for c, p in enumerate(rates)}


@settings(max_examples=100, deadline=None)
@given(
    weights=st.lists(st.floats(0.0, 1.0), min_size=len(A.RATES), max_size=len(A.RATES)).filter(lambda w: sum(w) > 0),
    n=st.integers(1, N - 1),
    data=st.data(),
)
def test_the_regions_at_n_trials_are_a_distribution_and_a_region_already_certain_is_decided(weights, n, data):
    prior = np.array(weights) / sum(weights)
    k = data.draw(st.integers(0, n))
    p = A.final_regions(prior, k, n, N)
    assert p.min() >= 0 and p.sum() == pytest.approx(1.0)
    possible = {A.region(k + more, N) for more in range(N - n + 1)}
    if possible == {A.region(k, n)}:  # every way the rest can go leaves it there
        assert A.decided(prior, k, n, N)
    if A.region(k, n) not in possible:  # a region it cannot end in is never decided
        assert not A.decided(prior, k, n, N)


def test_a_map_of_all_or_nothing_cells_closes_them_after_the_minimum_and_a_split_cell_runs_on():
    outcomes = {c: [c % 2 == 0] * N for c in range(40)}
    outcomes[40] = [True, False] * 5
    kept = A.twin(_records(outcomes), list(outcomes), N)
    counts = {c: sum(1 for r in kept.values() if r["cell"] == c) for c in outcomes}
    assert all(counts[c] == A.MIN_TRIALS for c in range(40))
    assert A.MIN_TRIALS < counts[40] <= 4  # certain to be uncertain once it holds 2 of each


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_twin_saves_trials_keeps_most_regions_and_never_runs_a_cell_past_n(seed):
    outcomes = _drawn_map(seed)
    kept = A.twin(_records(outcomes), list(outcomes), N)
    counts = {c: sum(1 for r in kept.values() if r["cell"] == c) for c in outcomes}
    assert all(A.MIN_TRIALS <= n <= N for n in counts.values())
    assert all(f"{c}:{k}" in kept for c, n in counts.items() for k in range(n))  # each cell's first trials
    moved = sum(A.region(sum(o[: counts[c]]), counts[c]) != A.region(sum(o), N) for c, o in outcomes.items())
    assert len(kept) < 0.5 * N * len(outcomes) and moved <= 0.1 * len(outcomes)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**16), r=st.integers(A.MIN_TRIALS, N - 1), part=st.floats(0.0, 1.0))
def test_a_round_interrupted_part_way_opens_the_same_cells_when_continued(seed, r, part):
    outcomes = _drawn_map(seed, cells=30)
    cells = list(outcomes)
    before = {key: rec for key, rec in A.twin(_records(outcomes), cells, N).items() if rec["k"] < r}
    opened = A.open_cells(cells, before, N, r)
    partly = dict(before)
    for c in opened[: int(part * len(opened))]:  # some of round r's trials finished before the stop
        partly[f"{c}:{r}"] = {"cell": c, "k": r, "success": outcomes[c][r], "reached": outcomes[c][r]}
    assert A.open_cells(cells, partly, N, r) == opened


def test_an_adaptive_run_needs_more_trials_than_the_minimum_and_is_never_merged_with_a_full_run(tmp_path):
    with pytest.raises(ValueError, match="more than 2 trials"):
        E.Experiment(adaptive=True, trials_per_cell=2)
    full = E.Experiment(cells=2, trials_per_cell=4, resolution=5, timestep_s=0.002)
    R.ResultsFile.open(tmp_path / "results.jsonl", full)
    with pytest.raises(E.ExperimentMismatch, match="adaptive"):
        R.ResultsFile.open(tmp_path / "results.jsonl", E.Experiment(**{**full.__dict__, "adaptive": True}))


def _heatmap(out, *extra):
    args = [sys.executable, "-m", "mantaray.cli", "sim", "heatmap", "--cells", "3", "--trials", "4", "--duration"]
    args += ["2", "--resolution", "5", "--timestep", "0.002", "--jobs", "1", "--seed", "5", "--out", str(out)]
    return subprocess.run([*args, *extra], capture_output=True, text=True, timeout=300)


def test_the_command_runs_the_twin_of_the_full_run_of_its_seed_and_says_what_it_saved(tmp_path):
    full = _heatmap(tmp_path / "full")
    assert full.returncode == 0, full.stderr
    adaptive = _heatmap(tmp_path / "adaptive", "--adaptive", "--json")
    assert adaptive.returncode == 0 and "Traceback" not in adaptive.stderr, adaptive.stderr
    records = {n: R.ResultsFile.load(tmp_path / n / "results.jsonl").records for n in ("full", "adaptive")}
    drop = ("wall_time_s", "physics_wall_s")

    def same(r):
        return {k: v for k, v in r.items() if k not in drop}

    expected = A.twin(records["full"], list(range(9)), 4)
    assert {k: same(r) for k, r in records["adaptive"].items()} == {k: same(r) for k, r in expected.items()}
    summary = json.loads(adaptive.stdout)
    assert summary["trials"] == len(expected) < 36 and summary["protocol"]["adaptive"] is True
