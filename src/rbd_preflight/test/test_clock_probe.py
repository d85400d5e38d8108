"""rbd_preflight.clock_probe: a host's clock from the HTTP Date of its XML-RPC servers (no ROS).

Against real HTTP servers on 127.0.0.1: Python's own XML-RPC server (what rospy, roslaunch and
rosmaster serve) for the Date header's presence, and a server whose Date runs a known skew ahead,
so the measured offset can be compared with the truth.
"""

import http.server
import socketserver
import threading
import time
import xmlrpc.server

import pytest

from rbd_preflight import clock_probe


class _Threading(socketserver.ThreadingMixIn, http.server.HTTPServer):
    daemon_threads = True


def skewed_server(skew, date=True):
    class Handler(http.server.BaseHTTPRequestHandler):
        def date_time_string(self, timestamp=None):
            return http.server.BaseHTTPRequestHandler.date_time_string(self, time.time() + skew)

        def send_header(self, key, value):
            if key == "Date" and not date:
                return  # as roscpp's XmlRpc++: no Date header
            http.server.BaseHTTPRequestHandler.send_header(self, key, value)

        def do_POST(self):  # noqa: N802
            self.rfile.read(int(self.headers.get("Content-Length", 0)))
            body = b"<?xml version='1.0'?><methodResponse><params/></methodResponse>"
            self.send_response(200)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):
            pass

    server = _Threading(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, "http://127.0.0.1:%d/" % server.server_address[1]


@pytest.mark.parametrize("skew", [0.080, -0.237])  # zero skew: the XML-RPC test below
def test_measures_a_known_skew_within_its_uncertainty(skew):
    server, url = skewed_server(skew)
    try:
        offset, uncertainty, samples = clock_probe.measure(clock_probe.http_date_sampler(url), budget=3.5)
    finally:
        server.shutdown()
    # the truth lies within the reported bounds, and those are tight on loopback (a loaded 2-core
    # machine may stretch a round trip to a few ms)
    assert abs(offset - skew) <= uncertainty + 1e-3, (offset, uncertainty, len(samples))
    assert uncertainty < 0.02
    assert len(samples) < 400  # it aims at the turns of the second instead of hammering the server


def test_python_xmlrpc_servers_send_a_date_and_roscpp_like_ones_are_reported():
    rpc = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
    rpc.register_function(lambda caller: [1, "", 42], "getPid")
    threading.Thread(target=rpc.serve_forever, daemon=True).start()
    plain, plain_url = skewed_server(0.0, date=False)
    try:
        rpc_url = "http://127.0.0.1:%d/" % rpc.server_address[1]
        t_send, t_recv, second = clock_probe.http_date_sampler(rpc_url)()
        assert t_send <= t_recv and abs(second - t_recv) < 2.0
        with pytest.raises(clock_probe.NoDateHeaderError):
            clock_probe.http_date_sampler(plain_url)()
        # measure_host takes the first server of the host that sends a Date
        offset, uncertainty, used = clock_probe.measure_host([plain_url, rpc_url], budget=3.0)
        assert used == rpc_url and abs(offset) <= uncertainty + 1e-3
        with pytest.raises(clock_probe.NoDateHeaderError, match="no Date header from 2 server"):
            clock_probe.measure_host([plain_url, "http://127.0.0.1:1/"], budget=1.0)
    finally:
        rpc.shutdown()
        plain.shutdown()


def test_offset_bounds_intersect_the_samples():
    # server 0.3 s ahead: replies at local 10.65 / 10.72 read 10 / 11 (server 10.95 / 11.02)
    samples = [(10.64, 10.66, 10), (10.71, 10.73, 11)]
    lo, hi = clock_probe.offset_bounds(samples)
    assert lo == pytest.approx(11 - 10.73) and hi == pytest.approx(11 - 10.64)
    assert lo <= 0.3 <= hi
    with pytest.raises(ValueError):
        clock_probe.offset_bounds([(10.0, 10.01, 10), (10.02, 10.03, 12)])  # a jump of 2 s in 20 ms
    with pytest.raises(ValueError):
        clock_probe.offset_bounds([])


def test_parse_date_and_host_of():
    assert clock_probe.parse_date("Sun, 06 Nov 1994 08:49:37 GMT") == 784111777
    with pytest.raises(ValueError):
        clock_probe.parse_date("yesterday")
    assert clock_probe.host_of("http://jetson:41234/") == "jetson"
    assert clock_probe.host_of(None) is None
