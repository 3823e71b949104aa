"""`mantaray sim compare`: the difference map of two heatmap runs (first minus second)."""

from __future__ import annotations

import argparse
import sys

from mantaray.outputs import FIGURE_SUFFIXES, writable_file

from .common import load_results, output


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim compare`: the difference map of two heatmap runs, both measured alike."""
    from mantaray.plots import heatmap_figure

    from ..evaluation.summary import summarize

    output(parser, writable_file, args.out, FIGURE_SUFFIXES)
    runs = [load_results(parser, given, "compare") for given in (args.first, args.second)]
    (a, b), (pa, pb) = [summarize(r) for r in runs], [r.experiment for r in runs]
    _check_comparable(parser, pa, pb, args.reached)
    for given, results in zip((args.first, args.second), runs, strict=True):
        left = len(results.missing())
        if left:
            print(
                f"mantaray sim compare: warning: {given} is incomplete ({left} of "
                f"{left + len(results.records)} trials not run); its rates are over the trials that ran",
                file=sys.stderr,
            )
    f = pa.rig().module
    label = [f"{p.object_name} {p.controller} α={p.alpha_m:g}" for p in (pa, pb)]
    rule = "within ε at any frame" if args.reached else "within ε at T"
    (rates_a, score_a), (rates_b, score_b) = [
        (s.reach_rates, s.reach_score) if args.reached else (s.rates, s.score) for s in (a, b)
    ]
    figure = heatmap_figure(
        rates_a - rates_b,
        (f.size_x_m, f.size_y_m),
        f"{label[0]} − {label[1]} ({rule})\nscores {score_a:.1f} − {score_b:.1f} = {score_a - score_b:+.1f}",
        args.out,
        difference=True,
    )
    relative = f" ({(score_a - score_b) / score_b:+.0%} of the second)" if score_b > 0 else ""
    print(
        f"{rule}: {label[0]}: score {score_a:.1f}; {label[1]}: score {score_b:.1f}; difference "
        f"{score_a - score_b:+.1f}{relative}; figure {figure}"
    )
    return 0


def _check_comparable(parser: argparse.ArgumentParser, pa, pb, reached: bool) -> None:
    """What success means, and where it is measured, must be the same in both runs (object, controller, α, gains
    and plant are what a comparison is for); a usage error otherwise."""
    differ = [name for name in ("cells", "tolerance_m", "duration_s") if getattr(pa, name) != getattr(pb, name)]
    if set(pa.cell_ids()) != set(pb.cell_ids()):
        differ.append("only_cells")
    if differ:
        parser.error(
            "the runs measure success differently ("
            + "; ".join(f"{name} {getattr(pa, name)} against {getattr(pb, name)}" for name in differ)
            + "): compare runs that differ only in what is being compared"
        )
    if not reached and (pa.stop_when_reached or pb.stop_when_reached):
        parser.error(
            "a run that stops at its first frame within ε (--stop-when-reached) has no end-of-T success; "
            "compare with --reached"
        )
