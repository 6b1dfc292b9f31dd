"""Work split over forked worker processes: how many, and running them.

Drawing a video frame is Python and Pillow, which hold the GIL: in one process the drawing
is one core's work however many the machine has, and on a long imitation it is the critical
path. :func:`visprim.sim.video.write_video_parts` therefore splits a video into consecutive
parts, each drawn and encoded by its own process (the first by the parent), and joins the
parts. The other processes are forks of the parent, so each inherits the drawer the parent
built and nothing is pickled.

Workers are used only where the parent can fork them safely and gains from them: Linux, at
least two usable cores and enough frames (:func:`draw_workers`). A fork holds only the
thread that made it, so a job must not use a thread pool the parent started (Rayon's in
visprim's kernels, a BLAS's for large products): the video's parts draw with Pillow and
encode with the GIF encoder or an ffmpeg process, which use none. A worker that fails raises
its error (type and message) in the parent; an interrupt or an error in the parent stops the
workers: they ignore SIGINT (the parent decides), and SIGTERM makes them clean up (stop
their encoder) and exit. A worker's parts are written in a folder the parent removes at
the end, so an encoder a crashed worker left running has nowhere to write.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import traceback
from collections.abc import Callable, Iterator, Sequence
from typing import Any

#: The most processes a video is drawn by (the parent and forks of it).
MAX_DRAW_WORKERS = 4

#: Fewer frames than this per worker are drawn in one process: forking costs more than it
#: saves.
MIN_FRAMES_PER_WORKER = 100


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system tells it)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def draw_workers(n_frames: int, workers: int | None = None, cores_per_part: int = 1) -> int:
    """How many processes share ``n_frames`` frames: ``workers`` if given (a whole number
    ≥ 0), else one per ``cores_per_part`` usable cores, up to :data:`MAX_DRAW_WORKERS`, fewer
    so that each has :data:`MIN_FRAMES_PER_WORKER` frames. 0 (draw in one process) where fork
    is unavailable or unsafe (only Linux forks here) or fewer than 2 would work.

    A part keeps about one core busy drawing; an MP4 part keeps a second busy with its
    encoder (x264 in one thread), so MP4 parts ask for ``cores_per_part=2``: on 2 cores an
    MP4 is then drawn in one process, which already keeps both cores busy (docs/imitation.rst
    has the measurements)."""
    if cores_per_part < 1:
        raise ValueError(f"cores_per_part must be ≥ 1, got {cores_per_part}")
    if workers is not None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
            raise ValueError(f"workers must be a whole number ≥ 0, got {workers!r}")
        n = min(workers, max(0, n_frames))
    else:
        n = min(
            usable_cores() // cores_per_part, MAX_DRAW_WORKERS, n_frames // MIN_FRAMES_PER_WORKER
        )
    if not sys.platform.startswith("linux") or n < 2:
        return 0
    return n


def split(n: int, parts: int) -> list[range]:
    """``range(n)`` cut into ``parts`` consecutive ranges of sizes differing by at most 1."""
    if parts < 1:
        raise ValueError(f"parts must be ≥ 1, got {parts}")
    edges = [n * k // parts for k in range(parts + 1)]
    return [range(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)]


#: Seconds a stopped child may take to clean up (end its encoder) before it is killed.
STOP_S = 10.0


class WorkerError(RuntimeError):
    """A worker process failed (its error type and message, or how it ended)."""


class _Stopped(BaseException):
    """SIGTERM in a child: raised so that its ``finally`` clauses (an encoder's) run."""


class _Deferral:
    """Whether a worker's stop waits (:func:`stop_deferred`), and whether one came."""

    depth = 0
    pending = False


def _stop(signum: int, frame: Any) -> None:
    if _Deferral.depth:
        _Deferral.pending = True
        return
    raise _Stopped


@contextlib.contextmanager
def stop_deferred() -> Iterator[None]:
    """A block a worker's stop (SIGTERM) does not interrupt: it takes effect when the block
    ends. Used around starting a process whose handle the caller must hold before a stop
    can reach it (an encoder, which would otherwise outlive its owner and write its file
    after the cleanup). Outside a worker it changes nothing."""
    _Deferral.depth += 1
    try:
        yield
    finally:
        _Deferral.depth -= 1
        if not _Deferral.depth and _Deferral.pending:
            _Deferral.pending = False
            raise _Stopped


def _child(job: Callable[[], None], errors: Any) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop)
    try:
        job()
    except _Stopped:
        raise SystemExit(128 + signal.SIGTERM) from None
    except BaseException as exc:  # reported to the parent, which raises it
        errors.send(f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}")
        raise SystemExit(1) from None


def run_forked(jobs: Sequence[Callable[[], None]], what: str = "a worker process") -> None:
    """Run the jobs at once: the first in this process, each other in a forked child, and
    wait for them all.

    A child that fails raises :class:`WorkerError` here with its error (its traceback kept
    as the exception's note) once this process's own job is done; an exception here (in
    the own job, or an interrupt) stops the children before it propagates."""
    import multiprocessing

    if not jobs:
        return
    ctx = multiprocessing.get_context("fork")
    pipes = [ctx.Pipe(duplex=False) for _ in jobs[1:]]
    procs = [
        ctx.Process(target=_child, args=(job, pipe[1]), name=f"visprim-worker-{k}", daemon=True)
        for k, (job, pipe) in enumerate(zip(jobs[1:], pipes, strict=True), start=1)
    ]
    # Anything buffered would be written again by each child as it exits.
    sys.stdout.flush()
    sys.stderr.flush()
    started: list[Any] = []
    try:
        for p in procs:
            p.start()
            started.append(p)
        jobs[0]()
        for p, (receive, _) in zip(procs, pipes, strict=True):
            p.join()
            if p.exitcode != 0:
                message = receive.recv() if receive.poll() else None
                if message is None:
                    raise WorkerError(f"{what} ended with exit code {p.exitcode}")
                head, _, trace = message.partition("\n")
                error = WorkerError(f"{what} failed: {head}")
                error.add_note(trace.rstrip())
                raise error
    finally:
        for p in started:
            if p.is_alive():
                p.terminate()
        for p in started:
            p.join(STOP_S)
            if p.is_alive():
                p.kill()
                p.join()
        for a, b in pipes:
            a.close()
            b.close()
