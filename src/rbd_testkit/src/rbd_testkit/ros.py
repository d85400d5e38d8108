"""ROS-side pieces for rostest node scripts: a shuffled-order runner and a /rosout watcher.

Imports rospy and rostest only when used, so the rest of the kit stays ROS-free.
"""

import os
import random
import sys
import threading
import unittest
from typing import Any, List, Optional, Tuple

SEED_ENV = "RBD_TEST_SEED"


def order_seed() -> int:
    """The test-order seed: ``$RBD_TEST_SEED`` when set (``make test`` sets one per run), else random.

    Returns:
        The seed.
    """
    value = os.environ.get(SEED_ENV, "").strip()
    return int(value) if value else random.SystemRandom().randrange(1, 2 ** 31)


def shuffled_order(names: List[str], seed: int) -> List[str]:
    """The test method names in the order ``seed`` gives them.

    Each name's place depends only on the seed and the name itself, so a method added to a class
    does not reorder the others.

    Args:
        names: method names.
        seed: the order seed.

    Returns:
        The names, shuffled.
    """
    return sorted(names, key=lambda name: random.Random("%d:%s" % (seed, name)).random())


def run_rostest(package: str, test_name: str, case: type, seed: Optional[int] = None) -> None:
    """``rostest.rosrun`` with the test methods in a shuffled order, the seed printed.

    unittest runs methods in name order; a class whose tests only pass in that order hides
    dependencies between them. This runs them in the order of ``seed`` (see ``order_seed``)
    and prints it (``RBD_TEST_SEED=<seed>`` repeats the order).

    Args:
        package: the package of the test (as for ``rostest.rosrun``).
        test_name: the test's name (as for ``rostest.rosrun``).
        case: the ``unittest.TestCase`` class.
        seed: the order seed; None: ``order_seed()``.
    """
    import rostest

    seed = order_seed() if seed is None else seed
    names = unittest.TestLoader().getTestCaseNames(case)
    rank = {name: i for i, name in enumerate(shuffled_order(list(names), seed))}
    sys.stderr.write("rbd_testkit: %s.%s in shuffled order (%s=%d): %s\n"
                     % (package, test_name, SEED_ENV, seed, ", ".join(sorted(names, key=rank.get))))

    def by_rank(a: str, b: str) -> int:
        return rank.get(a, -1) - rank.get(b, -1)

    saved = unittest.TestLoader.sortTestMethodsUsing
    unittest.TestLoader.sortTestMethodsUsing = staticmethod(by_rank)
    try:
        rostest.rosrun(package, test_name, case)
    finally:
        unittest.TestLoader.sortTestMethodsUsing = saved


def subscriber_nodes(publisher: Any) -> List[str]:
    """The nodes whose subscriptions are connected to ``publisher`` now (a ``rospy.Publisher``).

    A latched publisher hands its last message to each subscriber on connection, so a node in
    this list has been sent it: wait for a node's name here instead of sleeping after a latched
    publish (e.g. a static transform) or after a subscriber count that other nodes could make.

    Args:
        publisher: a ``rospy.Publisher``.

    Returns:
        The subscribers' node names (e.g. ``["/ekf_localization"]``), one per connection.

    Example:
        >>> wait_for(lambda: "/ekf" in subscriber_nodes(static_tf.pub_tf), 20.0)  # doctest: +SKIP
    """
    return [str(info[1]) for info in publisher.impl.get_stats_info()]


def messages_received(node: str, topic: str) -> int:
    """How many messages ``node`` has received on ``topic`` so far, from the node's own statistics.

    The node's XML-RPC ``getBusStats`` counts the messages its subscription read from each live
    connection: a count above its value before a publish proves the message reached that node
    (not only that someone is subscribed). Needs ``rospy.init_node`` first.

    Args:
        node: the node's full name (e.g. ``/rbd_pos_controller``).
        topic: the topic's resolved name.

    Returns:
        The sum over the node's live connections on ``topic`` (0 when it has none).

    Raises:
        RuntimeError: the node did not answer the statistics call.

    Example:
        >>> n = messages_received("/rbd_pos_controller", "/rbd_lidar/speed_scale")  # doctest: +SKIP
        >>> pub.publish(Float32(0.0))
        >>> wait_for(lambda: messages_received("/rbd_pos_controller", "/rbd_lidar/speed_scale") > n, 5.0)
    """
    from xmlrpc.client import ServerProxy

    import rosgraph
    import rospy

    caller = rospy.get_name()
    code, message, stats = ServerProxy(rosgraph.Master(caller).lookupNode(node)).getBusStats(caller)
    if code != 1:
        raise RuntimeError("%s: getBusStats failed: %s" % (node, message))
    return sum(int(conn[2]) for name, conns in stats[1] if name == topic for conn in conns)


class RosoutWatcher:
    """Collects what nodes log on /rosout: a node's own log line proves an input reached it.

    Example:
        >>> rosout = RosoutWatcher()  # doctest: +SKIP
        >>> rosout.wait_connected("/rbd_gestrec")
        >>> mark = rosout.mark()
        >>> pub.publish(String("self_destruct"))
        >>> rosout.wait_for("unknown gesture 'self_destruct'", node="/rbd_gestrec", since=mark)
    """

    def __init__(self, topic: str = "/rosout") -> None:
        """Subscribe (needs ``rospy.init_node`` first).

        Args:
            topic: the log topic (``/rosout``: every node's own messages).
        """
        import rospy
        from rosgraph_msgs.msg import Log

        self._lock = threading.Lock()
        self.lines: List[Tuple[str, int, str]] = []
        self.sub = rospy.Subscriber(topic, Log, self._on_log, queue_size=200)

    def _on_log(self, msg: Any) -> None:
        with self._lock:
            self.lines.append((msg.name, msg.level, msg.msg))

    def mark(self) -> int:
        """The number of lines seen so far (to look only at later lines).

        Returns:
            The count.
        """
        with self._lock:
            return len(self.lines)

    def find(self, text: str, node: Optional[str] = None, since: int = 0) -> List[str]:
        """Lines containing ``text`` (from ``node``, if given) seen after line ``since``.

        Args:
            text: a substring of the message.
            node: the node's full name (e.g. ``/rbd_gestrec``); None: any node.
            since: a ``mark()``.

        Returns:
            The matching messages.
        """
        with self._lock:
            lines = self.lines[since:]
        return [m for n, _level, m in lines if text in m and (node is None or n == node)]

    def wait_for(self, text: str, node: Optional[str] = None, since: int = 0, timeout: float = 10.0) -> str:
        """Wait until a line containing ``text`` arrives (see ``find``).

        Args:
            text: a substring of the message.
            node: the node's full name; None: any node.
            since: a ``mark()``.
            timeout: seconds.

        Returns:
            The first matching message.

        Raises:
            WaitTimeoutError: none arrived in time.
        """
        from rbd_testkit.wait import wait_for

        what = "%r on /rosout from %s" % (text, node or "any node")
        return wait_for(lambda: self.find(text, node, since), timeout, 0.02, what=what)[0]

    def wait_connected(self, node: str, timeout: float = 20.0) -> None:
        """Wait until ``node``'s /rosout publisher is connected to this watcher.

        Lines a node logs before the connection is up are lost; wait for it before the input.

        Args:
            node: the node's full name.
            timeout: seconds.

        Raises:
            WaitTimeoutError: not connected in time.
        """
        import rosgraph
        import rospy

        from rbd_testkit.wait import wait_for

        master = rosgraph.Master(rospy.get_name())

        def connected() -> bool:
            uri = master.lookupNode(node)
            return self.sub.impl.has_connection(uri)

        wait_for(connected, timeout, 0.05, what="%s's /rosout connection" % node, ignore=(Exception,))

