"""`mantaray sim ...`: the simulation's command lines; each command's handler (sim/cli/<command>.py) loads when it runs."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from mantaray.arguments import number
from mantaray.host.cli_view import add_view_arguments
from mantaray.protocol import messages as m
from mantaray.protocol.codec import choices
from mantaray.protocol.rig import rig_file

from ..model.plant import DEFAULT_PLANT
from ..model.rig import VISION_MODES
from . import options as O

RUN = """One target-reaching trial: the native firmware on a pty drives the simulated rig in lock-step.

With --port, the firmware on that serial device path (a board, the AVR simulator) drives it instead. Exit status 0
when the object ends within the tolerance, 1 when it does not, 2 on bad arguments. Writes the trajectory plot (paper
Fig. 3 style), the trajectory (.npz) and, on request, a video."""

HEATMAP = """The paper's evaluation (Fig. 2): success rate per cell of the workspace, trials in parallel.

Each cell gets N trials with a random target inside the cell and a random start anywhere on the fabric; a trial
succeeds if the object ends within ε of its target at the end of T without falling off. The firmware core runs
in-process (the same C++ as the virtual MCU). Results go to OUT/results.jsonl, one line per trial as it finishes:
interrupt the run and the same command continues where it stopped."""

CALIBRATE = """Fit the simulated plant to evidence with an Optuna search over the declared parameter space
(sim/model/plant.toml).

Evidence is the paper's findings F1-F5 (default: a stratified sample of heatmap cells, the sphere, both controllers,
the paper's gains, several objectives at once) or, with --log, rig logs: the simulation driven by each log's commands
should retrace its trajectory. The study is OUT/study.db (SQLite): interrupt it and the same command continues;
--candidates is the total the study should hold. Writes OUT/report.md, report.json (best candidate, its findings,
parameter importances) and pareto.png; --fig3 also runs the paper's hardware experiment (F6) on the best candidate."""

TUNE = """Tune a controller's settings for a plant: an Optuna search on a stratified sample of heatmap cells, then the
paper's full protocol with the best settings on another seed (the search never sees those trials).

A candidate scores the targets it misses under both success rules (within ε at T, and within ε at any frame). The
study is OUT/study.db (SQLite): interrupt it and the same command continues; --candidates is the total the study
should hold. Writes OUT/settings.toml (for mantaray rig --settings, sim run and sim heatmap), report.json (both
scores, beside the paper's Manhattan on the same sample) and history.png; the final check's trials go to
OUT/final/results.jsonl (resumable too), its heatmaps under both rules beside them."""

FIDELITY = """The fidelity gate: does a cheaper physics configuration (the candidate) give a finer one's answers?

It runs one paired sample (a stratified draw of the paper's cells, every controller on each) at the candidate and at
the finer fidelity (by default `finer`: 6 vertices a side more at half the step), and judges, controller by
controller, the answers a user reads: the rates reached, within ε at T and fell off, the mean time to reach and the
median final error. Each is the paired difference candidate − finer with its 90 % interval: inside ±5 percentage
points (±0.5 s, ±5 mm) the two agree, wholly outside they differ (two one-sided tests at 5 %); the same for the
contrast of every two controllers, which a claim that one beats another rests on. Verdict: the candidate "keeps the
finer one's answers" (all agree), "changes the finer one's answers" (any differs), or is undecided, with the pairs
per controller that would decide it; --until-decided grows the sample (more trials per cell) until it is decided or
--max-pairs is reached. Reported beside it, not judged: each rate per zone of the workspace (centre, axes, diagonals, edges,
corners), and the flips (trials whose outcome the candidate changes) against a floor: the finer run with every start
moved by the rig's repeatability (2 mm; --shift, repeatable: --shift 0.002 --shift 0.0001 adds the 0.1 mm diagnostic
of chaos). Trials go to --trials-dir as they finish, shared by every gate that needs the same run: interrupt it and
the same command continues; --candidate-only runs a new candidate alone on the trials a finer run holds already.
--runs compares existing heatmap results files instead. The trials go round the runs in
an order whose every prefix is a stratified sample, so Ctrl-C writes the report of the trials paired so far (no
verdict; exit 130). Exit status: 0 keeps, 1 changes, 2 a usage error, 3 no verdict (undecided, the sample
incomplete, or the physics diverged)."""

COMPARE = "The difference map of two heatmap runs (first minus second), like the paper's Euclidean - Manhattan."


Handler = Callable[[argparse.Namespace, argparse.ArgumentParser], int]


def _load(command: str) -> Handler:
    """The handler of `mantaray sim <command>`, `run` of sim/cli/<command>.py, imported only when the command runs:
    parsing loads no simulation."""
    match command:
        case "run":
            from .run import run
        case "replay":
            from .replay import run
        case "heatmap":
            from .heatmap import run
        case "calibrate":
            from .calibrate import run
        case "tune":
            from .tune import run
        case "fidelity":
            from .fidelity import run
        case "compare":
            from .compare import run
        case _:
            raise KeyError(f"no handler for mantaray sim {command}")
    return run


def _handler(command: str, parser: argparse.ArgumentParser):
    """The function `mantaray sim <command>` calls: its handler, loaded when it runs, given its parser."""
    return lambda args: _load(command)(args, parser)


def add_parser(sub: argparse._SubParsersAction, help_text: str) -> None:
    """Register `sim` (help_text: its line in `mantaray --help`) and its subcommands on the top-level parser's
    subparsers."""
    sim = sub.add_parser(
        "sim",
        help=help_text,
        description="The simulated MANTA-RAY: the native firmware drives a MuJoCo model of the rig "
        "over a virtual serial port, through the same protocol as the hardware.",
    )
    sim_sub = sim.add_subparsers(dest="sim_command", metavar="SUBCOMMAND")
    shared = O.shared()
    fmt = argparse.ArgumentDefaultsHelpFormatter
    _add_run(sim_sub, shared, fmt)
    _add_heatmap(sim_sub, shared, fmt)
    _add_calibrate(sim_sub, shared, fmt)
    _add_tune(sim_sub, shared, fmt)
    _add_fidelity(sim_sub, shared, fmt)
    _add_replay(sim_sub, fmt)
    compare = sim_sub.add_parser(
        "compare",
        help="difference map of two heatmap runs (first minus second)",
        description=COMPARE,
        formatter_class=fmt,
    )
    compare.add_argument("first", help="results.jsonl of a heatmap run, or its directory")
    compare.add_argument("second", help="the run to subtract")
    compare.add_argument("--out", default="out/heatmap/difference.png", help="figure to write")
    compare.add_argument(
        "--reached",
        action="store_true",
        help="compare the rates of reaching ε at any frame (the paper's stopping rule) instead of ending within ε at T",
    )
    compare.set_defaults(func=_handler("compare", compare))
    sim.set_defaults(func=lambda args: (sim.print_help(), 2)[1])


def _add_run(sim_sub: argparse._SubParsersAction, shared: dict, fmt) -> None:
    run = sim_sub.add_parser(
        "run",
        help="one target-reaching trial (the main job)",
        description=RUN,
        formatter_class=fmt,
        parents=[
            shared["trial"],
            shared["alpha"],
            shared["closed_loop"],
            shared["fidelity"],
            O.plant_set(),
            O.out("the figure, trajectory and video", "out/sim"),
        ],
    )
    run.add_argument("--start", type=O.point, default=(0.05, -0.05), metavar="X,Y", help="object start [m]")
    run.add_argument("--target", type=O.point, default=(-0.05, 0.05), metavar="X,Y", help="target p_d [m]")
    run.add_argument("--seed", type=int, default=1, help="seed of the actuator noise and the camera model")
    run.add_argument(
        "--rig",
        type=rig_file,
        metavar="FILE",
        help="the rig to simulate: its rig file (none: protocol/rig.toml, one module; protocol/rigs/array_2x2.toml: "
        "a 2 x 2 array on 9 actuators, its firmware build in the loop); each module's fabric has the mesh of one",
    )
    run.add_argument("--rate", type=float, help="camera rate [Hz] (default the plant's: the paper's 12)")
    run.add_argument("--latency", type=float, help="camera latency [s], below one frame period (default the plant's)")
    run.add_argument("--noise", type=float, default=0.0, help="camera noise, standard deviation [m] per axis")
    run.add_argument("--drop", type=float, default=0.0, help="share of camera frames lost [0..1)")
    run.add_argument(
        "--vision",
        choices=VISION_MODES,
        help="positions from the host's tracker on rendered "
        "1280x720 overhead frames (ArUco marker on the object, or colour blob) instead of the truth",
    )
    run.add_argument("--json", action="store_true", help="print one JSON object instead of the sentence")
    run.add_argument("--video", action="store_true", help="also render an MP4 from the overhead camera")
    run.add_argument("--video-fps", type=float, default=30.0, help="video frame rate [1/s]")
    run.add_argument(
        "--port",
        help="serial device path of a firmware to use instead of starting the virtual MCU "
        "(a simulated-clock firmware runs in lock-step; a board needs --realtime)",
    )
    run.add_argument(
        "--realtime", action="store_true", help="run in real time against a wall-clock virtual MCU instead of lock-step"
    )
    run.add_argument(
        "--viewer",
        action="store_true",
        help="show the MuJoCo viewer (needs a display; implies "
        "nothing about pacing: add --realtime to watch at real speed)",
    )
    add_view_arguments(run)
    run.set_defaults(func=_handler("run", run))


def _add_replay(sim_sub: argparse._SubParsersAction, fmt) -> None:
    replay = sim_sub.add_parser(
        "replay",
        help="run one trial of a results file again, recorded (and live) for the viewer",
        description="One trial of a heatmap, calibration, tuning or fidelity run, by its cell and trial number, run "
        "again exactly as it ran (trials are deterministic) and written as a recording (.rrd) for the Rerun viewer "
        "(`rerun FILE`); it says whether the outcome matches the results file's.",
        formatter_class=fmt,
        parents=[O.out("the recording (default: beside the results file)")],
    )
    replay.add_argument("results", help="results.jsonl (or .jsonl.gz) of a run, or its folder")
    replay.add_argument("--cell", type=number(0, integer=True), required=True, help="the trial's cell index")
    replay.add_argument("--trial", type=number(0, integer=True), required=True, help="the trial's number in its cell")
    add_view_arguments(replay)
    replay.set_defaults(func=_handler("replay", replay))


def _add_heatmap(sim_sub: argparse._SubParsersAction, shared: dict, fmt) -> None:
    out = O.out(
        "results.jsonl, cells.csv, summary.json, heatmap.png and heatmap_reach.png (the paper's stopping rule) "
        "(default out/heatmap/OBJECT_CONTROLLER_alphaA, with _PLANT for a plant other than polyester and _KEY=VALUE "
        "for each --set)"
    )
    heat = sim_sub.add_parser(
        "heatmap",
        help="the paper's success heatmap (Fig. 2) over the workspace",
        description=HEATMAP,
        formatter_class=fmt,
        parents=[shared[k] for k in ("trial", "alpha", "closed_loop", "fidelity", "pool", "json")]
        + [O.plant_set(), out],
    )
    heat.add_argument("--cells", type=int, default=20, help="cells per side of the workspace (paper: 20)")
    heat.add_argument("--trials", type=int, default=10, help="trials per cell, N (paper: 10)")
    heat.add_argument("--seed", type=int, default=2026, help="seed of the whole run: starts, targets and noise")
    heat.add_argument(
        "--stop-when-reached",
        action="store_true",
        help="end each trial at its first frame within ε, as the paper's loop does: faster, and the map "
        "under the paper's stopping rule is the same, but 'ends within ε at T' is then not measured",
    )
    heat.add_argument(
        "--adaptive",
        action="store_true",
        help="stop a cell's trials once the region its N trials would put it in (success >= 0.9, failure <= 0.1, "
        "uncertain between) is decided at 95 %%, after at least 2 (sim/evaluation/adaptive.py): fewer trials, in rounds; "
        "its results file is its own (never merged with a full run's)",
    )
    heat.add_argument(
        "--only-cells", type=O.cells, metavar="I,J,...", help="run only these cells (index ix + iy*cells)"
    )
    add_view_arguments(heat)
    heat.set_defaults(func=_handler("heatmap", heat))


def _add_calibrate(sim_sub: argparse._SubParsersAction, shared: dict, fmt) -> None:
    out = O.out(
        "study.db, report.md, report.json, pareto.png "
        "(default out/calibration/findings, or out/calibration/log with --log)"
    )
    cal = sim_sub.add_parser(
        "calibrate",
        help="fit the plant to the paper's findings or to rig logs (Optuna, resumable)",
        description=CALIBRATE,
        formatter_class=fmt,
        parents=[shared[k] for k in ("trial", "fidelity", "pool", "json")]
        + [O.plant(DEFAULT_PLANT), O.plant_set(), out],
    )
    cal.add_argument(
        "--candidates",
        type=number(0, integer=True),
        default=100,
        help="candidates the study should hold when done (0: only write the report)",
    )
    cal.add_argument(
        "--params",
        metavar="KEY,KEY",
        help="search only these parameters (keys of sim/model/plant.toml; default every one declared search = true)",
    )
    cal.add_argument(
        "--log",
        action="append",
        metavar="RUN.jsonl",
        help="fit to this rig log (mantaray rig's output) instead of the findings; repeatable",
    )
    cal.add_argument("--horizon", type=float, help="with --log: compare only the first HORIZON seconds of each run")
    cal.add_argument(
        "--cells-per-stratum",
        type=int,
        default=4,
        help="cells drawn from each of centre, axes, diagonals, edges and corners",
    )
    cal.add_argument("--trials-per-cell", type=int, default=3)
    cal.add_argument(
        "--seed",
        type=int,
        default=12,
        help="seed of the search and its trials (the heatmaps judged afterwards use another)",
    )
    cal.add_argument("--fig3", action="store_true", help="also run the paper's Fig. 3 experiment (F6) on the best")
    cal.set_defaults(func=_handler("calibrate", cal))


def _add_tune(sim_sub: argparse._SubParsersAction, shared: dict, fmt) -> None:
    out = O.out(
        "study.db, settings.toml, report.json, history.png and final/ (default out/tune/OBJECT_CONTROLLER_alphaA_PLANT)"
    )
    tune = sim_sub.add_parser(
        "tune",
        help="tune a controller's settings for a plant (Optuna, resumable)",
        description=TUNE,
        formatter_class=fmt,
        parents=[shared[k] for k in ("trial", "alpha", "fidelity", "pool", "json")] + [O.plant("paper"), out],
    )
    tune.add_argument(
        "--controller",
        choices=choices(m.Controller),
        default="scheduled",
        help="the controller whose settings are searched (sim/search/tune.py, SPACE, says which)",
    )
    tune.add_argument(
        "--per-axis",
        action="store_true",
        help="search each PID's gains on its own (x and y apart) instead of one set for all: for a rig "
        "that is not symmetric",
    )
    tune.add_argument(
        "--start-from",
        metavar="FILE",
        help="a settings file of the same controller (say, tuned for another object) to try second, "
        "after the boot values, so the search starts from what is known; for a new study only",
    )
    tune.add_argument(
        "--candidates",
        type=number(1, integer=True),
        default=60,
        help="candidates the study should hold when done (a resumed search goes on to this total)",
    )
    O.sample(tune, cells_per_stratum=4, trials_per_cell=3)
    tune.add_argument(
        "--confirm",
        type=number(0, integer=True),
        default=0,
        metavar="K",
        help="after the search, score its K best candidates again on the same sample at --confirm-at, "
        "and take the best there: a search screened at a cheaper fidelity answers at the finer one "
        "(the report gives the rank correlation of the two scores; 0: no confirmation)",
    )
    tune.add_argument(
        "--confirm-at",
        default="reference",
        metavar="FIDELITY",
        help="the fidelity of the confirmation and of the final check: fast, reference or RESOLUTION:TIMESTEP",
    )
    tune.add_argument(
        "--prune",
        action="store_true",
        help="score each candidate a rung of the sample at a time (1, 2, 4 ... cells per stratum, the same "
        "for every candidate) and stop one whose misses are not among the better half at a rung "
        "(Optuna's successive halving): more candidates for the same trials; --candidates then "
        "counts the stopped ones too",
    )
    tune.add_argument("--seed", type=number(0, integer=True), default=31, help="seed of the search and its sample")
    tune.add_argument(
        "--final-trials",
        type=number(0, integer=True),
        default=10,
        help="trials per cell of the final check on the full protocol (paper: 10; 0: no final check)",
    )
    tune.add_argument(
        "--final-cells",
        type=number(1, integer=True),
        default=20,
        help="cells per side of the final check's workspace (paper: 20)",
    )
    tune.add_argument(
        "--final-seed",
        type=number(0, integer=True),
        default=2026,
        help="seed of the final check (the paper protocol's; never the search's)",
    )
    tune.set_defaults(func=_handler("tune", tune))


def _add_fidelity(sim_sub: argparse._SubParsersAction, shared: dict, fmt) -> None:
    gate = sim_sub.add_parser(
        "fidelity",
        help="the fidelity gate: does a cheaper physics keep a finer one's outcomes",
        description=FIDELITY,
        formatter_class=fmt,
        parents=[shared[k] for k in ("trial", "alpha", "jobs", "json")]
        + [
            O.plant(DEFAULT_PLANT),
            O.plant_set(),
            O.out(
                "report.json and report.md (default out/fidelity/OBJECT_PLANT[_KEY=VALUE]_alphaA_CANDIDATE_vs_FINER)"
            ),
        ],
    )
    gate.add_argument(
        "--candidate",
        default="reference",
        help="the configuration under test: fast, reference, or "
        "RESOLUTION:TIMESTEP [vertices per side : s] (like 15:0.002)",
    )
    gate.add_argument(
        "--finer",
        default="finer",
        help="the configuration whose answers it must give: finer (the candidate's mesh 6 vertices a side finer, "
        "at half its step), or as --candidate",
    )
    gate.add_argument(
        "--controller",
        action="append",
        metavar="NAME|FILE",
        help="a controller with its boot values, or a settings file (TOML, as mantaray sim tune writes); "
        "repeatable (default: manhattan and euclidean)",
    )
    O.sample(gate, cells_per_stratum=8, trials_per_cell=5)
    gate.add_argument("--seed", type=number(0, integer=True), default=77, help="seed of the sample's cells and trials")
    gate.add_argument(
        "--shift",
        type=float,
        action="append",
        metavar="M",
        help="[m] how far a floor's run moves every start; repeatable, one floor each (default: 0.002, the rig's "
        "repeatability)",
    )
    grows = gate.add_mutually_exclusive_group()
    grows.add_argument(
        "--until-decided",
        action="store_true",
        help="while undecided, grow the sample to the pairs its intervals say would decide it, and go on",
    )
    gate.add_argument(
        "--max-pairs",
        type=number(1, integer=True),
        default=1000,
        help="with --until-decided, the most pairs per controller the sample grows to",
    )
    grows.add_argument(
        "--report-only",
        action="store_true",
        help="judge the trials --trials-dir holds and run none (a sample too costly here, or still running elsewhere)",
    )
    grows.add_argument(
        "--candidate-only",
        action="store_true",
        help="run the candidate alone, on the trials the finer run and its floors hold already (read as they stand, "
        "so a gate adding to them may run beside): another candidate judged against a costly finer run at the "
        "candidate's cost",
    )
    gate.add_argument(
        "--runs",
        nargs="+",
        metavar="FILE",
        help="compare existing results files instead of running the sample: the candidate's, the finer run's, "
        "then any floors (the finer run with its starts moved)",
    )
    gate.add_argument(
        "--trials-dir",
        default="out/fidelity/trials",
        help="where each run keeps its trials (one results file per controller, fidelity and shift)",
    )
    gate.set_defaults(func=_handler("fidelity", gate))
