#!/usr/bin/env python3
"""A plain rospy node that stands on the ROS side of bridge tests (ground truth, no bridge code).

Usage: ``ros_probe.py [--sub TOPIC:TYPE:QUEUE]... [--pub TOPIC:TYPE:JSON]... [--defer SECONDS] [__name:=NAME]``

- every ``--sub`` is an ordinary ``rospy.Subscriber`` (queue_size QUEUE, 0 = rospy's None)
  whose callback only appends the message (as cheap as a subscriber can be); with
  ``--defer`` they are made only when ``~subscribe`` (std_srvs/Trigger) is called, one every
  SECONDS, in the order given (a subscriber that connects at a chosen moment);
- ``~report`` (std_srvs/Trigger) answers with JSON ``{topic: {"count": n, "messages": [...]}}``,
  each message as ROS itself renders it (``genpy.message.strify_message`` read back as YAML);
  for more than 100 messages only their ``data`` fields are listed; ``"connections"`` maps
  each ``--pub`` topic to its number of subscriber connections;
- every ``--pub`` is a ``rospy.Publisher`` registered at start; ``~publish`` (std_srvs/Trigger)
  publishes each one once with the fields given as JSON.
"""

import json
import sys
import threading
import time

import genpy
import roslib.message
import rospy
import yaml
from std_srvs.srv import Trigger, TriggerResponse


def _split(spec: str, parts: int) -> list:
    fields = spec.split(":", parts - 1)
    if len(fields) != parts:
        raise SystemExit("bad spec %r" % spec)
    return fields


def main() -> None:
    """Parse the arguments, subscribe/advertise, serve the two services."""
    args = rospy.myargv(sys.argv)[1:]
    subs, pubs, defer = [], [], None
    while args:
        flag, value = args[0], args[1]
        args = args[2:]
        if flag == "--defer":
            defer = float(value)
        else:
            (subs if flag == "--sub" else pubs).append(value)
    rospy.init_node("ros_probe")
    lock = threading.Lock()
    received = {}

    def subscribe() -> None:
        for spec in subs:
            topic, type_name, queue = _split(spec, 3)
            with lock:
                received[topic] = []
            rospy.Subscriber(
                topic,
                roslib.message.get_message_class(type_name),
                lambda msg, t=topic: received[t].append(msg),
                queue_size=int(queue) or None,
            )
            if defer:
                time.sleep(defer)

    def start(_request: object) -> TriggerResponse:
        threading.Thread(target=subscribe, daemon=True).start()
        return TriggerResponse(success=True, message="subscribing")

    if defer is None:
        subscribe()
    else:
        rospy.Service("~subscribe", Trigger, start)
    publishers = []
    for spec in pubs:
        topic, type_name, fields = _split(spec, 3)
        cls = roslib.message.get_message_class(type_name)
        publishers.append((rospy.Publisher(topic, cls, queue_size=10), cls, json.loads(fields)))

    def report(_request: object) -> TriggerResponse:
        out = {}
        with lock:
            for topic, messages in received.items():
                messages = list(messages)
                if len(messages) > 100:
                    listed = [getattr(m, "data", None) for m in messages]
                else:
                    listed = [yaml.safe_load(genpy.message.strify_message(m)) for m in messages]
                out[topic] = {"count": len(messages), "messages": listed}
        out["connections"] = {p.resolved_name: p.get_num_connections() for p, _, _ in publishers}
        return TriggerResponse(success=True, message=json.dumps(out))

    def publish(_request: object) -> TriggerResponse:
        for publisher, cls, fields in publishers:
            publisher.publish(cls(**fields))
        return TriggerResponse(success=True, message="%d published" % len(publishers))

    rospy.Service("~report", Trigger, report)
    rospy.Service("~publish", Trigger, publish)
    rospy.spin()


if __name__ == "__main__":
    main()
