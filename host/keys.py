"""Keys pressed during a run (`mantaray rig`): single keys from the terminal, no Enter needed, read without waiting.

None at all where stdin is no terminal (nohup, a pipe, a test) or the run is in the background, which then goes on."""

from __future__ import annotations

import os
import select
import signal


class Keys:
    """The terminal on fd (stdin) in cbreak mode (no line buffering, no echo; Ctrl-C still interrupts) until close().
    active is False, and read() always '', where fd is no terminal or this process is not in its foreground."""

    def __init__(self, fd: int = 0) -> None:
        self.fd = fd
        self._saved = None  # the terminal's settings to restore; None: keys are not read
        if os.name == "posix" and self._foreground():
            import termios
            import tty

            self._saved = termios.tcgetattr(fd)
            tty.setcbreak(fd)

    @property
    def active(self) -> bool:
        return self._saved is not None

    def _foreground(self) -> bool:
        """A terminal whose foreground is this process's group: reading it cannot stop the process (SIGTTIN)."""
        try:
            return os.isatty(self.fd) and os.tcgetpgrp(self.fd) == os.getpgrp()
        except OSError:
            return False

    def read(self) -> str:
        """The keys pressed since the last call, '' when none (or when not active, or in the background now)."""
        if not self.active or not self._foreground():
            return ""
        pressed = b""
        while select.select([self.fd], [], [], 0)[0]:
            try:
                chunk = os.read(self.fd, 64)
            except OSError:  # the terminal hung up
                break
            if not chunk:
                break
            pressed += chunk
        return pressed.decode(errors="replace")

    def close(self) -> None:
        """The terminal's settings back as they were (also from the background: SIGTTOU is ignored meanwhile)."""
        if self._saved is None:
            return
        import termios

        previous = signal.signal(signal.SIGTTOU, signal.SIG_IGN)
        try:
            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
        except termios.error:  # the terminal is gone: nothing to restore
            pass
        finally:
            signal.signal(signal.SIGTTOU, previous)
            self._saved = None

    def __enter__(self) -> Keys:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
