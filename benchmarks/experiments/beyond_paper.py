"""Beyond the paper: the controllers tuned for the fitted plant, checked on the paper's protocol beside its Manhattan.

Run: python3 benchmarks/experiments/beyond_paper.py [--runs sphere_scheduled,sphere_cascade] [--jobs 2] [--collect]
Each run is `mantaray sim tune` (sim/search/tune.py) for one object and controller on the `paper` plant into
out/tune/<run>/: the search on its own sample, then the full protocol (20 x 20 cells, N = 10, T = 10 s, seed 2026,
to the end of T) with the best settings. The baseline is the paper's Manhattan on the same trials, run by
`python3 benchmarks/experiments/paper_heatmaps.py --plant paper --to-end --runs <object run>` (same seed: trial for trial
the same starts, targets and noise seeds, so the comparison is paired). Both are resumable, and a run starts
from what docs/results/tune/<run>/ holds (the study, the final check's trials, the settings), where every session
writes it back; --collect only writes back what out/ holds (say, from a run still going). With both done, the
script prints each run's scores under both rules beside the baseline's, the falls, McNemar's test on the paired
trials (for either rule and for the falls), and copies the tuned controller's heatmaps and writes the difference
maps to docs/figures/.
"""

from __future__ import annotations

import argparse
import gzip
import json
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import paper_heatmaps  # a sibling script: the baselines' committed trials, and the zones of the paper's maps

from mantaray.sim.evaluation import committed
from mantaray.sim.evaluation.paired import edge_falls, mcnemar
from mantaray.sim.evaluation.results_file import write_whole

REPO = Path(__file__).resolve().parents[2]
COMMITTED = REPO / "docs" / "results" / "tune"
BASELINES = REPO / "out" / "heatmap"  # where paper_heatmaps.py --plant paper --to-end puts them
SPHERE_CASCADE = COMMITTED / "sphere_cascade" / "settings.toml"
RUNS = {  # name: (object, controller, alpha [m], the baseline run of paper_heatmaps.py, settings to start from)
    "sphere_scheduled": ("sphere", "scheduled", 0.0, "sphere_manhattan_paper_to_end", None),
    "sphere_cascade": ("sphere", "cascade", 0.0, "sphere_manhattan_paper_to_end", None),
    # the cube and the bunny with the better of the two on the sphere's final checks (docs/results.md), their
    # searches started from the sphere's best as well as from the boot values
    "cube_cascade_alpha0.1": ("cube", "cascade", 0.1, "cube_manhattan_alpha0.1_paper_to_end", SPHERE_CASCADE),
    "bunny_cascade_alpha0.05": ("bunny", "cascade", 0.05, "bunny_manhattan_alpha0.05_paper_to_end", SPHERE_CASCADE),
}
PAIRED_APART = ("controller", "settings", "gains")  # what a paired comparison may differ in: the controller only
KEPT = ("settings.toml", "report.json", "history.png")  # beside study.db and the final check's trials


def out_dir(run: str) -> Path:
    obj, controller, alpha, _, _ = RUNS[run]
    return REPO / "out" / "tune" / f"{obj}_{controller}_alpha{alpha:g}_paper"


def restore(run: str) -> None:
    """Start from the committed study and final trials when out/ has none."""
    out, kept = out_dir(run), COMMITTED / run
    if (out / "study.db").exists() or not (kept / "study.db").exists():
        return
    (out / "final").mkdir(parents=True, exist_ok=True)
    shutil.copyfile(kept / "study.db", out / "study.db")
    if (kept / "final.jsonl.gz").exists():
        (out / "final" / "results.jsonl").write_bytes(gzip.decompress((kept / "final.jsonl.gz").read_bytes()))
    print(f"{run}: continuing from {kept.relative_to(REPO)}", flush=True)


def collect(run: str) -> None:
    """Write what out/ holds back to docs/results/tune/<run>/ (the study copied consistently, even while in use)."""
    out, kept = out_dir(run), COMMITTED / run
    if not (out / "study.db").exists():
        return
    kept.mkdir(parents=True, exist_ok=True)
    with sqlite3.connect(out / "study.db") as src, sqlite3.connect(kept / "study.db") as dst:
        src.backup(dst)
    final = out / "final" / "results.jsonl"
    if final.exists():
        write_whole(kept / "final.jsonl.gz", gzip.compress(final.read_bytes(), mtime=0))
    for name in KEPT:
        if (out / name).exists():
            shutil.copyfile(out / name, kept / name)
    print(f"{run}: kept in {kept.relative_to(REPO)}", flush=True)


def baseline(run: str) -> Path:
    """The baseline's trials: out/ holds them where paper_heatmaps.py ran here, else they come from docs/results/."""
    path = BASELINES / RUNS[run][3] / "results.jsonl"
    committed.restore(path, paper_heatmaps.COMMITTED / f"{RUNS[run][3]}.jsonl.gz")
    return path


def compare(run: str) -> dict | None:
    """Scores, falls and McNemar of a run's final check against its baseline; None, saying why, until both are done."""
    from mantaray.sim.evaluation import results_file as R
    from mantaray.sim.evaluation import summary as S

    tuned_path, base_path = out_dir(run) / "final" / "results.jsonl", baseline(run)
    runs_it = {
        tuned_path: f"python3 benchmarks/experiments/beyond_paper.py --runs {run}",
        base_path: "python3 benchmarks/experiments/paper_heatmaps.py --plant paper --to-end --runs "
        + RUNS[run][3].removesuffix("_paper_to_end"),
    }
    loaded = {}
    for path, command in runs_it.items():
        loaded[path] = R.ResultsFile.load(path) if path.exists() else None
        if loaded[path] is None or loaded[path].missing():
            print(
                f"{run}: not compared: {path.relative_to(REPO)} is {'missing' if loaded[path] is None else 'incomplete'}"
                f" (`{command}` runs it)",
                file=sys.stderr,
                flush=True,
            )
            return None
    tuned, base = loaded[tuned_path], loaded[base_path]
    differ = sorted(
        k for k, v in tuned.experiment.to_json().items() if k not in PAIRED_APART and base.experiment.to_json()[k] != v
    )
    if differ:  # then trial k of a cell is not the same start, target and noise in both: no pairs
        raise SystemExit(f"{run}: the final check and {base_path} differ in {', '.join(differ)}: not paired trials")
    st, sb = S.summarize(tuned), S.summarize(base)
    out = {
        "tuned": {
            "score": round(st.score, 1),
            "reach_score": round(st.reach_score, 1),
            "fell_off": round(float(st.fell_rates.mean()), 3),
        },
        "paper_manhattan": {
            "score": round(sb.score, 1),
            "reach_score": round(sb.reach_score, 1),
            "fell_off": round(float(sb.fell_rates.mean()), 3),
        },
        "ratio": {
            "score": round(st.score / sb.score, 2) if sb.score else None,
            "reach_score": round(st.reach_score / sb.reach_score, 2) if sb.reach_score else None,
        },
        "mcnemar": {rule: mcnemar(tuned.records, base.records, rule) for rule in ("success", "reached", "fell_off")},
        "zones": {
            "tuned": paper_heatmaps.zone_rates(tuned_path)["zones"],
            "paper_manhattan": paper_heatmaps.zone_rates(base_path)["zones"],
        },
        "outer_band": edge_falls(tuned.records, base.records),
    }
    for rule, flag in (("", []), ("_reach", ["--reached"])):
        drawn = tuned_path.parent / f"heatmap{rule}.png"  # the tuned controller's own map (sim tune draws it)
        if drawn.exists():
            shutil.copyfile(drawn, REPO / "docs" / "figures" / f"heatmap_{run}{rule}.png")
        subprocess.run(
            [
                sys.executable,
                "-m",
                "mantaray.cli",
                "sim",
                "compare",
                str(tuned_path),
                str(base_path),
                *flag,
                "--out",
                str(REPO / "docs" / "figures" / f"difference_{run}_minus_manhattan{rule}.png"),
            ],
            cwd=REPO,
            check=True,
            stdout=subprocess.DEVNULL,
        )
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", default=",".join(RUNS), help="comma-separated names of: " + ", ".join(RUNS))
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--candidates", type=int, default=60, help="candidates each search should hold")
    parser.add_argument("--collect", action="store_true", help="only write back what out/ holds")
    args = parser.parse_args()
    names = args.runs.split(",")
    unknown = [n for n in names if n not in RUNS]
    if unknown:
        parser.error(f"unknown run(s) {', '.join(unknown)}; known: {', '.join(RUNS)}")
    table = {}
    for run in names:
        obj, controller, alpha, _, start = RUNS[run]
        if not args.collect:
            restore(run)
            start_from = ["--start-from", str(start.relative_to(REPO))] if start else []
            proc = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "mantaray.cli",
                    "sim",
                    "tune",
                    "--controller",
                    controller,
                    "--object",
                    obj,
                    "--alpha",
                    str(alpha),
                    "--plant",
                    "paper",
                    "--candidates",
                    str(args.candidates),
                    "--jobs",
                    str(args.jobs),
                    *start_from,
                    "--out",
                    str(out_dir(run).relative_to(REPO)),
                ],
                cwd=REPO,
            )
            try:
                returncode = proc.wait()
            except KeyboardInterrupt:  # Ctrl-C reaches sim tune too: it ends keeping what it did
                returncode = proc.wait()
            finally:
                collect(run)  # and that is written back
            if returncode != 0:
                print(f"{run}: tune ended with exit {returncode}; what it did is kept", file=sys.stderr)
                return returncode
        else:
            collect(run)
        table[run] = compare(run)
        if table[run] is not None:
            print(f"{run}: {json.dumps(table[run])}", flush=True)
    figures = REPO / "docs" / "figures" / "beyond_paper.json"
    done = {k: v for k, v in table.items() if v is not None}
    if done:
        stored = json.loads(figures.read_text()) if figures.exists() else {}
        figures.write_text(json.dumps({**stored, **done}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
