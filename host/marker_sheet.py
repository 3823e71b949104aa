"""The printable A4 sheet of the rig's ArUco markers at true size (PDF or PNG), with a ruler to check the print."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from mantaray.outputs import OutputError

from .markers import MarkerLayout, marker_image, quiet_scale

A4_MM = (210.0, 297.0)
DPI_RANGE = (72, 2400)  # [1/inch] a PNG sheet's resolution: from screen to the finest printers


PRINTED = MarkerLayout()  # the layout this sheet prints unless told another


def write_marker_sheet(out: Path, dpi: int, layout: MarkerLayout = PRINTED) -> int:
    """Draw the four corner markers and two of each object's marker on A4 into out; returns how many markers it holds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    items = [(f"corner {k} (id {i})", i, layout.corner_size_m) for k, i in enumerate(layout.corner_ids)]
    items += [(f"object (id {i})", i, layout.object_size_m) for i in layout.object_ids for _ in range(2)]  # a spare
    fig = plt.figure(figsize=(A4_MM[0] / 25.4, A4_MM[1] / 25.4))
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, A4_MM[0])
    ax.set_ylim(0, A4_MM[1])
    ax.set_axis_off()
    for n, (label, marker_id, size_m) in enumerate(items):
        side = size_m * 1000 * quiet_scale(layout)  # [mm] with the white quiet zone
        x = 25 + (n % 2) * 90
        y = A4_MM[1] - 40 - (n // 2) * 80 - side
        ax.imshow(
            marker_image(layout, marker_id, 480),
            cmap="gray",
            vmin=0,
            vmax=255,
            interpolation="nearest",
            extent=(x, x + side, y, y + side),
        )
        ax.text(x, y - 6, f"{label}: black square {size_m * 1000:.0f} mm", fontsize=8)
    ax.plot([25, 125], [15, 15], color="black", lw=1)
    ax.text(25, 18, "100 mm: check this after printing (print at 100 %, no fit-to-page)", fontsize=8)
    ax.text(
        25,
        8,
        f"{layout.dictionary}; corner markers at (±{layout.corner_offset_m[0]}, ±{layout.corner_offset_m[1]})"
        " m in the fabric frame, their tops toward +y",
        fontsize=7,
    )
    try:
        write_then_replace(out, lambda tmp: fig.savefig(tmp, dpi=dpi))
    finally:
        plt.close(fig)
    return len(items)


def write_then_replace(out: Path, write: Callable[[Path], None]) -> None:
    """write(path) into a file beside out (its suffix out's, for writers that go by it), then put that file in out's
    place: a write that fails (a full disk) leaves out as it was, or absent, never cut short, and removes its file.
    The failure is an OutputError of one line, also when the writer reports it as something else (matplotlib's PDF
    writer raises an AttributeError on a full disk, the OSError behind it)."""
    tmp = out.with_name(f".{out.stem}.tmp-{os.getpid()}{out.suffix}")
    try:
        write(tmp)
        os.replace(tmp, out)
    except Exception as exc:
        cause = next((e for e in _chain(exc) if isinstance(e, OSError)), None)
        if cause is None:
            raise
        raise OutputError(f"cannot write {out}: {cause.strerror or cause}") from None
    finally:
        tmp.unlink(missing_ok=True)  # gone already when the write went through


def _chain(exc: BaseException | None):
    """exc, the exception it was raised while handling, and so on back to the first."""
    while exc is not None:
        yield exc
        exc = exc.__context__
