"""The GIF written by a forked child process while the parent draws the PNGs (two cores: about half the time).

Only where forking is safe and pays: Linux, more than one CPU, no other Python thread running. The child
inherits the analysis and the linkages already built (no pickling, no linear algebra after the fork), sends its
progress and its outcome through a pipe, and exits; :meth:`BackgroundGif.wait` relays the progress to the
caller. If the child fails, the parent writes the GIF itself, so an error is raised where it happens, with its
own type and traceback.
"""
from __future__ import annotations

import os
import sys
import threading
import warnings
from pathlib import Path


def can_fork() -> bool:
    import multiprocessing

    return (sys.platform.startswith("linux") and (os.cpu_count() or 1) > 1 and threading.active_count() == 1
            and "fork" in multiprocessing.get_all_start_methods())


class BackgroundGif:
    """``machine_gif(analysis, path, links=links)`` in a forked child; :meth:`wait` for it."""

    def __init__(self, analysis, path, links):
        import multiprocessing

        self.analysis, self.path, self.links = analysis, Path(path), links
        ctx = multiprocessing.get_context("fork")
        self._recv, send = ctx.Pipe(duplex=False)
        with warnings.catch_warnings():  # Python >= 3.12 warns about fork() beside native (BLAS) threads
            warnings.simplefilter("ignore", DeprecationWarning)
            self._proc = ctx.Process(target=_child, args=(analysis, self.path, links, send), daemon=True)
            self._proc.start()
        send.close()  # the child holds the only write end: its exit ends the pipe

    def wait(self, progress=None) -> Path:
        """Relay the child's progress to ``progress(message, frame, frames)`` until it is done; the GIF's path."""
        from .animation import machine_gif

        outcome = None
        try:
            while True:
                try:
                    msg = self._recv.recv()
                except EOFError:
                    break
                if msg[0] == "progress":
                    if progress:
                        progress(*msg[1:])
                else:
                    outcome = msg[0]
                    break
        finally:
            self._recv.close()
            self._proc.join()
        if outcome != "done" or self._proc.exitcode != 0:  # write it here: a failure is raised where it happens
            return machine_gif(self.analysis, self.path, progress, links=self.links)
        return self.path

    def cancel(self) -> None:
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join()
        self._recv.close()


def _child(analysis, path, links, send):
    from .animation import machine_gif

    try:
        machine_gif(analysis, path, lambda message, i, n: send.send(("progress", message, i, n)), links=links)
        send.send(("done",))
    except BaseException:  # noqa: BLE001 - the parent redoes the work and raises it
        send.send(("failed",))
    finally:
        send.close()
