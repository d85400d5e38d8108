"""The A1 link's diagnostics verdict (rbd_a1_driver.link_health), without ROS."""

import pytest

from rbd_a1_driver.link_health import ERROR, OK, WARN, LinkSnapshot, RateMeter, link_values, link_verdict

HEALTHY = dict(fresh=True, remote="released")


def test_a_healthy_link_is_ok():
    assert link_verdict(LinkSnapshot(**HEALTHY)) == (OK, "ok")


@pytest.mark.parametrize(
    "fields, level, words",
    [
        (dict(fresh=False, wrong_recent=7, last_size=300, known_sizes="265, 1025"), ERROR, "7 packets of 300 B"),
        (dict(fresh=False), ERROR, "no HighState"),
        (dict(estop_lost=True), ERROR, "e-stop signal lost"),
        (dict(remote="engaged", remote_combo="L2+B"), WARN, "remote e-stop engaged (L2+B)"),
        (dict(estop=True), WARN, "e-stop engaged"),
        (dict(estop_missing=True), WARN, "no e-stop signal yet"),
    ],
)
def test_each_cause_gives_its_level_and_says_so(fields, level, words):
    got_level, message = link_verdict(LinkSnapshot(**dict(HEALTHY, **fields)))
    assert got_level == level and words in message
    if level != OK:
        assert "zero velocity" in message


def test_the_first_cause_wins():
    # no HighState beats a held e-stop: the A1 not being heard is the worse news
    both = LinkSnapshot(fresh=False, estop=True, estop_lost=True, remote="engaged")
    assert link_verdict(both) == (ERROR, "no HighState: sending zero velocity")
    assert link_verdict(LinkSnapshot(fresh=True, estop=True, estop_lost=True))[1].startswith("e-stop signal lost")
    forced = LinkSnapshot(fresh=False, wrong_recent=1, last_size=265, known_sizes="1025", forced="v3.3.4")
    assert "(~sdk_layout forces v3.3.4)" in link_verdict(forced)[1]


def test_values_carry_the_contract_keys_as_text():
    values = dict(link_values(LinkSnapshot(fresh=True, state_rate=499.96, cmd_rate=250.0, last_size=1025, armed=True)))
    assert values["high_state_rate"] == "500.0" and values["high_cmd_rate"] == "250.0"
    assert values["high_state_size"] == "1025" and values["estop_gate_armed"] == "true"
    assert values["sdk_layout"] == "unknown"  # none detected yet
    assert all(isinstance(v, str) for v in values.values())
    assert list(values)[:3] == ["lcm_url", "sdk_layout", "sdk_layout_source"]


def test_rate_meter_counts_between_reads():
    meter = RateMeter(10.0)
    assert meter.read(11.0, 500, 250, 0) == pytest.approx((500.0, 250.0, 0))
    assert meter.read(13.0, 1500, 750, 4) == pytest.approx((500.0, 250.0, 4))
    assert meter.read(13.5, 1500, 750, 4) == pytest.approx((0.0, 0.0, 0))  # silence, no new bad packets


def test_unknown_snapshot_field_is_an_error():
    with pytest.raises(ValueError, match="fresch"):
        LinkSnapshot(fresch=True)
