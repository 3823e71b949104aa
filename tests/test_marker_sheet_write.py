"""Writing the marker sheet: a write that fails part-way (a full disk) leaves the old sheet or none, never a cut one,
and the command says so in one line with exit status 2."""

from __future__ import annotations

import errno
import os
import resource
import signal
import subprocess
import sys

import pytest
from matplotlib.figure import Figure

from mantaray.host import marker_sheet as M
from mantaray.outputs import OutputError

FILE_LIMIT_BYTES = 8000  # a sheet is ~30 kB as a PDF, more as a PNG: the write fails part-way, as on a full disk


def _file_size_limit() -> None:
    """In the child: files may not grow past FILE_LIMIT_BYTES; a write past it fails (EFBIG) instead of killing."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_LIMIT_BYTES, FILE_LIMIT_BYTES))


@pytest.mark.parametrize("name", ["sheet.pdf", "sheet.png"])
def test_a_write_cut_off_part_way_leaves_no_file_and_says_so_in_one_line(tmp_path, name):
    """matplotlib's PDF writer answers a failed write with an AttributeError; the command names the OSError."""
    out = tmp_path / name
    run = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "markers", "--out", str(out)],
        cwd=tmp_path,
        preexec_fn=_file_size_limit,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2
    assert run.stderr.splitlines() == [f"mantaray markers: cannot write {out}: File too large"]
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_keeps_the_sheet_written_before(tmp_path, monkeypatch):
    out = tmp_path / "markers.pdf"
    out.write_bytes(b"last week's sheet")

    def full_disk(figure, path, **options):
        with open(path, "wb") as f:
            f.write(b"%PDF-1.4 and then")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Figure, "savefig", full_disk)
    with pytest.raises(OutputError) as failed:
        M.write_marker_sheet(out, 300)
    assert str(failed.value) == f"cannot write {out}: No space left on device"
    assert out.read_bytes() == b"last week's sheet" and list(tmp_path.iterdir()) == [out]


def test_a_writer_that_fails_otherwise_raises_as_it_did_and_leaves_nothing(tmp_path):
    def broken(path):
        path.write_bytes(b"half")
        raise ZeroDivisionError

    with pytest.raises(ZeroDivisionError):
        M.write_then_replace(tmp_path / "sheet.png", broken)
    assert list(tmp_path.iterdir()) == []


def test_a_sheet_written_whole_takes_the_old_ones_place(tmp_path):
    out = tmp_path / "markers.png"
    out.write_bytes(b"old")
    assert M.write_marker_sheet(out, 72) == 6
    assert out.read_bytes().startswith(b"\x89PNG") and list(tmp_path.iterdir()) == [out]
