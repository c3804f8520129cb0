"""A forked child that shares the figures with the parent (two cores: about half the time).

The child is forked as soon as the analysis is done (:func:`start_shared`: the parent writes its tables while the
child imports matplotlib and draws). It first writes the GIF, then takes figures from the back of the list while
the parent takes them from the front, until the two meet (one shared pair of indices under a lock), so neither core
idles whatever each figure costs. Only where forking is safe and pays: Linux, more than one CPU, no other Python
thread running. The child inherits the analysis and the linkages already built (no pickling, no linear algebra
after the fork) and reports through a pipe: which figure it starts, which file it has written, the GIF's progress,
and its outcome. If it fails, the parent writes what the child had taken itself, so an error is raised where it
happens, with its own type and traceback.
"""
from __future__ import annotations

import os
import sys
import threading
import warnings
from typing import Callable, Sequence

#: A job: ``write(progress)`` writes one file; ``progress(message, i, n)`` may be called while it runs.
Job = Callable[[Callable], object]


def can_fork() -> bool:
    import multiprocessing

    return (sys.platform.startswith("linux") and (os.cpu_count() or 1) > 1 and threading.active_count() == 1
            and "fork" in multiprocessing.get_all_start_methods())


class SharedJobs:
    """Jobs ``0 … n−1`` taken from the front by the parent and from the back by the child, each exactly once."""

    def __init__(self, n: int, ctx):
        self._ends = ctx.Array("i", [0, n], lock=True)

    def take_front(self) -> int | None:
        with self._ends.get_lock():
            head, tail = self._ends[0], self._ends[1]
            if head >= tail:
                return None
            self._ends[0] = head + 1
            return head

    def take_back(self) -> int | None:
        with self._ends.get_lock():
            head, tail = self._ends[0], self._ends[1]
            if head >= tail:
                return None
            self._ends[1] = tail - 1
            return tail - 1

    def first_of_back(self) -> int:
        """The first job the back end took (its jobs are this one to the last)."""
        with self._ends.get_lock():
            return self._ends[1]


class Background:
    """A forked child that runs ``first`` (if given) and then takes ``jobs`` from the back of ``shared``.

    Messages relayed by :meth:`relay` / :meth:`wait` to the caller's handlers: ``on_start(k)`` before job k,
    ``on_written(k)`` after it (k = −1 for ``first``), ``on_progress(message, i, n)`` from inside a job."""

    FIRST = -1

    def __init__(self, first: Job | None, jobs: Sequence[Job], shared: SharedJobs, ctx, after=None):
        self.first, self.jobs, self.shared = first, jobs, shared
        self.written: set[int] = set()
        self._outcome = None
        self._recv, send = ctx.Pipe(duplex=False)
        with warnings.catch_warnings():  # Python >= 3.12 warns about fork() beside native (BLAS) threads
            warnings.simplefilter("ignore", DeprecationWarning)
            self._proc = ctx.Process(target=_child, args=(first, jobs, shared, send, after), daemon=True)
            self._proc.start()
        send.close()  # the child holds the only write end: its exit ends the pipe

    def relay(self, on_start, on_written, on_progress, block: bool = False) -> None:
        """Pass on the child's messages; without ``block`` only those already sent, else until it is done."""
        while self._outcome is None and (block or self._recv.poll()):
            try:
                msg = self._recv.recv()
            except EOFError:
                self._outcome = "failed"
                break
            kind = msg[0]
            if kind == "start":
                on_start(msg[1])
            elif kind == "written":
                self.written.add(msg[1])
                on_written(msg[1])
            elif kind == "progress":
                on_progress(*msg[1:])
            else:
                self._outcome = kind

    def wait(self, on_start, on_written, on_progress) -> None:
        """Relay until the child is done; if it failed, run here what it had taken and not written."""
        try:
            self.relay(on_start, on_written, on_progress, block=True)
        finally:
            self._recv.close()
            self._proc.join()
        if self._outcome == "done" and self._proc.exitcode == 0:
            return
        if self.first is not None and self.FIRST not in self.written:
            self.first(on_progress)
            on_written(self.FIRST)
        for k in range(self.shared.first_of_back(), len(self.jobs)):
            if k not in self.written:
                on_start(k)
                self.jobs[k](on_progress)
                on_written(k)

    def cancel(self) -> None:
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join()
        self._recv.close()


class SharedRun:
    """Jobs started by :func:`start_shared`: :meth:`finish` runs this process's share and waits for the child's;
    :meth:`cancel` stops the child (a no-op once finished). The child starts at construction, so the caller may
    do other work (write its tables) while it runs. ``after()``, if given, runs in each process once its share is
    done (the child's before the parent's)."""

    def __init__(self, jobs: Sequence[Job], first: Job | None, parallel: bool, after=None):
        self.jobs, self.first, self.after = jobs, first, after
        self.child = self.shared = None
        if parallel:
            import multiprocessing

            ctx = multiprocessing.get_context("fork")
            self.shared = SharedJobs(len(jobs), ctx)
            self.child = Background(first, jobs, self.shared, ctx, after)

    def finish(self, *, on_start, on_written, on_progress) -> None:
        """Run every job not taken by the child, here; then wait for the child (and redo what it failed)."""
        if self.child is None:
            for k, job in enumerate(self.jobs):
                on_start(k)
                job(on_progress)
                on_written(k)
            if self.first is not None:
                self.first(on_progress)
                on_written(Background.FIRST)
        else:
            try:
                while (k := self.shared.take_front()) is not None:
                    self.child.relay(on_start, on_written, on_progress)
                    on_start(k)
                    self.jobs[k](on_progress)
                    on_written(k)
                self.child.wait(on_start, on_written, on_progress)
                self.child = None
            finally:
                self.cancel()  # a job failed here: stop the child
        if self.after is not None:
            self.after()

    def cancel(self) -> None:
        if self.child is not None:
            self.child.cancel()
            self.child = None


def start_shared(jobs: Sequence[Job], first: Job | None, *, parallel: bool, after=None) -> SharedRun:
    """Fork the child now (where ``parallel``) that runs ``first`` and then takes jobs from the back; the
    returned run's :meth:`~SharedRun.finish` does the rest here. ``after``: see :class:`SharedRun`."""
    return SharedRun(jobs, first, parallel, after)


def run_shared(jobs: Sequence[Job], first: Job | None, *, parallel: bool, on_start, on_written,
               on_progress, after=None) -> None:
    """Run every job once (and ``first``, last when alone): with a forked child where ``parallel``, else here."""
    start_shared(jobs, first, parallel=parallel, after=after).finish(on_start=on_start, on_written=on_written,
                                                                     on_progress=on_progress)


def _child(first, jobs, shared, send, after):
    def progress(message, i, n):
        send.send(("progress", message, i, n))

    try:
        if first is not None:
            first(progress)
            send.send(("written", Background.FIRST))
        while (k := shared.take_back()) is not None:
            send.send(("start", k))
            jobs[k](progress)
            send.send(("written", k))
        if after is not None:
            after()
        send.send(("done",))
    except BaseException:  # noqa: BLE001 - the parent redoes the work and raises it
        send.send(("failed",))
    finally:
        send.close()
