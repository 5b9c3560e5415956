"""The progress line of a command on stderr."""

from __future__ import annotations

import sys
import time


class Progress:
    """Progress of a command: the phase it is in (`status`) and the solve,
    fed by interpolate's callback(k, error).

    On a terminal: one live line on stderr (the phase, then iteration and
    E_k/E_0 redrawn at most 10 times a second), erased at the end. In a pipe
    or a file: a plain line every two seconds of iterating (short runs print
    none), no phases. Disabled: nothing at all. A context manager: the live
    line is erased however the block ends (before an error message).
    """

    def __init__(self, label: str = "", enabled: bool = True, stream=None):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.tty = enabled and _isatty(self.stream)
        self.interval = 0.1 if self.tty else 2.0
        self.width = 0
        self.restart(label)

    def restart(self, label: str) -> None:
        """A new solve: its label, its clock."""
        self.label = label
        self.start = self.last = time.perf_counter()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _draw(self, text: str) -> None:
        global _live_line
        self.stream.write("\r" + text.ljust(self.width))
        self.width = len(text)
        self.stream.flush()
        _live_line = self

    def status(self, text: str) -> None:
        """Show the phase the command is in (terminal only); current_phase() returns it."""
        global _phase
        _phase = text
        if self.tty:
            self._draw(f"{text} ...")

    def __call__(self, k: int, error: float) -> bool:
        if self.enabled:
            now = time.perf_counter()
            if now - self.last >= self.interval:
                self.last = now
                text = f"{self.label}: iteration {k}, E_k/E_0 = {error:.3e}, {now - self.start:.1f} s"
                if self.tty:
                    self._draw(text)
                else:
                    self.stream.write(text + "\n")
                    self.stream.flush()
        return False  # never ask the solver to stop

    def close(self) -> None:
        """Erase the live line (it is drawn again by the next update)."""
        global _live_line
        if self.tty and self.width:
            self.stream.write("\r" + " " * self.width + "\r")
            self.stream.flush()
            self.width = 0
        if _live_line is self:
            _live_line = None


_live_line: Progress | None = None  # the Progress whose line is on the terminal now
_phase = ""  # the last phase a Progress was told of (status), shown or not


def current_phase() -> str:
    """The phase the command is in, for an error that has no place of its own (out of memory)."""
    return _phase


def reset_phase() -> None:
    global _phase
    _phase = ""


def erase_live_line() -> None:
    """Erase the live line, if one is drawn, so that a message gets a line of its own."""
    if _live_line is not None:
        _live_line.close()


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
