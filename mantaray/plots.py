"""The figures from plain arrays, shared by the rig and the simulation: Fig. 3 paths and phases, Fig. 2 heatmaps, Pareto fronts."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: runs headless
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402


def path_phase_figure(
    xy_m: np.ndarray,
    tilt_deg: np.ndarray,
    start_m,
    targets_m,
    tolerance_m: float,
    title: str,
    module_m: tuple[float, float],
    tilt_limit_deg: float,
    path: str | Path,
    t_s=None,
    command_m=None,
    range_m: float | None = None,
    modules: tuple[int, int] = (1, 1),
    handovers_m=None,
) -> Path:
    """Save the object's path (start, targets with their tolerance circles, the module's outline) above the
    phase plot theta_zx vs theta_zy with the tilt-limit square, as the paper's Fig. 3 draws them. targets_m
    is one target, or each frame's target along a path. With t_s [s] (one per row of xy_m and tilt_deg; NaN rows
    are frames without a measurement), a column beside them shows over time the distance to the target against
    epsilon, both tilts against the limit and, with command_m, the four actuator commands [m] against +-range_m.
    On an array (modules along x, y, of module_m each) the surface is outlined with the modules' borders dashed,
    and handovers_m marks where the firmware passed the object to another module. Returns the file written."""
    if t_s is None:
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(4.2, 8.0))
    else:
        fig = plt.figure(figsize=(9.6, 8.0))
        grid = fig.add_gridspec(6, 2, width_ratios=(1.0, 1.15))
        top, bottom = fig.add_subplot(grid[0:3, 0]), fig.add_subplot(grid[3:6, 0])
        _draw_over_time(
            fig,
            grid,
            np.asarray(t_s, dtype=float),
            xy_m,
            targets_m,
            tolerance_m,
            tilt_deg,
            tilt_limit_deg,
            command_m,
            range_m,
        )
    _draw_paths(top, [(xy_m, start_m, targets_m)], tolerance_m, module_m, modules)
    if handovers_m is not None and len(handovers_m):
        points = np.asarray(handovers_m, dtype=float).reshape(-1, 2)
        top.plot(points[:, 0], points[:, 1], "D", color="tab:orange", ms=4, label="hand-over")
    top.set_title(title, fontsize=9)
    top.legend(fontsize=7, loc="upper right")
    _draw_phase(bottom, [tilt_deg], tilt_limit_deg)
    bottom.set_title(f"controller output; red: ±{tilt_limit_deg:.1f}° tilt limit", fontsize=9)
    return _save(fig, path)


def _draw_over_time(
    fig,
    grid,
    t_s: np.ndarray,
    xy_m,
    targets_m,
    tolerance_m: float,
    tilt_deg,
    tilt_limit_deg: float,
    command_m,
    range_m: float | None,
) -> None:
    """The right-hand column of path_phase_figure: error, tilts and commands against time."""
    xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    targets = np.asarray(targets_m, dtype=float).reshape(-1, 2)
    targets = targets if len(targets) == len(xy) else np.broadcast_to(targets[-1], xy.shape)
    rows = 3 if command_m is not None else 2
    span = 6 // rows
    error = fig.add_subplot(grid[0:span, 1])
    error.plot(t_s, np.hypot(*(xy - targets).T) * 100, color="tab:cyan", lw=1.2)
    error.axhline(tolerance_m * 100, ls="--", color="tab:blue", lw=1.0, label=f"ε = {tolerance_m * 100:g} cm")
    error.set_ylabel("distance to target [cm]")
    error.legend(fontsize=7, loc="upper right")
    tilts = fig.add_subplot(grid[span : 2 * span, 1], sharex=error)
    tilt = np.asarray(tilt_deg, dtype=float).reshape(-1, 2)
    tilts.plot(t_s[: len(tilt)], tilt[:, 0], lw=1.0, label="θ_zx")
    tilts.plot(t_s[: len(tilt)], tilt[:, 1], lw=1.0, label="θ_zy")
    for sign in (1, -1):
        tilts.axhline(sign * tilt_limit_deg, ls=":", color="tab:red", lw=1.2)
    tilts.set_ylabel("tilt [deg]")
    tilts.legend(fontsize=7, loc="upper right", ncol=2)
    last = tilts
    if command_m is not None:
        commands = fig.add_subplot(grid[2 * span : 6, 1], sharex=error)
        command = np.asarray(command_m, dtype=float).reshape(-1, 4)
        for i in range(4):
            commands.plot(t_s[: len(command)], command[:, i] * 100, lw=1.0, label=f"a{i}")
        if range_m is not None:
            for sign in (1, -1):
                commands.axhline(sign * range_m * 100, ls=":", color="tab:red", lw=1.2)
        commands.set_ylabel("command [cm], + lowers")
        commands.legend(fontsize=7, loc="upper right", ncol=4)
        last = commands
    last.set_xlabel("time [s]")


def fig3_figure(
    runs: dict[str, list[dict]],
    tolerance_m: float,
    module_m: tuple[float, float],
    tilt_limit_deg: float,
    title: str,
    path: str | Path,
) -> Path:
    """Save the paper's Fig. 3 for several objects: per object (a column) every run's path to its target's
    tolerance circle above the phase plot of its tilts. runs: object -> [{path_m, tilt_deg, target_m, reached}]."""
    fig, axes = plt.subplots(2, len(runs), figsize=(2.6 * len(runs), 5.6), squeeze=False)
    for col, (name, trials) in enumerate(runs.items()):
        top, bottom = axes[0][col], axes[1][col]
        _draw_paths(top, [(t["path_m"], (0.0, 0.0), t["target_m"]) for t in trials], tolerance_m, module_m)
        reached = sum(bool(t["reached"]) and not t.get("fell_off") for t in trials)
        top.set_title(f"{name}, α = {trials[0].get('alpha_m', 0):g}: {reached}/{len(trials)}", fontsize=8)
        _draw_phase(bottom, [t["tilt_deg"] for t in trials], tilt_limit_deg)
    fig.suptitle(title, fontsize=9)
    return _save(fig, path)


def _draw_paths(
    ax, runs: list[tuple], tolerance_m: float, module_m: tuple[float, float], modules: tuple[int, int] = (1, 1)
) -> None:
    """The surface's outline (an array's module borders dashed) and, per run (xy_m, start_m or None, one target or a
    path of targets), its path."""
    hx, hy = modules[0] * module_m[0] / 2, modules[1] * module_m[1] / 2
    ax.add_patch(Rectangle((-hx, -hy), 2 * hx, 2 * hy, fill=False, lw=1.2, color="0.3"))
    for i in range(1, modules[0]):
        ax.axvline(-hx + i * module_m[0], ls="--", lw=0.8, color="0.5")
    for j in range(1, modules[1]):
        ax.axhline(-hy + j * module_m[1], ls="--", lw=0.8, color="0.5")
    for i, (xy_m, start_m, targets_m) in enumerate(runs):
        first = i == 0
        targets = np.asarray(targets_m, dtype=float).reshape(-1, 2)
        if len(targets) > 1:
            ax.plot(targets[:, 0], targets[:, 1], ls="--", lw=1.0, color="tab:blue", label="path" if first else None)
        ax.add_patch(Circle(targets[-1], tolerance_m, fill=False, ls="--", lw=1.2, color="tab:blue"))
        xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if len(xy):
            ax.plot(xy[:, 0], xy[:, 1], color="tab:cyan", lw=1.5, label="object" if first else None)
            ax.plot(*xy[-1], "o", color="tab:red", ms=5, label="end" if first else None)
        if start_m is not None:
            ax.plot(*start_m, "s", color="0.2", ms=5, label="start" if first else None)
        ax.plot(*targets[-1], "x", color="tab:blue", ms=7, label="target" if first else None)
    ax.set_xlim(-hx - 0.05, hx + 0.05)
    ax.set_ylim(-hy - 0.05, hy + 0.05)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def _draw_phase(ax, tilts: list, tilt_limit_deg: float) -> None:
    """Each run's theta_zx against theta_zy [deg] with the dotted red square of the tilt limit."""
    lim = tilt_limit_deg
    ax.add_patch(Rectangle((-lim, -lim), 2 * lim, 2 * lim, fill=False, ls=":", lw=1.5, color="tab:red"))
    span = lim * 1.15
    for tilt_deg in tilts:
        tilt = np.asarray(tilt_deg, dtype=float).reshape(-1, 2)
        tilt = tilt[np.all(np.isfinite(tilt), axis=1)]
        if len(tilt):
            ax.plot(tilt[:, 0], tilt[:, 1], color="tab:purple", lw=1.0)
            ax.plot(*tilt[0], "s", color="0.2", ms=4)
            span = max(span, float(np.abs(tilt).max()) * 1.1)
    ax.set_xlim(-span, span)
    ax.set_ylim(-span, span)
    ax.set_aspect("equal")
    ax.set_xlabel("θ_zx [deg]")
    ax.set_ylabel("θ_zy [deg]")


def _save(fig, path: str | Path) -> Path:
    """Lay out, write (creating the folder) and close a figure; returns the file written."""
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def heatmap_figure(
    rates: np.ndarray, module_m: tuple[float, float], title: str, path: str | Path, difference: bool = False
) -> Path:
    """Save a per-cell map like the paper's Fig. 2: success rate [%] per cell ([iy, ix], NaN: not run), or with
    difference=True a signed difference of two rates in percentage points; returns the file written."""
    hx, hy = module_m[0] / 2, module_m[1] / 2
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    cmap = plt.get_cmap("RdBu" if difference else "viridis").copy()
    cmap.set_bad("0.85")
    limits = (-100, 100) if difference else (0, 100)
    image = ax.imshow(
        rates * 100,
        origin="lower",
        extent=(-hx, hx, -hy, hy),
        cmap=cmap,
        vmin=limits[0],
        vmax=limits[1],
        interpolation="nearest",
    )
    fig.colorbar(image, ax=ax, label="difference [percentage points]" if difference else "success rate [%]")
    ax.set_xlabel("target x [m]")
    ax.set_ylabel("target y [m]")
    ax.set_title(title, fontsize=9)
    return _save(fig, path)


def pareto_figure(
    values: np.ndarray, on_front: np.ndarray, names: tuple[str, ...], title: str, path: str | Path
) -> Path:
    """Save one panel per pair of objectives (values: [candidates, objectives], all minimised): every candidate a
    grey dot, those on the Pareto front (on_front) ringed."""
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))]
    fig, axes = plt.subplots(1, len(pairs), figsize=(4.2 * len(pairs), 3.8), squeeze=False)
    for ax, (i, j) in zip(axes[0], pairs, strict=True):
        ax.scatter(values[:, i], values[:, j], s=12, c="0.6", label="candidate")
        ax.scatter(
            values[on_front, i], values[on_front, j], s=40, facecolors="none", edgecolors="C3", label="Pareto front"
        )
        ax.set_xlabel(names[i], fontsize=8)
        ax.set_ylabel(names[j], fontsize=8)
    axes[0][0].legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    return _save(fig, path)


def savings_figure(points: list[tuple[str, float, float]], aim: tuple[float, float], title: str, path) -> Path:
    """Each run's (label, trials saved [x], cells moved [%]) beside the aim's bounds (dashed): right of and below."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, saved, moved in points:
        ax.scatter(saved, moved, color="tab:blue")
        ax.annotate(label, (saved, moved), fontsize=6, xytext=(3, 2), textcoords="offset points")
    ax.axvline(aim[0], color="grey", ls="--", lw=0.8)
    ax.axhline(aim[1], color="grey", ls="--", lw=0.8)
    ax.set_xlabel("trials of the full map / trials of its adaptive twin")
    ax.set_ylabel("cells whose region moves [%]")
    ax.set_title(title, fontsize=8)
    return _save(fig, path)
