"""The paper's findings F1-F6 computed from synthetic trial records: zones, strata, the shape index, totals, verdicts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.sim.evaluation import findings as F

CELLS = 20


def _records(rate_of, seed=0, trials=10, cells=None):
    """Synthetic records: for each cell, `trials` trials whose target is the cell's centre and whose outcome is
    drawn with probability rate_of(x, y) (deterministic from the seed)."""
    rng = np.random.default_rng(seed)
    out = []
    for cell in range(CELLS * CELLS) if cells is None else cells:
        x, y = F.cell_centre(cell, CELLS)
        for k in range(trials):
            ok = bool(rng.random() < rate_of(x, y))
            out.append({"cell": cell, "k": k, "target_m": [x, y], "success": ok, "reached": ok, "fell_off": not ok})
    return out


def test_the_strata_partition_the_grid_as_declared():
    strata = F.strata_cells(CELLS)
    assert sum(len(v) for v in strata.values()) == CELLS * CELLS
    assert len(strata["centre"]) == 64 and len(strata["corners"]) == 36 and len(strata["edges"]) == 168
    for name, cells in strata.items():
        for c in cells:
            x, y = F.cell_centre(c, CELLS)
            assert F.stratum(x, y) == name


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), per=st.integers(1, 8))
def test_a_stratified_sample_draws_from_every_stratum_from_the_seed_alone(seed, per):
    sample = F.stratified_sample(CELLS, per, seed)
    assert sample == F.stratified_sample(CELLS, per, seed)
    assert len(set(sample)) == len(sample) == per * len(F.STRATA)
    drawn = [F.stratum(*F.cell_centre(c, CELLS)) for c in sample]
    assert all(drawn.count(name) == per for name in F.STRATA)


def test_the_rule_picks_the_outcome_and_an_unknown_rule_is_refused():
    record = {"success": False, "reached": True}
    assert F.outcome(record, "reached") and not F.outcome(record, "end")
    with pytest.raises(ValueError, match="success rule"):
        F.outcome(record, "sometimes")


def test_central_and_corner_rates_count_trials_by_their_target():
    records = _records(lambda x, y: 1.0 if max(abs(x), abs(y)) < 0.1 else 0.0)
    stats = F.map_stats(records, CELLS, "end")
    assert stats.central_rate == 1.0 and stats.corner_rate == 0.0
    corner_only = _records(lambda x, y: 1.0 if min(abs(x), abs(y)) > 0.175 else 0.0)
    assert F.map_stats(corner_only, CELLS, "reached").corner_rate == 1.0


def test_a_full_map_totals_the_sum_of_its_cell_rates():
    records = _records(lambda x, y: max(0.0, 1 - 4 * math.hypot(x, y)), seed=3)
    stats = F.map_stats(records, CELLS, "end")
    rates = {}
    for r in records:
        rates.setdefault(r["cell"], []).append(r["success"])
    assert stats.total == pytest.approx(sum(np.mean(v) for v in rates.values()))


def test_a_stratified_sample_estimates_the_total_of_a_map_constant_within_strata():
    level = {"centre": 1.0, "axes": 0.6, "diagonals": 0.4, "edges": 0.2, "corners": 0.1}
    exact = sum(len(v) * level[k] for k, v in F.strata_cells(CELLS).items())
    sample = F.stratified_sample(CELLS, 4, seed=5)
    sampled = []  # ten trials a cell with exactly the stratum's rate
    for c in sample:
        x, y = F.cell_centre(c, CELLS)
        n = 10
        hits = round(level[F.stratum(x, y)] * n)
        sampled += [
            {"cell": c, "k": k, "target_m": [x, y], "success": k < hits, "reached": k < hits, "fell_off": False}
            for k in range(n)
        ]
    assert F.map_stats(sampled, CELLS, "end").total == pytest.approx(exact)


@pytest.mark.parametrize("norm, sign", [(lambda x, y: max(abs(x), abs(y)), 1), (lambda x, y: abs(x) + abs(y), -1)])
def test_the_shape_index_tells_a_square_map_from_a_diamond(norm, sign):
    records = _records(lambda x, y: float(np.clip(1.5 - 6 * norm(x, y), 0, 1)), seed=11)
    q = F.map_stats(records, CELLS, "end").shape_index
    assert np.sign(q) == sign and abs(q) > 0.02


def test_the_findings_hold_on_a_map_made_to_match_the_paper_and_fail_on_a_swapped_one():
    # A square map (rate falling with the L-inf norm) totalling ~174 whose corners stay above 10 %, and a
    # diamond (falling with the L1 norm) totalling ~106 with empty corners: the paper's Fig. 2a-b in outline.
    square = lambda x, y: float(np.clip((0.25 - max(abs(x), abs(y))) / 0.19, 0, 1))  # noqa: E731
    diamond = lambda x, y: float(np.clip((0.21 - abs(x) - abs(y)) / 0.06, 0, 1))  # noqa: E731
    m = F.map_stats(_records(square, seed=1, trials=20), CELLS, "end")
    e = F.map_stats(_records(diamond, seed=2, trials=20), CELLS, "end")
    verdicts = {f.name: f.holds for f in F.heatmap_findings(m, e)}
    assert verdicts == {"F1": True, "F2": True, "F3": True, "F4": True, "F5": True}, F.heatmap_findings(m, e)
    assert F.objectives(m, e)[:2] == (0.0, 0.0) and F.objectives(m, e)[2] < 2 * math.log(1.2)
    swapped = {f.name: f.holds for f in F.heatmap_findings(e, m)}
    assert not swapped["F2"] and not swapped["F4"]
    assert F.objectives(e, m)[1] > 0


def test_f1_fails_when_one_controller_misses_central_targets():
    good = F.map_stats(_records(lambda x, y: 1.0), CELLS, "end")
    poor = F.map_stats(_records(lambda x, y: 0.5, seed=4), CELLS, "end")
    assert not F.heatmap_findings(good, poor)[0].holds
    assert F.objectives(good, poor)[0] == pytest.approx(0.9 - poor.central_rate)


def test_f6_needs_every_object_five_times_and_every_trial_reached():
    full = [{"object": name, "reached": True, "fell_off": False} for name in F.FIG3_ALPHA_M for _ in range(5)]
    assert F.fig3_finding(full).holds
    one_fell = full[:-1] + [{"object": "bunny", "reached": True, "fell_off": True}]
    assert not F.fig3_finding(one_fell).holds
    assert not F.fig3_finding(full[5:]).holds  # the sphere's five missing
    assert F.fig3_finding([]).holds is None


def test_a_measure_the_trials_cannot_give_makes_its_objective_nan_not_zero():
    only_centre = F.map_stats(_records(lambda x, y: 1.0, cells=F.strata_cells(CELLS)["centre"]), CELLS, "end")
    assert math.isnan(only_centre.corner_rate) and math.isnan(only_centre.total)
    central, corners, totals = F.objectives(only_centre, only_centre)
    assert central == 0.0 and math.isnan(corners) and math.isnan(totals)


def test_totals_are_scaled_to_the_papers_400_cells():
    ten = [
        {"cell": c, "k": 0, "target_m": list(F.cell_centre(c, 10)), "success": True, "reached": True, "fell_off": False}
        for c in range(100)
    ]
    assert F.map_stats(ten, 10, "end").total == pytest.approx(400.0)  # every cell of a 10 x 10 grid succeeds


def test_a_map_with_one_rate_everywhere_has_no_shape():
    assert F.map_stats(_records(lambda x, y: 0.0), CELLS, "end").shape_index == 0.0
