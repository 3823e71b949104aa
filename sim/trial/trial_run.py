"""One watched trial, what `mantaray sim run` runs: the firmware in the loop over a pty (or a port), shown and recorded
while it runs, and its figure, trajectory, recording and video written: the simulation's counterpart of host/rig_run.py."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mantaray.protocol import rig as rig_description

from ..model.rig import Rig
from ..model.tracking import Tracking
from .bridge import Bridge, TrialResult, TrialSpec


@dataclass(frozen=True)
class TrialOutputs:
    """Where one trial's outputs go, and how it is watched while it runs."""

    out: Path  # the folder of every output
    stem: str  # every output's file name, without its suffix
    metadata: dict  # the run's settings, written into its recording
    tilt_limit_deg: float  # [deg] the controller's tilt limit, drawn in the figure
    video_fps: float | None = None  # [frames/s] an .mp4 of the rendered camera at this rate; None: no video
    viewer: bool = False  # MuJoCo's interactive viewer beside the run (needs a display)
    live: object | None = None  # a started live view (mantaray.host.cli_view.start_live) to stream to; None: none
    linger_s: float | None = None  # [s] how long the live view stays up after the run (None: its default)


def run_trial(
    rig: Rig,
    tracking: Tracking,
    spec: TrialSpec,
    outputs: TrialOutputs,
    report: Callable[[str], None],
    *,
    port: str | None = None,
    realtime: bool = False,
    progress: Callable[[float], None] | None = None,
) -> tuple[TrialResult, dict[str, str | None]]:
    """The trial run on a virtual MCU of its own (or the board at port), in lock-step unless realtime, and its
    outputs: (result, {figure, trajectory, recording, video: path}), the recording None where it could not be
    written, the video only when asked for. A start that is not over the hanging sheet raises model.fabric_height's
    ValueError."""
    from mantaray.host.link import Link
    from mantaray.host.transport import SerialTransport
    from mantaray.host.view import REPORTED_ACTUATORS, RunView
    from mantaray.host.vmcu import VirtualMcu

    from .trial_view import TrialView

    live = outputs.live
    hx, hy = rig.module.grid.half_extent_m
    description = rig_description.named(rig.module.build)
    with contextlib.ExitStack() as stack:
        program = description.vmcu_program
        port = port or stack.enter_context(VirtualMcu(clock="wall" if realtime else "sim", program=program)).path
        link = Link(SerialTransport(port), description=description)
        stack.callback(link.close)
        bridge = Bridge(link, rig, tracking, lockstep=not realtime)
        grpc_url = None if live is None else live.options.grpc_url
        view = RunView(
            "mantaray_sim_run", outputs.out / f"{outputs.stem}.rrd", grpc_url, outputs.metadata, REPORTED_ACTUATORS,
            (2 * hx, 2 * hy), report, world=True,
        )  # fmt: skip
        trial_view = bridge.view = TrialView(view, bridge.model, bridge.data, rig, link, lockstep=not realtime)
        if outputs.viewer:
            import mujoco.viewer

            bridge.viewer = mujoco.viewer.launch_passive(bridge.model, bridge.data)
        if outputs.video_fps is not None:
            from .video import Recorder

            bridge.recorder = Recorder(bridge.model, fps=outputs.video_fps, grid=rig.module.grid)
        try:
            result = bridge.run(spec, progress=progress)
        finally:
            recording = trial_view.close()
        if bridge.viewer is not None:
            bridge.viewer.close()
        if live is not None:
            live.linger(outputs.linger_s, report)
    paths = {
        "figure": str(_figure(result, rig, outputs)),
        "trajectory": str(save_trajectory(result, outputs.out / f"{outputs.stem}.npz")),
        "recording": None if recording is None else str(recording),  # None: the view could not write it
    }
    if bridge.recorder is not None:
        paths["video"] = str(bridge.recorder.save(outputs.out / f"{outputs.stem}.mp4"))
    return result, paths


OUTCOMES = ("fell off", "success", "not within ε at T")  # one word per meaning: success is within ε at T (the exit
# status); "reached" is within ε at some camera frame


def outcome_words(result: TrialResult) -> str:
    """The outcome, one of OUTCOMES."""
    return OUTCOMES[0] if result.fell_off else OUTCOMES[1] if result.success else OUTCOMES[2]


def _figure(result: TrialResult, rig: Rig, outputs: TrialOutputs) -> Path:
    from mantaray.plots import path_phase_figure

    spec = result.spec
    return path_phase_figure(
        result.true_xy_m,
        result.tilt_deg,
        spec.start_m,
        [spec.target_m],
        spec.tolerance_m,
        f"{result.object_name}, {spec.controller}, α = {spec.alpha_m:g} m: {outcome_words(result)}\n"
        f"final error {result.final_error_m * 100:.1f} cm (ε = {spec.tolerance_m * 100:g} cm)",
        (rig.module.size_x_m, rig.module.size_y_m),
        outputs.tilt_limit_deg,
        outputs.out / f"{outputs.stem}.png",
        t_s=result.t_s,
        command_m=result.command_m,
        range_m=rig.actuators.range_m,
        modules=(rig.module.modules_x, rig.module.modules_y),
        handovers_m=result.handover_xy_m,
    )


def save_trajectory(result: TrialResult, path: Path) -> Path:
    """The trial's time series as a compressed .npz (names with their units)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path,
        t_s=result.t_s,
        true_xy_m=result.true_xy_m,
        measured_xy_m=result.measured_xy_m,
        tilt_deg=result.tilt_deg,
        command_m=result.command_m,
        measured_m=result.measured_m,
        state=result.state,
        module=result.module,
        start_m=result.spec.start_m,
        target_m=result.spec.target_m,
    )
    return path
