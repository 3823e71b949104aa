"""Paired comparisons of two runs of the same trials: McNemar's exact test on a yes/no outcome, bootstraps on a number."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

BOOTSTRAP_DRAWS = 20000  # resamples of the paired differences behind each interval (50 beyond a 0.25 % tail)
MIN_BOOTSTRAP_N = 20  # fewer differences than this give no interval: a percentile bootstrap of a handful
# never reaches past their extremes, so it would call any one-signed handful a bias


def binomial_tail(k: int, n: int) -> float:
    """P(X >= k) for X ~ Binomial(n, 1/2): the chance of k or more heads in n fair tosses."""
    if k <= 0:
        return 1.0
    return math.fsum(math.comb(n, i) for i in range(k, n + 1)) / 2.0**n


@dataclass(frozen=True)
class Discordance:
    """A yes/no outcome on paired trials: how often it holds in a alone and in b alone, and McNemar's exact test."""

    pairs: int
    only_a: int
    only_b: int

    @property
    def flips(self) -> int:
        """Pairs whose outcome differs between the two runs."""
        return self.only_a + self.only_b

    @property
    def p_two_sided(self) -> float:
        """McNemar's exact p: how likely a split of the flips at least this uneven is when neither run is favoured."""
        if self.flips == 0:
            return 1.0
        return min(1.0, 2.0 * binomial_tail(max(self.only_a, self.only_b), self.flips))

    @property
    def p_more_in_a(self) -> float:
        """One-sided exact p that the outcome holds more often in a than in b."""
        return binomial_tail(self.only_a, self.flips)

    def to_json(self) -> dict:
        return {
            "pairs": self.pairs,
            "only_a": self.only_a,
            "only_b": self.only_b,
            "flips": self.flips,
            "p": round(self.p_two_sided, 6),
        }


def discordance(a: Sequence[bool], b: Sequence[bool]) -> Discordance:
    """The Discordance of one outcome over pairs (a[i], b[i])."""
    if len(a) != len(b):
        raise ValueError(f"paired outcomes must be as many in both runs, got {len(a)} and {len(b)}")
    x, y = np.asarray(a, dtype=bool), np.asarray(b, dtype=bool)
    return Discordance(len(x), int(np.sum(x & ~y)), int(np.sum(~x & y)))


@dataclass(frozen=True)
class MeanInterval:
    """The mean of paired differences with a bootstrap percentile interval."""

    n: int
    mean: float
    low: float
    high: float

    def to_json(self, digits: int = 5) -> dict:
        return {
            "n": self.n,
            "mean": _round(self.mean, digits),
            "low": _round(self.low, digits),
            "high": _round(self.high, digits),
        }


def mean_interval(differences: Sequence[float], level: float = 0.95, seed: int = 0) -> MeanInterval:
    """Mean of the differences and its bootstrap percentile interval at level (NaN bounds with fewer than
    MIN_BOOTSTRAP_N differences; NaN throughout with none)."""
    d = np.asarray(differences, dtype=float)
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    if d.size < MIN_BOOTSTRAP_N:
        return MeanInterval(int(d.size), float(d.mean()) if d.size else math.nan, math.nan, math.nan)
    rng = np.random.default_rng(seed)
    means = d[rng.integers(0, d.size, size=(BOOTSTRAP_DRAWS, d.size))].mean(axis=1)
    tail = (1.0 - level) / 2.0
    return MeanInterval(
        int(d.size), float(d.mean()), float(np.quantile(means, tail)), float(np.quantile(means, 1.0 - tail))
    )


def median_difference_interval(
    a: Sequence[float], b: Sequence[float], level: float = 0.95, seed: int = 0
) -> MeanInterval:
    """The difference of medians, median(a) − median(b), over pairs (a[i], b[i]), with a bootstrap percentile
    interval that resamples the pairs (NaN bounds with fewer than MIN_BOOTSTRAP_N pairs; NaN throughout with none).
    Returned as a MeanInterval whose mean is that difference."""
    x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if x.shape != y.shape:
        raise ValueError(f"paired values must be as many in both runs, got {x.size} and {y.size}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    if x.size == 0:
        return MeanInterval(0, math.nan, math.nan, math.nan)
    difference = float(np.median(x) - np.median(y))
    if x.size < MIN_BOOTSTRAP_N:
        return MeanInterval(int(x.size), difference, math.nan, math.nan)
    pick = np.random.default_rng(seed).integers(0, x.size, size=(BOOTSTRAP_DRAWS, x.size))
    medians = np.median(x[pick], axis=1) - np.median(y[pick], axis=1)
    tail = (1.0 - level) / 2.0
    return MeanInterval(
        int(x.size), difference, float(np.quantile(medians, tail)), float(np.quantile(medians, 1.0 - tail))
    )


def _round(x: float, digits: int) -> float | None:
    return None if math.isnan(x) else round(x, digits)


# --------------------------------------------------- a tuned controller's trials against the paper's, paired
def mcnemar(a: dict, b: dict, key: str) -> dict:
    """Paired trials (same cell and k) of two results files' records (a: the tuned controller's, b: the paper's): those where key (success, reached, or fell_off) holds
    only in a, only in b, and McNemar's z (positive: more in a)."""
    common = sorted(set(a) & set(b))
    d = discordance([bool(a[k][key]) for k in common], [bool(b[k][key]) for k in common])
    z = (d.only_a - d.only_b) / math.sqrt(d.flips) if d.flips else 0.0
    return {"paired": d.pairs, "only_tuned": d.only_a, "only_paper": d.only_b, "z": round(z, 2)}


def edge_falls(a: dict, b: dict) -> dict:
    """In the outer 5 cm band, paired trials of a (tuned) and b (paper): the falls, how many of them had reached ε
    first (the reach rule counts those as successes), and the trials a keeps on the sheet where b fell."""
    band = [k for k in sorted(set(a) & set(b)) if max(abs(v) for v in a[k]["target_m"]) > 0.20]
    kept = [k for k in band if b[k]["fell_off"] and not a[k]["fell_off"]]
    out = {
        "trials": len(band),
        "kept_on_by_tuned": len(kept),
        "of_those_reached": {
            "tuned": sum(bool(a[k]["reached"]) for k in kept),
            "paper_manhattan": sum(bool(b[k]["reached"]) for k in kept),
        },
    }
    for name, rec in (("tuned", a), ("paper_manhattan", b)):
        fell = [k for k in band if rec[k]["fell_off"]]
        out[f"fell_{name}"] = {"trials": len(fell), "reached_first": sum(bool(rec[k]["reached"]) for k in fell)}
    return out
