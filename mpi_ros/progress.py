# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A progress line on stderr for long work (``identify --order auto``, ``diagnose``, ``demo``).

One :class:`Progress` per command run: calling it with a text redraws one status line in
place (a carriage return), prefixed with the time since the run started (redrawn every
second while the work runs, so the clock moves during a long step); :meth:`Progress.say`
prints a permanent line (the command's messages) and keeps the status line below it.  The
status line is drawn only when the stream is a terminal and ``quiet`` is False, so a log
file, a pipe or a test's captured stderr get the permanent lines only.  The library functions take
the status callback as ``progress: Callable[[str], None] | None``
(:func:`mpi_ros.model_fit.identify`, :func:`mpi_ros.diagnosis.diagnose`).
"""

from collections.abc import Callable
import shutil
import sys
import threading
import time
from typing import Any, TextIO

__all__ = ['Progress', 'ProgressCallback']

#: What the library functions accept: a callable taking one line of text.
ProgressCallback = Callable[[str], None]


class Progress:
    """
    A status line redrawn in place on a terminal, and permanent lines.

    Parameters
    ----------
    quiet : bool
        True: never draw the status line (``--quiet``).
    stream : text stream, optional
        Where to write (default: ``sys.stderr`` at the time of each write).
    prefix : str
        Text before the elapsed time on the status line (e.g. ``'[demo] '``).
    interval : float
        Least time [s] between two redraws of the status line; updates in between are
        skipped (a loop may report every sample).  Texts passed with ``force=True`` are
        always drawn.
    tick : float
        Period [s] of the redraw that moves the clock while no new text comes (a daemon
        thread, started with the first status line; 0: none).  :meth:`close` stops it.

    Attributes
    ----------
    active : bool
        Whether the status line is drawn (a terminal and not ``quiet``).
    started : float
        ``time.monotonic()`` at construction.

    """

    def __init__(self, *, quiet: bool = False, stream: TextIO | None = None,
                 prefix: str = '', interval: float = 0.1, tick: float = 1.0) -> None:
        self._stream = stream
        self.active = not quiet and _isatty(self.stream)
        self.prefix = prefix
        self.interval = float(interval)
        self.tick = float(tick)
        self.started = time.monotonic()
        self._text = ''
        self._drawn = ''
        self._last_draw = -float('inf')
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    @property
    def stream(self) -> TextIO:
        """Return the stream written to."""
        return self._stream if self._stream is not None else sys.stderr

    @property
    def elapsed(self) -> float:
        """Return the time [s] since the run started."""
        return time.monotonic() - self.started

    def __call__(self, text: str, *, force: bool = True) -> None:
        """
        Show `text` on the status line (nothing when not :attr:`active`).

        Parameters
        ----------
        text : str
            What is being done (e.g. ``'order n=8, l=4 (5 of 11)'``).
        force : bool
            False: skip the redraw when the last one is less than ``interval`` ago.

        """
        if not self.active:
            return
        with self._lock:
            self._text = text           # the clock's next redraw shows it at the latest
            if not force and time.monotonic() - self._last_draw < self.interval:
                return
            self._draw()
        if self._ticker is None and self.tick > 0.0:
            self._ticker = threading.Thread(target=self._run_ticker, name='progress',
                                            daemon=True)
            self._ticker.start()

    def update(self, text: str) -> None:
        """Show `text` unless the last redraw is less than ``interval`` ago (loops)."""
        self(text, force=False)

    def say(self, text: str) -> None:
        """
        Print a permanent line (always, terminal or not); the status line stays below it.

        Parameters
        ----------
        text : str
            The line, without a newline.

        """
        with self._lock:
            if self.active and self._drawn:
                self._write(f'\r\x1b[K{text}\n{self._drawn}')
            else:
                self._write(f'{text}\n')

    def clear(self) -> None:
        """Remove the status line (before the command prints its result or an error)."""
        with self._lock:
            if self.active and self._drawn:
                self._write('\r\x1b[K')
            self._drawn = self._text = ''

    def close(self) -> None:
        """Remove the status line and stop the clock's redraw."""
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join(timeout=2.0 * self.tick + 1.0)
        self.clear()

    def __enter__(self) -> 'Progress':
        """Return this progress line."""
        return self

    def __exit__(self, *exc: Any) -> None:
        """Remove the status line and stop the clock."""
        self.close()

    def _draw(self) -> None:
        # With the lock held.
        self._last_draw = time.monotonic()
        line = f'{self.prefix}[{self.elapsed:6.1f} s] {self._text}'
        width = shutil.get_terminal_size((100, 24)).columns - 1
        self._drawn = line[:max(width, 20)]
        self._write(f'\r\x1b[K{self._drawn}')

    def _run_ticker(self) -> None:
        while not self._stop.wait(self.tick):
            with self._lock:
                if self._text and time.monotonic() - self._last_draw >= self.tick:
                    self._draw()

    def _write(self, text: str) -> None:
        stream = self.stream
        stream.write(text)
        stream.flush()


def _isatty(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):   # closed or not a file
        return False
