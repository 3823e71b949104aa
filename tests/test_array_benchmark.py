"""The array-against-one-module benchmark's fairness (benchmarks/experiments/array_vs_module.py): paired trials that
cross modules, two rigs with the same sheet, and failures classified by what happened."""

from __future__ import annotations

import importlib.util
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mantaray.paths import REPO
from mantaray.sim.model import mjcf as J

_spec = importlib.util.spec_from_file_location("array_vs_module", REPO / "benchmarks/experiments/array_vs_module.py")
B = sys.modules["array_vs_module"] = importlib.util.module_from_spec(_spec)  # dataclasses look their module up
_spec.loader.exec_module(B)


@given(st.integers(0, 2**31), st.integers(1, 6))
def test_every_trial_starts_in_one_module_and_aims_into_another_drawn_from_the_seed_alone(seed, trials):
    drawn = B.cases(["sphere", "cube"], trials, seed)
    assert drawn == B.cases(["sphere", "cube"], trials, seed)  # both rigs run these very trials
    for case in drawn:
        start, target = B.GRID.module_at(*case.start_m), B.GRID.module_at(*case.target_m)
        assert start is not None and target is not None and start != target
        for point, module, half in ((case.start_m, start, B.START_HALF_M), (case.target_m, target, B.TARGET_HALF_M)):
            cx, cy = B.GRID.module_centre(module)
            assert abs(point[0] - cx) <= half and abs(point[1] - cy) <= half


def test_the_big_module_has_the_arrays_sheet_and_surface():
    """Same vertices a side, as far apart, as heavy and joined by edges of the same time constant; the same surface;
    4 actuators against 9."""
    array, module = B.simulated_rig("array", "sphere", 11, 0.002), B.simulated_rig("module", "sphere", 11, 0.002)
    assert J.sheet_vertices(array) == J.sheet_vertices(module) == (21, 21)
    assert array.fabric.spacing_m == pytest.approx(module.fabric.spacing_m)
    assert array.fabric.edge_timeconst_s == pytest.approx(module.fabric.edge_timeconst_s)
    array_sheet_kg = array.fabric.mass_kg * array.module.grid.module_count
    assert module.fabric.mass_kg == pytest.approx(array_sheet_kg)
    assert array.module.grid.half_extent_m == module.module.grid.half_extent_m == (0.5, 0.5)
    assert (array.module.grid.actuator_count, module.module.grid.actuator_count) == (9, 4)


def _record(**changes) -> dict:
    record = {
        "success": False,
        "fell_off": False,
        "sim_time_s": 20.0,
        "handover_s": [4.0],
        "handovers": 1,
        "start_m": [-0.25, -0.25],  # module 0
        "target_m": [0.25, -0.25],  # module 1: one shared edge away
        "final_xy_m": [0.24, -0.25],
    }
    return {**record, **changes}


@pytest.mark.parametrize(
    "changes, why",
    [
        ({"success": True}, None),
        ({"fell_off": True, "sim_time_s": 5.0}, "fell at a hand-over"),
        ({"fell_off": True, "sim_time_s": 9.0}, "fell elsewhere"),
        ({"handovers": 3, "handover_s": [4.0, 5.0, 6.0]}, "handed back"),
        ({"final_xy_m": [-0.1, -0.25]}, "short of the target's module"),
        ({}, "in the target's module, not within epsilon at T"),
    ],
)
def test_a_failed_trial_is_classified_by_what_happened(changes, why):
    assert B.failure(_record(**changes)) == why
