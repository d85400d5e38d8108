"""Late clouds of the simulated OS1 (issue 27): delays, the seeded late fraction, publication order."""

import math

import pytest

from rbd_sim.cloud_delay import CloudDelay


def test_default_holds_nothing_back():
    d = CloudDelay()
    assert not d.enabled
    assert d.push(5.0, "a") == 5.0
    assert d.pop_due(5.0) == ["a"] and len(d) == 0


def test_fixed_delay_publishes_each_cloud_that_long_after_its_capture():
    d = CloudDelay(delay=0.15)
    assert d.enabled
    dues = [d.push(10.0 + 0.1 * i, i) for i in range(3)]
    assert dues == pytest.approx([10.15, 10.25, 10.35])
    assert d.next_due() == pytest.approx(10.15)
    assert d.pop_due(10.149) == []
    assert d.pop_due(10.15) == [0]
    assert d.pop_due(10.5) == [1, 2]
    assert d.next_due() is None


def test_late_fraction_is_seeded_and_about_right():
    def draws(seed):
        d = CloudDelay(delay=0.15, late_fraction=0.2, late_delay=0.3, seed=seed)
        return [d.next_delay() for _ in range(5000)]

    a = draws(7)
    assert set(a) == {0.15, 0.3}
    assert abs(a.count(0.3) / len(a) - 0.2) < 0.02
    assert draws(7) == a  # same seed, same late clouds
    assert draws(8) != a
    assert set(draws(1)[:50]) == {0.15, 0.3}  # mixed from the start, not in blocks
    never = CloudDelay(delay=0.15, late_fraction=0.0, late_delay=0.3)
    always = CloudDelay(delay=0.15, late_fraction=1.0, late_delay=0.3)
    assert {never.next_delay() for _ in range(200)} == {0.15}
    assert {always.next_delay() for _ in range(200)} == {0.3}


def test_a_late_cloud_comes_out_after_a_younger_one():
    d = CloudDelay(delay=0.15, late_fraction=0.2, late_delay=0.3, seed=3)
    captured = [(0.1 * i, d.push(0.1 * i, i)) for i in range(200)]
    out = []
    for k in range(2100):  # a 10 ms publication loop over the 20 s captured
        out.extend(d.pop_due(0.01 * k))
    assert sorted(out) == list(range(200))  # every cloud once
    dues = dict((i, due) for i, (_, due) in enumerate(captured))
    assert [dues[i] for i in out] == sorted(dues[i] for i in out)  # published in due order
    swapped = [(a, b) for a, b in zip(out, out[1:]) if a > b]
    assert swapped, "no late cloud overtaken by a younger one"
    for older_after, younger in ((b, a) for a, b in swapped):
        assert dues[older_after] - captured[older_after][0] == pytest.approx(0.3)
        assert dues[younger] - captured[younger][0] == pytest.approx(0.15)


@pytest.mark.parametrize(
    "kw",
    [{"delay": -0.1}, {"delay": math.nan}, {"late_delay": math.inf}, {"late_fraction": 1.5},
     {"late_fraction": -0.1}, {"delay": True}, {"delay": "0.1"}],
)
def test_bad_values_are_refused(kw):
    with pytest.raises(ValueError):
        CloudDelay(**kw)
