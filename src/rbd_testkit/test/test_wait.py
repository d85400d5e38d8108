"""wait_for and stays_unchanged: what they return, when they fail, and that a missing proof fails."""

import time

import pytest

from rbd_testkit import WaitTimeoutError, stays_unchanged, wait_for, wait_quiet


class Counter:
    def __init__(self, true_from):
        self.calls = 0
        self.true_from = true_from

    def __call__(self):
        self.calls += 1
        return self.calls if self.calls >= self.true_from else 0


def test_wait_for_returns_the_first_true_value():
    pred = Counter(3)
    assert wait_for(pred, 5.0, step=0.001) == 3
    assert pred.calls == 3


def test_wait_for_returns_the_false_value_on_timeout_and_calls_once_more_at_the_deadline():
    calls = []
    t0 = time.monotonic()
    assert wait_for(lambda: calls.append(time.monotonic()) or [], 0.2, step=0.05) == []
    assert time.monotonic() - t0 >= 0.2
    assert calls[-1] - t0 >= 0.2
    assert len(calls) >= 2


def test_wait_for_with_what_raises_a_test_failure_naming_it():
    with pytest.raises(WaitTimeoutError, match="state IDLE") as info:
        wait_for(lambda: None, 0.05, what="state IDLE")
    assert isinstance(info.value, AssertionError)


def test_wait_for_abort_ends_early():
    t0 = time.monotonic()
    assert wait_for(lambda: False, 30.0, step=0.01, abort=lambda: True) is False
    assert time.monotonic() - t0 < 10.0


def test_wait_for_ignores_only_the_listed_exceptions():
    state = {"n": 0}

    def flaky():
        state["n"] += 1
        if state["n"] < 3:
            raise ConnectionError("not yet")
        return "up"

    assert wait_for(flaky, 5.0, step=0.001, ignore=(ConnectionError,)) == "up"
    with pytest.raises(KeyError):
        wait_for(lambda: {}["x"], 1.0, ignore=(ConnectionError,))


def test_stays_unchanged_passes_after_the_proof_and_the_hold():
    box = {"arrived": False}
    t0 = time.monotonic()
    baseline = stays_unchanged(lambda: "IDLE", lambda: box["arrived"], hold=0.2,
                               send=lambda: box.update(arrived=True))
    assert baseline == "IDLE"
    assert time.monotonic() - t0 >= 0.2


def test_stays_unchanged_fails_without_proof_even_when_nothing_changed():
    # The point of the helper: an input that never arrived must not pass as "ignored".
    with pytest.raises(AssertionError, match="no proof of the echo"):
        stays_unchanged(lambda: "IDLE", lambda: False, hold=0.0, timeout=0.1, proof="the echo")


def test_stays_unchanged_fails_when_the_value_changes_during_the_hold():
    start = time.monotonic()
    with pytest.raises(AssertionError, match="while held.*'IDLE' -> 'MOVING'"):
        stays_unchanged(lambda: "IDLE" if time.monotonic() - start < 0.1 else "MOVING", lambda: True, hold=2.0,
                        what="state")


def test_stays_unchanged_fails_when_the_value_changes_before_the_proof():
    values = iter(["IDLE", "MOVING"])
    with pytest.raises(AssertionError, match="before the input was proven"):
        stays_unchanged(lambda: next(values), lambda: False, hold=0.0, timeout=5.0)


def test_stays_unchanged_reads_the_baseline_before_sending():
    state = {"v": 0}
    with pytest.raises(AssertionError, match="0 -> 1"):
        stays_unchanged(lambda: state["v"], lambda: True, hold=0.0, send=lambda: state.update(v=1))


def test_wait_quiet_returns_the_value_once_it_kept_still():
    t0 = time.monotonic()

    def count():  # grows for 0.3 s, then stays at its last value
        return min(int((time.monotonic() - t0) / 0.05), 6)

    assert wait_quiet(count, 0.2, 5.0, step=0.01) == 6
    assert time.monotonic() - t0 >= 0.3 + 0.2 - 0.02


def test_wait_quiet_times_out_on_a_value_that_never_settles():
    t0 = time.monotonic()
    assert wait_quiet(time.monotonic, 0.1, 0.3, step=0.01) is None
    assert time.monotonic() - t0 >= 0.3
    with pytest.raises(WaitTimeoutError, match="the ticks drained"):
        wait_quiet(time.monotonic, 0.1, 0.1, step=0.01, what="the ticks drained")


def test_wait_quiet_with_a_tolerance_restarts_on_a_slow_drift():
    t0 = time.monotonic()

    def drift():  # 1 mm every 10 ms for 0.3 s (never 5 mm in one step), then still at 30 mm
        return min(time.monotonic() - t0, 0.3) * 0.1

    value = wait_quiet(drift, 0.2, 5.0, step=0.01, same=lambda a, b: abs(a - b) < 0.005)
    assert value == pytest.approx(0.03)  # the drift added up past the tolerance: not settled at its start
    assert time.monotonic() - t0 >= 0.3 + 0.2 - 0.05
