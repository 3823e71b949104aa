"""The paired comparison of a tuned controller's trials with the paper's (McNemar's counts and z, the outer band's
falls: sim/evaluation/paired.py, what benchmarks/experiments/beyond_paper.py publishes), and the committed trials a run starts from
(sim/evaluation/committed.py)."""

import gzip
import math

from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.sim.evaluation import committed as K
from mantaray.sim.evaluation import paired as B

FLAGS = ("success", "reached", "fell_off")
record = st.fixed_dictionaries(
    {
        "success": st.booleans(),
        "reached": st.booleans(),
        "fell_off": st.booleans(),
        "target_m": st.tuples(st.floats(-0.25, 0.25), st.floats(-0.25, 0.25)),
    }
)
trials = st.dictionaries(st.tuples(st.integers(0, 399), st.integers(0, 9)), record, max_size=60)


@settings(max_examples=200, deadline=None)
@given(trials, trials, st.sampled_from(FLAGS))
def test_mcnemar_counts_the_discordant_pairs_of_the_common_trials(a, b, key):
    out = B.mcnemar(a, b, key)
    common = set(a) & set(b)
    pairs = [(a[k][key], b[k][key]) for k in common]
    only_a, only_b = pairs.count((True, False)), pairs.count((False, True))
    assert (out["paired"], out["only_tuned"], out["only_paper"]) == (len(common), only_a, only_b)
    expected_z = (only_a - only_b) / math.sqrt(only_a + only_b) if only_a + only_b else 0.0
    assert out["z"] == round(expected_z, 2)
    swapped = B.mcnemar(b, a, key)  # the test is antisymmetric: swapping the controllers flips the sign
    assert (swapped["only_tuned"], swapped["only_paper"], swapped["z"]) == (only_b, only_a, -out["z"])


@settings(max_examples=200, deadline=None)
@given(trials, trials)
def test_edge_falls_counts_only_the_outer_band(a, b):
    out = B.edge_falls(a, b)
    band = [k for k in set(a) & set(b) if max(abs(v) for v in a[k]["target_m"]) > 0.20]
    kept = [k for k in band if b[k]["fell_off"] and not a[k]["fell_off"]]
    assert (out["trials"], out["kept_on_by_tuned"]) == (len(band), len(kept))
    assert out["of_those_reached"]["tuned"] == sum(a[k]["reached"] for k in kept)
    for name, rec in (("tuned", a), ("paper_manhattan", b)):
        assert out[f"fell_{name}"]["trials"] == sum(rec[k]["fell_off"] for k in band)
        assert out[f"fell_{name}"]["reached_first"] == sum(rec[k]["fell_off"] and rec[k]["reached"] for k in band)


def test_restore_starts_from_the_committed_trials_once_and_never_over_what_out_holds(tmp_path):
    committed = tmp_path / "committed.jsonl.gz"
    committed.write_bytes(gzip.compress(b'{"header": 1}\n{"key": "0:0"}\n'))
    results = tmp_path / "out" / "run" / "results.jsonl"  # out/ and the run's folder do not exist yet
    assert K.restore(results, committed)
    assert K.trials_in(results) == 1
    results.write_bytes(b'{"header": 1}\n{"key": "0:0"}\n{"key": "0:1"}\n')  # the run went on
    assert not K.restore(results, committed)
    assert K.trials_in(results) == 2
    assert not K.restore(tmp_path / "other" / "results.jsonl", tmp_path / "none.jsonl.gz")
