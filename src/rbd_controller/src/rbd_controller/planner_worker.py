"""Planning off the controller's tick: one planner job at a time in a worker thread. ROS-free.

The tick hands the worker a job (a function over a scene snapshot taken under the controller's
lock) with a key naming what it was planned for, then polls: :meth:`PlannerWorker.poll` returns
the :class:`Outcome` once the job finished, never blocks. A job that raises is an outcome with
``error`` set (the caller gives up with that reason and logs it): the node never dies of a planner
bug. A result whose key no longer matches what the caller is doing (the scene changed, the state
left AVOIDING, an e-stop) is dropped by :meth:`PlannerWorker.cancel`, or by the caller comparing
``Outcome.key``; a job cannot be interrupted, so the planner must honour its own wall-clock budget,
but a cancelled job's result is never delivered. ``inline=True`` runs the job inside ``submit``
(deterministic tests with a simulated clock).
"""

import threading
import time
import traceback
from typing import Any, Callable, Optional


class Outcome:
    """A finished planner job.

    Attributes:
        key: what the job was submitted for (compared by the caller to drop stale results).
        result: the job's return value (None when it raised).
        error: "" or the exception's type and message.
        trace: the formatted traceback when it raised (for the log).
        seconds: wall-clock time the job took [s].
    """

    def __init__(self, key: Any, result: Any, error: str, trace: str, seconds: float) -> None:
        self.key = key
        self.result = result
        self.error = error
        self.trace = trace
        self.seconds = seconds

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Outcome(key=%r, %s in %.2f s)" % (self.key, self.error or "ok", self.seconds)


class PlannerWorker:
    """Runs one planner job at a time off the caller's thread.

    Args:
        inline: run jobs synchronously inside :meth:`submit` (tests).
        clock: wall clock for the job's duration [s].
    """

    def __init__(self, inline: bool = False, clock: Callable[[], float] = time.monotonic) -> None:
        self.inline = bool(inline)
        self.clock = clock
        self._lock = threading.Lock()
        self._job = 0  # id of the job whose result is wanted (0: none)
        self._running = 0  # id of the job running in a thread (0: none)
        self._done = None  # type: Optional[Outcome]
        self._next = 0

    @property
    def busy(self) -> bool:
        """A submitted job has not finished (or was cancelled but still runs)."""
        with self._lock:
            return self._running != 0

    @property
    def pending(self) -> bool:
        """A submitted, not cancelled job has no outcome polled yet."""
        with self._lock:
            return self._job != 0

    def submit(self, key: Any, job: Callable[[], Any]) -> bool:
        """Start job() for key; False (nothing started) while an earlier job still runs.

        A cancelled job that still runs blocks a new one: only one planner runs at a time (the
        machine has two cores and the planner's caches are not shared between threads).
        """
        with self._lock:
            if self._running:
                return False
            self._next += 1
            job_id = self._next
            self._job = job_id
            self._done = None
            self._running = job_id
        if self.inline:
            self._run(job_id, key, job)
            return True
        thread = threading.Thread(target=self._run, args=(job_id, key, job), name="rbd_planner", daemon=True)
        try:
            thread.start()
        except RuntimeError as err:  # no thread can be started: report it as the job's failure
            self._finish(job_id, Outcome(key, None, "RuntimeError: %s" % err, "", 0.0))
        return True

    def _run(self, job_id: int, key: Any, job: Callable[[], Any]) -> None:
        t0 = self.clock()
        try:
            outcome = Outcome(key, job(), "", "", self.clock() - t0)
        except Exception as err:  # noqa: BLE001 - any planner bug becomes a reason, never a dead node
            outcome = Outcome(key, None, "%s: %s" % (type(err).__name__, err), traceback.format_exc(),
                              self.clock() - t0)
        self._finish(job_id, outcome)

    def _finish(self, job_id: int, outcome: Outcome) -> None:
        with self._lock:
            if self._running == job_id:
                self._running = 0
            if self._job == job_id:
                self._done = outcome

    def poll(self) -> Optional[Outcome]:
        """The wanted job's outcome once, when it finished; else None."""
        with self._lock:
            done, self._done = self._done, None
            if done is not None:
                self._job = 0
            return done

    def cancel(self) -> None:
        """Drop the wanted job: its outcome (now or later) is never returned."""
        with self._lock:
            self._job = 0
            self._done = None
