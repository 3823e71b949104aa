"""The convergence study: the fidelity gate on each mesh and step against a finer one, for two plants; its table.

Run: python3 benchmarks/experiments/fidelity_study.py [--gates paper_15x15_2ms,...] [--jobs 2] [--collect]
Each gate is `mantaray sim fidelity` (sim/evaluation/fidelity.py) on one object (the sphere unless the gate names another), to
the end of T, with the gate's sample (by default 40 cells, 8 from each stratum, 5 trials each, seed 77) for two
controllers: on the `paper` plant the paper's Manhattan and the cascade tuned for that object on it (docs/results/tune/), on the
polyester plant the paper's Manhattan and Euclidean. Gates that share a run share its trials (out/fidelity/trials/).
The trials are committed gzipped in docs/results/fidelity/trials/ and the script starts from them, so on a fresh
clone it only rewrites the reports; every run resumes where it stopped (a 21 x 21 run takes hours on 2 cores).
--judge-only judges again the trials each gate holds and runs none (the gate's --report-only). --collect only
writes back what out/ holds (from a gate still running, say). The reports go to docs/results/fidelity/<gate>/ and
the table of every verdict to docs/results/fidelity/convergence.md.
"""

from __future__ import annotations

import argparse
import gzip
import json
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from mantaray.sim.cli.common import interruptible
from mantaray.sim.evaluation.committed import keep
from mantaray.sim.evaluation.results_file import write_whole

REPO = Path(__file__).resolve().parents[2]
COMMITTED = REPO / "docs" / "results" / "fidelity"
TRIALS = REPO / "out" / "fidelity" / "trials"
CASCADES = {  # object: (α [m] it was tuned at and is gated at, the cascade tuned for it on the paper plant)
    "sphere": (0.0, "docs/results/tune/sphere_cascade/settings.toml"),
    "cube": (0.1, "docs/results/tune/cube_cascade_alpha0.1/settings.toml"),
}
THREADS = (("fabric.stretch", "threads"),)  # the sheet held by tension-only threads (sim/README.md, Convergence 7)
KERNEL = (*THREADS, ("contact.model", "kernel"))  # ... and met through the kernel contact (Convergence 9)
REPEATABILITY = "0.002"  # [m] the floor the reference's gates are judged beside: the rig's repeatability
CHAOS = "0.0001"  # [m] the floor of the mesh-contact gates: a diagnostic of chaos


@dataclass(frozen=True)
class Gate:
    """One gate: the plant, the candidate and finer fidelities, the values it fixes over the plant, its object, how
    far its floor moves every start [m], the cells it draws from each stratum (5 trials each, per controller), and
    whether it runs its candidate alone on the trials another gate's finer run holds (`--candidate-only`)."""

    plant: str
    candidate: str
    finer: str
    fixed: tuple[tuple[str, str], ...] = ()
    object_name: str = "sphere"
    shift: str = CHAOS
    cells_per_stratum: int = 8
    candidate_only: bool = False

    def arms(self) -> tuple[str, str]:
        return ("manhattan", CASCADES[self.object_name][1]) if self.plant == "paper" else ("manhattan", "euclidean")

    def alpha(self) -> float:
        return CASCADES[self.object_name][0]


GATES = {  # name: its gate, in the order they run
    "paper_15x15_2ms": Gate("paper", "15:0.002", "15:0.001"),
    "paper_11x11_2ms": Gate("paper", "11:0.002", "15:0.001"),
    "paper_11x11_1ms": Gate("paper", "11:0.001", "15:0.001"),
    "paper_15x15_0.5ms": Gate("paper", "15:0.0005", "15:0.001"),  # is 1 ms itself converged in the step?
    "paper_15x15_0.25ms_vs_0.5ms": Gate("paper", "15:0.00025", "15:0.0005"),  # ... and 0.5 ms?
    "polyester_15x15_2ms": Gate("polyester", "15:0.002", "15:0.001"),
    "polyester_11x11_2ms": Gate("polyester", "11:0.002", "15:0.001"),
    "polyester_11x11_1ms": Gate("polyester", "11:0.001", "15:0.001"),
    "polyester_15x15_0.5ms": Gate("polyester", "15:0.0005", "15:0.001"),  # is 1 ms converged for this plant too?
    "paper_15x15_1ms_vs_21x21": Gate("paper", "15:0.001", "21:0.001"),
    "polyester_15x15_0.5ms_vs_21x21": Gate("polyester", "15:0.0005", "21:0.0005"),  # the reference's mesh (no clamp)
    "polyester_15x15_0.25ms_vs_0.5ms": Gate("polyester", "15:0.00025", "15:0.0005"),  # the reference's step
    # threads: 15 x 15 at its cheapest stable step against 21 x 21 at the step that mesh needs (its bending is
    # explicit, and a sheet free to buckle is stiffer to it): the mesh and the step in one gate
    "polyester_threads_15x15_0.5ms_vs_21x21_0.25ms": Gate("polyester", "15:0.0005", "21:0.00025", THREADS),
    # ... and the mesh alone, at the step both need (it shares the 21 x 21 runs)
    "polyester_threads_15x15_vs_21x21_0.25ms": Gate("polyester", "15:0.00025", "21:0.00025", THREADS),
    # the reference candidate of issue 39: the kernel contact on threads, 15 x 15 at 1 ms, against 21 x 21 at 0.25 ms
    # (21 x 21 at 0.5 ms, its `finer`, diverges on threads), beside the rig's repeatability
    "paper_kernel_15x15_1ms_vs_21x21_0.25ms": Gate("paper", "15:0.001", "21:0.00025", KERNEL, shift=REPEATABILITY),
    # ... and at 0.5 ms, whose `finer` that is: its candidate alone, on the finer trials the 1 ms gate made
    "paper_kernel_15x15_0.5ms_vs_21x21_0.25ms": Gate(
        "paper", "15:0.0005", "21:0.00025", KERNEL, shift=REPEATABILITY, candidate_only=True
    ),
    # 0.5 ms moved no answer of 1 ms's: the mesh, then, at 1 ms, on the same finer trials
    "paper_kernel_17x17_1ms_vs_21x21_0.25ms": Gate(
        "paper", "17:0.001", "21:0.00025", KERNEL, shift=REPEATABILITY, candidate_only=True
    ),
    "paper_kernel_19x19_1ms_vs_21x21_0.25ms": Gate(
        "paper", "19:0.001", "21:0.00025", KERNEL, shift=REPEATABILITY, candidate_only=True
    ),
    "paper_kernel_cube_15x15_1ms_vs_21x21_0.25ms": Gate(
        "paper", "15:0.001", "21:0.00025", KERNEL, "cube", REPEATABILITY
    ),
    "polyester_kernel_15x15_1ms_vs_21x21_0.25ms": Gate(  # 200 pairs: 4 cells a stratum
        "polyester", "15:0.001", "21:0.00025", KERNEL, shift=REPEATABILITY, cells_per_stratum=4
    ),
}


def command(name: str, jobs: int | None, report_only: bool = False) -> list[str]:
    g = GATES[name]
    arms = [a for arm in g.arms() for a in ("--controller", arm)]
    sets = [a for key, value in g.fixed for a in ("--set", f"{key}={value}")]
    return [
        "mantaray",
        "sim",
        "fidelity",
        "--object",
        g.object_name,
        "--alpha",
        f"{g.alpha():g}",
        "--candidate",
        g.candidate,
        "--finer",
        g.finer,
        "--plant",
        g.plant,
        *sets,
        *arms,
        "--shift",
        g.shift,
        "--cells-per-stratum",
        str(g.cells_per_stratum),
        "--trials-dir",
        str(TRIALS.relative_to(REPO)),
        "--out",
        f"out/fidelity/{name}",
        *(["--jobs", str(jobs)] if jobs else []),
        *(["--report-only"] if report_only else ["--candidate-only"] if g.candidate_only else []),
    ]


def restore() -> None:
    """Start from the committed trials where out/ has none (or fewer) of a run."""
    for kept in sorted((COMMITTED / "trials").glob("*.jsonl.gz")):
        path = TRIALS / kept.name.removesuffix(".gz")
        data = gzip.decompress(kept.read_bytes())
        if not path.exists() or path.read_bytes().count(b"\n") < data.count(b"\n"):
            path.parent.mkdir(parents=True, exist_ok=True)
            write_whole(path, data)


def collect(name: str) -> None:
    """Write a gate's report (once it pairs a trial) and every trial of out/ back to docs/results/fidelity/."""
    (COMMITTED / "trials").mkdir(parents=True, exist_ok=True)
    for path in sorted(TRIALS.glob("*.jsonl")):
        keep(path, COMMITTED / "trials" / (path.name + ".gz"))
    out = REPO / "out" / "fidelity" / name
    if not (out / "report.json").exists() or not json.loads((out / "report.json").read_text())["pairs"]:
        return
    for report in ("report.json", "report.md"):
        if (out / report).exists():
            (COMMITTED / name).mkdir(parents=True, exist_ok=True)
            (COMMITTED / name / report).write_bytes((out / report).read_bytes())


def _interval(d: dict) -> str:
    if d["estimate"] is None:
        return "no pairs"
    if d["low"] is None:
        return f"{d['estimate']:+.3f} ({d['n']} pairs: no interval)"
    return f"{d['estimate']:+.3f} [{d['low']:+.3f} .. {d['high']:+.3f}]"


def table() -> str:
    """Every committed gate's verdict and its judged rates, one row each."""
    rows = [
        "# The fidelity gate on each mesh and step (to the end of T)",
        "",
        "Written by `python3 benchmarks/experiments/fidelity_study.py`; each gate's report, with the command that "
        "reproduces it, is in its folder here. Each rate: the paired difference candidate − finer per controller, "
        "with its 90 % interval, judged against ±5 percentage points (`mantaray sim fidelity --help`); ✓ equivalent, "
        "✗ different, ? undecided. Flips: the trials whose outcome differs from the finer run's, at the candidate / at "
        "the finer run with every start moved by the gate's shift (0.1 mm: a diagnostic of chaos; 2 mm: the rig's "
        "repeatability; not judged).",
        "",
        "| plant | object, α, floor | candidate | finer | pairs | reached | within ε at T | fell off | flips (reached) "
        "| verdict |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    mark = {"equivalent": "✓", "different": "✗", "undecided": "?"}
    for name in GATES:
        g = GATES[name]
        path = COMMITTED / name / "report.json"
        if not path.exists():
            continue
        r = json.loads(path.read_text())

        def judged(key: str, r: dict = r) -> str:
            return "; ".join(
                f"{arm} {_interval(answers[key]['difference'])} {mark[answers[key]['difference']['status']]}"
                for arm, answers in r["per_arm"].items()
            )

        flips = "; ".join(
            f"{arm} {row['reached']['candidate']} / {row['reached']['floor']}"
            for arm, rows in r["flips"].items()
            for row in rows
        )
        verdict = r["verdict"] or f"incomplete ({r['pairs']} of {r['expected_pairs']})"
        label = g.plant + "".join(f", {v}" for _, v in g.fixed)
        rows.append(
            f"| {label} | {g.object_name}, α {g.alpha():g} m, {g.shift} m floor | {r['candidate']} | {r['finer']} | "
            f"{r['pairs']} | {judged('reached')} | {judged('success')} | {judged('fell_off')} | {flips} | [{verdict}]({name}/report.md) |"
        )
    return "\n".join(rows) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--gates", default=",".join(GATES), help=f"comma-separated, of: {', '.join(GATES)}")
    parser.add_argument("--jobs", type=int, help="parallel workers (default: every core)")
    parser.add_argument("--collect", action="store_true", help="only write back what out/ holds, run nothing")
    parser.add_argument(
        "--judge-only",
        action="store_true",
        help="judge again the trials each gate holds (the committed ones, on a fresh clone) and run none",
    )
    args = parser.parse_args()
    names = [n.strip() for n in args.gates.split(",") if n.strip()]
    unknown = [n for n in names if n not in GATES]
    if unknown:
        parser.error(f"unknown gates {', '.join(unknown)}; the gates are {', '.join(GATES)}")
    restore()
    interruptible()  # Ctrl-C (or SIGINT, also when started in the background, or SIGTERM) ends it as below
    for name in names:
        if not args.collect:
            print(f"{name}: {' '.join(command(name, args.jobs, args.judge_only))}", flush=True)
            gate_run = subprocess.Popen(command(name, args.jobs, args.judge_only), cwd=REPO)
            try:
                code = gate_run.wait()
            except KeyboardInterrupt:  # the gate keeps every finished trial and reports them: wait, then write back
                gate_run.send_signal(signal.SIGINT)  # where only this process was interrupted (the gate takes two)
                gate_run.wait()
                collect(name)
                (COMMITTED / "convergence.md").write_text(table())
                print(f"\ninterrupted: {name}'s trials are kept; the same command continues", file=sys.stderr)
                return 130
            if code not in (0, 1):  # 0: keeps, 1: changes; 3: no verdict (incomplete, diverged); 2: misused
                print(f"{name}: the gate gave no verdict (exit {code}; its message is above)", file=sys.stderr)
        collect(name)
        (COMMITTED / "convergence.md").write_text(table())  # after every gate: a stop loses no row
    print(f"table: {(COMMITTED / 'convergence.md').relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
