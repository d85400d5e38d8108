"""Waiting on conditions instead of sleeping: ``wait_for`` and the "stays unchanged" check."""

import time
from typing import Any, Callable, Optional, Tuple, Type


class WaitTimeoutError(AssertionError):
    """A condition a test waited for did not come true in time (a test failure, not an error)."""


def wait_for(
    predicate: Callable[[], Any],
    timeout: float = 10.0,
    step: float = 0.05,
    what: Optional[str] = None,
    abort: Optional[Callable[[], bool]] = None,
    ignore: Tuple[Type[BaseException], ...] = (),
) -> Any:
    """Poll ``predicate`` until it returns something true or ``timeout`` seconds pass.

    The predicate is called at least once, and once more at the deadline.

    Args:
        predicate: the condition; its (true) value is returned.
        timeout: seconds to wait at most.
        step: pause between two calls [s].
        what: a description of the condition; when given, a timeout raises ``WaitTimeoutError``
            with it instead of returning the false value.
        abort: stop waiting early when this returns true (e.g. ``rospy.is_shutdown``).
        ignore: exception types that count as "not yet" (e.g. a service not up yet).

    Returns:
        The predicate's first true value; on timeout or abort (without ``what``) its last value
        (None when its last call raised one of ``ignore``).

    Raises:
        WaitTimeoutError: on timeout or abort when ``what`` is given.

    Example:
        >>> wait_for(lambda: node.state == "IDLE", 5.0, what="state IDLE")  # doctest: +SKIP
        >>> assert wait_for(lambda: msgs, 2.0)  # doctest: +SKIP
    """
    deadline = time.monotonic() + timeout
    value = None
    while True:
        try:
            value = predicate()
        except ignore:
            value = None
        if value:
            return value
        now = time.monotonic()
        if now >= deadline or (abort is not None and abort()):
            break
        time.sleep(max(0.0, min(step, deadline - now)))
    if what is not None:
        raise WaitTimeoutError("timed out after %.1f s waiting for %s (last value: %r)" % (timeout, what, value))
    return value


def wait_quiet(
    read: Callable[[], Any],
    quiet: float,
    timeout: float = 10.0,
    step: float = 0.05,
    what: Optional[str] = None,
    same: Optional[Callable[[Any, Any], bool]] = None,
) -> Any:
    """Wait until ``read()`` has kept one value for ``quiet`` seconds (a stream drained, a robot settled).

    Not a "nothing happened" check: it waits for a quiet period, however long the noise lasts
    (up to ``timeout``); a check that an input changes nothing is ``stays_unchanged``.

    Args:
        read: the observed value (a message count, a rounded pose...); compared with ``!=``.
        quiet: seconds the value must stay the same.
        timeout: seconds to wait at most.
        step: polling period [s].
        what: a description; when given, a timeout raises ``WaitTimeoutError`` with it.
        same: ``same(first, now)`` true when ``now`` still counts as the quiet period's first
            value (a tolerance for a pose); default ``==``. A slow drift adds up and restarts it.

    Returns:
        The last value read (quiet), or None on timeout without ``what``.

    Raises:
        WaitTimeoutError: no quiet period within ``timeout`` when ``what`` is given.

    Example:
        >>> n = wait_quiet(inbox.count, 0.45, what="the warm-up messages drained")  # doctest: +SKIP
    """
    first = {"value": read(), "since": time.monotonic()}
    last = {"value": first["value"]}

    def settled() -> bool:
        value, now = read(), time.monotonic()
        last["value"] = value
        if not (same(first["value"], value) if same is not None else value == first["value"]):
            first["value"], first["since"] = value, now
            return False
        return now - first["since"] >= quiet

    if not wait_for(settled, timeout, step, what=None if what is None else "%s (quiet for %.2f s)" % (what, quiet)):
        return None
    return last["value"]


def stays_unchanged(
    read: Callable[[], Any],
    arrived: Callable[[], Any],
    hold: float,
    send: Optional[Callable[[], Any]] = None,
    timeout: float = 10.0,
    step: float = 0.02,
    what: str = "the observed value",
    proof: str = "the input's arrival",
) -> Any:
    """Assert that an input changes nothing, after first proving that the input arrived.

    A "nothing happened" check that only sleeps passes for the wrong reason when the input
    never reached the system (a wrong topic name, a dead connection). This check:

    1. reads the baseline ``read()``, then calls ``send()`` (when given);
    2. waits up to ``timeout`` for ``arrived()``: the proof that *this* input reached the
       system under test (its log line, a counter that moved past its value before the send,
       an echo of this input's id, a follow-up message on the same connection);
    3. keeps checking ``read() == baseline`` for ``hold`` more seconds.

    ``read()`` is compared with the baseline at every step of 2 and 3.

    Args:
        read: what must not change (a state, a list of motion samples since the send...).
        arrived: true once the input is proven to have arrived.
        hold: seconds ``read()`` must keep its value after the proof.
        send: delivers the input (called after the baseline is read); None when the caller
            has sent it already.
        timeout: seconds to wait for the proof.
        step: polling period [s].
        what: name of the observed value, for the failure message.
        proof: name of the proof, for the failure message.

    Returns:
        The baseline value.

    Raises:
        AssertionError: the value changed, or the proof never came (then the check proves
            nothing and fails).

    Example:
        >>> n = node.rejected  # doctest: +SKIP
        >>> stays_unchanged(lambda: node.state, lambda: node.rejected > n, hold=1.0,
        ...                 send=lambda: pub.publish(bad), what="state", proof="rejected counter")
    """
    baseline = read()
    if send is not None:
        send()
    start = time.monotonic()

    def check(phase: str) -> None:
        value = read()
        if value != baseline:
            raise AssertionError("%s changed %s, %.2f s after the input: %r -> %r"
                                 % (what, phase, time.monotonic() - start, baseline, value))

    def proven() -> Any:
        check("before the input was proven to arrive")
        return arrived()

    if not wait_for(proven, timeout, step):
        raise AssertionError(
            "no proof of %s within %.1f s: an unchanged %s would prove nothing" % (proof, timeout, what))
    end = time.monotonic() + hold

    def held() -> bool:
        check("while held")
        return time.monotonic() >= end

    wait_for(held, hold, step)  # its last call comes at the deadline, after ``end``
    return baseline
