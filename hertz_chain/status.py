"""The outcome of a run, defined once: `Status`.

Every entry point reports one of these (the simulator's `Solution.status`, a batch's `status_code`, the
analysis `Report`, the JSON, the NetCDF and the command line's exit code). Plain Python, no JAX: the
command line reads it before anything heavy is imported.

| status | meaning | headline results | exit code |
|---|---|---|---|
| `complete` | the first cascade ended (every contact open, no neighbours approach, mass 1 moves up from the ground or rests on it); for a chain held by an end force (`Stack.end_force`), which never flies apart, the run reached `t_max` | valid | 0 |
| `complete with rebounds` | as `complete`; the run went on (`until="t_max"`) and saw later impacts, reported on their own | valid | 0 |
| `incomplete: t_max reached` | `t_max` came before the cascade ended | partial | 3 |
| `incomplete: max_steps reached` | the step budget ran out before the cascade ended | partial | 3 |
| `no contact` | no body ever touched another or the ground before `t_max` | none | 4 |
| `failed` | the solver produced a non-finite state | none | 5 |

Exit code 2 is kept for bad input (a `HertzChainError` before anything runs).
"""

from __future__ import annotations

import enum

__all__ = ["Status", "EXIT_BAD_INPUT"]

#: Exit code of the command line for bad input (a file, flag or value it refuses).
EXIT_BAD_INPUT = 2


class Status(enum.IntEnum):
    """How a run ended. The integer is the code carried in batched results (`status_code`)."""

    COMPLETE = 0
    COMPLETE_WITH_REBOUNDS = 1
    INCOMPLETE_T_MAX = 2
    INCOMPLETE_MAX_STEPS = 3
    NO_CONTACT = 4
    FAILED = 5

    @property
    def text(self) -> str:
        """The status as printed in tables and JSON."""
        return _TEXT[self]

    @property
    def ok(self) -> bool:
        """The headline results (launch velocities, gains) are valid."""
        return self in (Status.COMPLETE, Status.COMPLETE_WITH_REBOUNDS)

    @property
    def incomplete(self) -> bool:
        return self in (Status.INCOMPLETE_T_MAX, Status.INCOMPLETE_MAX_STEPS)

    @property
    def exit_code(self) -> int:
        """The command line's exit status for a run that ended so (0 only when `ok`)."""
        return 0 if self.ok else (3 if self.incomplete else (4 if self is Status.NO_CONTACT else 5))

    def hint(self, max_steps: int | None = None) -> str:
        """One sentence: what to change so that the run completes ('' when it did)."""
        if self is Status.INCOMPLETE_T_MAX:
            # a review: "leave it unset" was offered where the default had stopped the run (a struck chain
            # without ground whose lower masses collide long after the top's launch)
            return ("the cascade had not ended at t_max: raise solver.t_max (the default, when unset, may stop a "
                    "chain without ground, or a gapped stack without gravity, whose lower masses go on colliding), "
                    "or set solver.until = \"launch\" to stop once the top mass's launch is final (which can "
                    "also come after t_max)")
        if self is Status.INCOMPLETE_MAX_STEPS:
            now = "" if max_steps is None else f" (now {max_steps})"
            return (f"the step budget ran out before the run's end (the cascade's end, or t_max with "
                    f"until = \"t_max\"): raise solver.max_steps{now} or loosen solver.rtol/atol")
        if self is Status.NO_CONTACT:
            return ("nothing touched before t_max: check the initial velocities and gaps (something must move "
                    "towards the ground or a neighbour, or gravity must bring it there)")
        if self is Status.FAILED:
            return ("the state became non-finite: check masses and contact parameters, and try tighter "
                    "tolerances or a smaller Tolerances.max_step")
        return ""

    def error(self, what: str, need: str):
        """The `SolverError` of a run of `what` that ended so: its status, what to change and `need` (why
        the caller cannot go on, e.g. "a fit needs complete runs"); the status is kept on the error
        (`.status`) for the command line's exit code."""
        from .errors import SolverError

        err = SolverError(f"{what} ended {self.text}: {self.hint()}; {need}")
        err.status = self
        return err

    def __str__(self) -> str:
        return self.text

    @classmethod
    def from_text(cls, text: str) -> Status:
        """The status whose `text` is `text`."""
        for s in cls:
            if s.text == text:
                return s
        raise ValueError(f"status = {text!r} is invalid: one of {[s.text for s in cls]}")


_TEXT = {
    Status.COMPLETE: "complete",
    Status.COMPLETE_WITH_REBOUNDS: "complete with rebounds",
    Status.INCOMPLETE_T_MAX: "incomplete: t_max reached",
    Status.INCOMPLETE_MAX_STEPS: "incomplete: max_steps reached",
    Status.NO_CONTACT: "no contact",
    Status.FAILED: "failed",
}
