"""A status line on stderr for command-line work that takes more than about two seconds.

`with progress("simulating FILE"):` prints nothing when the work ends within `delay` seconds. After
that, on a terminal, one line rewritten in place: the task, the elapsed time and, the first time a
stack shape runs, that JAX is compiling (compiled solvers are cached in the cache folder and reused by
later runs); the line is erased at the end. Off a terminal (a pipe, a log file, CI) nothing is printed
unless `HERTZ_CHAIN_PROGRESS=1`, which prints one line when the wait starts and one when it ends.
`HERTZ_CHAIN_PROGRESS=0` silences it everywhere. Plain threads rather than tqdm or rich: the work is
one opaque call (a compiled solve), so there is no count to draw a bar of, only the elapsed time.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time

__all__ = ["progress"]

DELAY_S = 2.0


def _mode(stream) -> str | None:
    flag = os.environ.get("HERTZ_CHAIN_PROGRESS", "").strip()
    if flag == "0":
        return None
    if flag == "1":
        return "lines" if not stream.isatty() else "tty"
    return "tty" if stream.isatty() else None


@contextlib.contextmanager
def progress(task: str, delay: float | None = None, stream=None):
    """Show `task` and the elapsed time on `stream` (default stderr) while the block runs longer than
    `delay` seconds (default 2, or `HERTZ_CHAIN_PROGRESS_DELAY`)."""
    stream = stream or sys.stderr
    mode = _mode(stream)
    if mode is None:
        yield
        return
    if delay is None:
        try:  # a malformed setting falls back to the default: a status line must never stop a run
            delay = float(os.environ.get("HERTZ_CHAIN_PROGRESS_DELAY", DELAY_S))
        except ValueError:
            delay = DELAY_S
        if not delay >= 0:
            delay = DELAY_S
    t0 = time.perf_counter()
    done = threading.Event()
    shown = threading.Event()
    note = "the first run of a stack shape compiles its solver: later runs reuse the cache"

    def run():
        if done.wait(delay):
            return
        shown.set()
        if mode == "lines":
            print(f"hertz-chain: {task} ... ({note})", file=stream, flush=True)
            return
        while not done.wait(0.25):
            el = time.perf_counter() - t0
            print(f"\rhertz-chain: {task} ... {el:4.0f} s ({note})", end="", file=stream, flush=True)

    th = threading.Thread(target=run, daemon=True)
    th.start()
    try:
        yield
    finally:
        done.set()
        th.join()
        if shown.is_set():
            el = time.perf_counter() - t0
            if mode == "lines":
                print(f"hertz-chain: {task}: done in {el:.1f} s", file=stream, flush=True)
            else:
                print("\r\033[K", end="", file=stream, flush=True)
