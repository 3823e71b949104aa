"""`mantaray sim heatmap`: the paper's success map (Fig. 2), and the files it is written to."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mantaray.arguments import controller_settings, reporter, start_live
from mantaray.outputs import writable_dir

from .cli_common import check_ray, interruptible, output, plant_for_settings, workers
from .plant import DEFAULT_PLANT


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim heatmap`: the protocol checked, its results file opened or continued, the missing trials run."""
    from .executors import RayUnavailable, Watch, run, run_local, run_ray
    from .experiment import Experiment, ExperimentMismatch
    from .fidelity import fixed_slug
    from .model import SimulationUnstable
    from .results_file import ResultsFile, ResultsFileBusy

    settings = controller_settings(parser, args)
    args.plant = plant_for_settings(parser, settings, args.plant)
    try:
        protocol = Experiment(
            object_name=args.object,
            controller=args.controller,
            cells=args.cells,
            trials_per_cell=args.trials,
            tolerance_m=args.tolerance,
            duration_s=args.duration,
            alpha_m=args.alpha,
            seed=args.seed,
            gains=args.gains,
            resolution=args.resolution,
            timestep_s=args.timestep,
            only_cells=args.only_cells,
            plant=args.plant,
            plant_set=tuple(sorted(args.set)),
            stop_when_reached=args.stop_when_reached,
            settings=settings.values,
        )
    except ValueError as exc:
        parser.error(str(exc))
    plant = ("" if args.plant == DEFAULT_PLANT else f"_{args.plant}") + fixed_slug(protocol.plant_set)
    check_ray(parser, args)
    if args.live and args.executor == "ray":
        parser.error("--live shows the trial of a worker of this machine: use it with --executor local")
    tuned = f"_{Path(args.settings).stem}" if args.settings else ""
    out = output(
        parser,
        writable_dir,
        args.out or f"out/heatmap/{args.object}_{args.controller}{tuned}_alpha{args.alpha:g}{plant}",
    )
    try:
        results = ResultsFile.open(out / "results.jsonl", protocol)
    except (ExperimentMismatch, ValueError, ResultsFileBusy) as exc:
        print(f"mantaray sim heatmap: {exc}", file=sys.stderr)
        return 2
    for warning in results.warnings():
        print(f"mantaray sim heatmap: warning: {warning}", file=sys.stderr)
    todo = results.missing()
    total = len(protocol.cell_ids()) * protocol.trials_per_cell
    if len(todo) < total:
        print(
            f"continuing {out / 'results.jsonl'}: {total - len(todo)} of {total} trials already done", file=sys.stderr
        )
    from .progress import Progress

    live = start_live(parser, args, _report)
    if live is not None:
        _report(f"live view of one worker's trials at {live.options.page_url}")
    bar = Progress(total, initial=total - len(todo), unit="trial", label="heatmap")  # on stderr, beside --json
    interruptible()
    try:
        if args.executor == "ray":
            records = run_ray(protocol, todo, args.jobs, args.ray_address)
        else:
            watch = None if live is None else Watch(live.options.grpc_url)
            records = run_local(protocol, todo, workers(args.jobs), watch)
        run(results, records, progress=lambda record: bar.update(1))
        if live is not None:
            live.linger(args.linger, _report)
    except KeyboardInterrupt:
        bar.close()
        print(
            f"\ninterrupted: {len(results.records)} of {total} trials are in {out / 'results.jsonl'}; "
            f"the same command continues the run",
            file=sys.stderr,
        )
        return 130
    except SimulationUnstable as exc:
        bar.close()
        print(
            f"mantaray sim heatmap: {exc}; the {len(results.records)} finished trials are kept in "
            f"{out / 'results.jsonl'}",
            file=sys.stderr,
        )
        return 1
    except RayUnavailable as exc:
        bar.close()
        print(f"mantaray sim heatmap: {exc}", file=sys.stderr)
        return 2
    finally:
        if live is not None:
            live.close()
    bar.close()
    title = (
        f"{args.object}, {args.controller}, α = {args.alpha:g} m, ε = {args.tolerance:g} m, T = {args.duration:g} s, "
        f"{protocol.trials_per_cell} trials/cell"
    )
    summary = heatmap_outputs(results, out, title)
    if args.json:
        print(json.dumps(summary))
    else:
        regions = summary["regions"]
        print(
            f"{args.object}, {args.controller}: score {summary['score']:.1f} of {len(protocol.cell_ids())} cells "
            f"(within ε at any frame: {summary['reach_score']:.1f}); regions: "
            + ", ".join(f"{name} {r['cells']} cells ({r['area_m2']:.4f} m²)" for name, r in regions.items())
            + f"; {out}/results.jsonl, cells.csv, summary.json, heatmap.png"
        )
    return 0


_report = reporter("sim heatmap")


def heatmap_outputs(results, out: Path, title: str) -> dict:
    """Write per-cell rates (CSV), the summary (JSON) and the figure beside the results file; return the summary."""
    from mantaray.plots import heatmap_figure

    from .experiment import cell_bounds
    from .summary import summarize

    s = summarize(results)
    p = results.protocol
    f = p.rig().frame
    rows = ["cell,ix,iy,x_lo_m,y_lo_m,trials,success_rate,reach_rate,fell_rate"]
    for cell in p.cell_ids():
        ix, iy = cell % p.cells, cell // p.cells
        x_lo, _, y_lo, _ = cell_bounds(p, (f.size_x_m, f.size_y_m), cell)
        rows.append(
            f"{cell},{ix},{iy},{x_lo:.4f},{y_lo:.4f},{s.trials_per_cell[iy, ix]},{s.rates[iy, ix]:.3f},"
            f"{s.reach_rates[iy, ix]:.3f},{s.fell_rates[iy, ix]:.3f}"
        )
    (out / "cells.csv").write_text("\n".join(rows) + "\n")
    summary = {"protocol": p.to_json(), **s.to_json()}
    size = (f.size_x_m, f.size_y_m)
    summary["figure"] = str(
        heatmap_figure(
            s.rates,
            size,
            f"{title}\nscore {s.score:.1f} of {len(p.cell_ids())} (within ε at any frame: {s.reach_score:.1f})",
            out / "heatmap.png",
        )
    )
    summary["reach_figure"] = str(
        heatmap_figure(
            s.reach_rates,
            size,
            f"{title}\nwithin ε at any frame (where the paper's loop stops): score {s.reach_score:.1f}",
            out / "heatmap_reach.png",
        )
    )
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    return summary
