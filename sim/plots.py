"""Figures of a trial in the style of the paper's Fig. 3: the object's path over the fabric and the tilt phase plot."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: runs headless
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

from .bridge import TrialResult  # noqa: E402


def trajectory_figure(result: TrialResult, module_m: tuple[float, float], tilt_limit_deg: float,
                      path: str | Path) -> Path:
    """Save the Fig. 3-style figure of a simulated trial (path_phase_figure); returns the file written."""
    spec = result.spec
    outcome = "fell off" if result.fell_off else ("reached" if result.success else "not reached")
    title = (f"{result.object_name}, {spec.controller}, α = {spec.alpha_m:g} m: {outcome}\n"
             f"final error {result.final_error_m * 100:.1f} cm (ε = {spec.tolerance_m * 100:g} cm)")
    return path_phase_figure(result.true_xy_m, result.tilt_deg, spec.start_m, [spec.target_m], spec.tolerance_m,
                             title, module_m, tilt_limit_deg, path)


def path_phase_figure(xy_m: np.ndarray, tilt_deg: np.ndarray, start_m, targets_m, tolerance_m: float, title: str,
                      module_m: tuple[float, float], tilt_limit_deg: float, path: str | Path) -> Path:
    """Save the object's path (start, targets with their tolerance circles, the module's outline) above the
    phase plot theta_zx vs theta_zy with the tilt-limit square, as the paper's Fig. 3 draws them. targets_m
    is one target, or the successive targets of a path; returns the file written."""
    hx, hy = module_m[0] / 2, module_m[1] / 2
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(4.2, 8.0))

    top.add_patch(Rectangle((-hx, -hy), 2 * hx, 2 * hy, fill=False, lw=1.2, color="0.3"))
    targets = np.asarray(targets_m, dtype=float).reshape(-1, 2)
    if len(targets) > 1:
        top.plot(targets[:, 0], targets[:, 1], ls="--", lw=1.0, color="tab:blue", label="path")
    top.add_patch(Circle(targets[-1], tolerance_m, fill=False, ls="--", lw=1.2, color="tab:blue"))
    xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if len(xy):
        top.plot(xy[:, 0], xy[:, 1], color="tab:cyan", lw=1.5, label="object")
        top.plot(*xy[-1], "o", color="tab:red", ms=6, label="end")
    if start_m is not None:
        top.plot(*start_m, "s", color="0.2", ms=6, label="start")
    top.plot(*targets[-1], "x", color="tab:blue", ms=8, label="target")
    top.set_title(title, fontsize=9)
    top.set_xlim(-hx - 0.05, hx + 0.05)
    top.set_ylim(-hy - 0.05, hy + 0.05)
    top.set_aspect("equal")
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.legend(fontsize=7, loc="upper right")

    lim = tilt_limit_deg
    bottom.add_patch(Rectangle((-lim, -lim), 2 * lim, 2 * lim, fill=False, ls=":", lw=1.5, color="tab:red"))
    tilt = np.asarray(tilt_deg, dtype=float).reshape(-1, 2)
    tilt = tilt[np.all(np.isfinite(tilt), axis=1)]
    if len(tilt):
        bottom.plot(tilt[:, 0], tilt[:, 1], color="tab:purple", lw=1.0)
        bottom.plot(*tilt[0], "s", color="0.2", ms=5)
    span = max(lim * 1.15, float(np.abs(tilt).max()) * 1.1 if len(tilt) else 0.0)
    bottom.set_xlim(-span, span)
    bottom.set_ylim(-span, span)
    bottom.set_aspect("equal")
    bottom.set_xlabel("θ_zx [deg]")
    bottom.set_ylabel("θ_zy [deg]")
    bottom.set_title(f"controller output; red: ±{lim:.1f}° tilt limit", fontsize=9)
    return _save(fig, path)


def _save(fig, path: str | Path) -> Path:
    """Lay out, write (creating the folder) and close a figure; returns the file written."""
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def heatmap_figure(rates: np.ndarray, module_m: tuple[float, float], title: str, path: str | Path,
                   difference: bool = False) -> Path:
    """Save a per-cell map like the paper's Fig. 2: success rate [%] per cell ([iy, ix], NaN: not run), or with
    difference=True a signed difference of two rates in percentage points; returns the file written."""
    hx, hy = module_m[0] / 2, module_m[1] / 2
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    cmap = plt.get_cmap("RdBu" if difference else "viridis").copy()
    cmap.set_bad("0.85")
    limits = (-100, 100) if difference else (0, 100)
    image = ax.imshow(rates * 100, origin="lower", extent=(-hx, hx, -hy, hy), cmap=cmap, vmin=limits[0],
                      vmax=limits[1], interpolation="nearest")
    fig.colorbar(image, ax=ax, label="difference [percentage points]" if difference else "success rate [%]")
    ax.set_xlabel("target x [m]")
    ax.set_ylabel("target y [m]")
    ax.set_title(title, fontsize=9)
    return _save(fig, path)
