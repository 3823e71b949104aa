"""Adaptive heatmaps: a cell's trials stop once the region its N trials would put it in is decided at 95 %.

The run goes in rounds: round r runs trial r of every cell still open. Every cell runs MIN_TRIALS; after that a cell
closes at round r when, on each map a run draws (ends within ε at T, and reached, the paper's reading), given its k
successes in r trials, the region of its rate at N trials (success >= 0.9, failure <= 0.1, uncertain between:
sim/evaluation/summary.py) is the region of k / r with a predictive probability of at least LEVEL. The prediction is empirical Bayes: the prior of a cell's success rate is the one that best explains every
cell's first r trials (the nonparametric maximum-likelihood mixture on a grid of rates, by EM), so a map whose
cells are mostly all-or-nothing closes its cells sooner than a map of middling ones. Which trials a round runs is a
function of the trials of the rounds before it alone, so a run interrupted part way and continued runs the same
trials as one that was not, and an adaptive run's trials are each cell's first trials of the full run of the same
seed (trials are drawn from (seed, cell, k): sim/evaluation/experiment.py).
"""

from __future__ import annotations

from math import comb

import numpy as np

from .summary import FAILURE_REGION_AT, SUCCESS_REGION_AT

MIN_TRIALS = 2  # [-] trials every cell runs before any may close
LEVEL = 0.95  # [-] the predictive probability a cell's region must reach for it to close
RATES = np.linspace(0.005, 0.995, 100)  # [-] the success rates the cells' prior is spread over
EM_ITERATIONS = 200
MAPS = ("success", "reached")  # the records' outcomes whose maps a cell's region must be decided on


def region(k: int, n: int) -> int:
    """0 failure, 1 uncertain, 2 success: the region of k successes in n trials (as sim/evaluation/summary.py draws it)."""
    rate = k / n
    return 2 if rate >= SUCCESS_REGION_AT else 0 if rate <= FAILURE_REGION_AT else 1


def _binomial(k: int, n: int, p: np.ndarray) -> np.ndarray:
    return comb(n, k) * p**k * (1 - p) ** (n - k)


def fit_prior(counts: list[tuple[int, int]]) -> np.ndarray:
    """The weights over RATES that best explain the cells' (successes, trials): the mixing distribution's maximum
    likelihood, by EM from a uniform start."""
    weights = np.full(len(RATES), 1 / len(RATES))
    if not counts:
        return weights
    likelihood = np.array([_binomial(k, n, RATES) for k, n in counts])  # [cells, rates]
    for _ in range(EM_ITERATIONS):
        posterior = likelihood * weights
        posterior /= posterior.sum(axis=1, keepdims=True)
        weights = posterior.mean(axis=0)
    return weights


def final_regions(prior: np.ndarray, k: int, n: int, trials_per_cell: int) -> np.ndarray:
    """[3] the probability of each region (failure, uncertain, success) at trials_per_cell trials, given k
    successes in the first n."""
    posterior = prior * _binomial(k, n, RATES)
    posterior /= posterior.sum()
    left = trials_per_cell - n
    p = np.zeros(3)
    for more in range(left + 1):
        p[region(k + more, trials_per_cell)] += posterior @ _binomial(more, left, RATES)
    return p


def decided(prior: np.ndarray, k: int, n: int, trials_per_cell: int) -> bool:
    """Whether a cell of k successes in n trials closes: its region now is its region at trials_per_cell trials
    with a probability of at least LEVEL."""
    return n >= trials_per_cell or final_regions(prior, k, n, trials_per_cell)[region(k, n)] >= LEVEL


def open_cells(cells: list[int], records: dict[str, dict], trials_per_cell: int, r: int) -> list[int]:
    """The cells whose trial r round r runs: every cell below MIN_TRIALS; after, each cell that ran every round
    before and whose region is not decided on both maps a run draws (ends within ε at T, and reached: the paper's
    reading), each map with its own prior, judged on the trials of rounds before r alone (those of round r, where it
    was interrupted part way, are not yet evidence)."""
    if r < MIN_TRIALS:
        return list(cells)
    members = set(cells)
    before = [record for record in records.values() if record["k"] < r and record["cell"] in members]
    ran = {c: 0 for c in cells}
    for record in before:
        ran[record["cell"]] += 1
    still = [c for c in cells if ran[c] == r]

    def decided_on(key: str) -> set[int]:
        successes = {c: 0 for c in cells}
        for record in before:
            successes[record["cell"]] += bool(record[key])
        prior = fit_prior([(successes[c], ran[c]) for c in cells if ran[c]])
        return {c for c in still if decided(prior, successes[c], r, trials_per_cell)}

    done = set.intersection(*(decided_on(key) for key in MAPS))
    return [c for c in still if c not in done]


def trials_left(cells: list[int], trials_per_cell: int, r: int) -> int:
    """The most trials the open cells of round r may still run, round r's included."""
    return len(cells) * (trials_per_cell - r)


def twin(records: dict[str, dict], cells: list[int], trials_per_cell: int) -> dict[str, dict]:
    """The records an adaptive run holds whose full run of the same seed holds these: round by round, the trials
    of the open cells, each the full run's own (an adaptive run's trials are each cell's first ones)."""
    kept: dict[str, dict] = {}
    for r in range(trials_per_cell):
        for cell in open_cells(cells, kept, trials_per_cell, r):
            kept[f"{cell}:{r}"] = records[f"{cell}:{r}"]
    return kept
