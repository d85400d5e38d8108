"""In-process fake rosbridge v2 server (websockets) for the link and GUI tests.

It records advertise/publish/subscribe/call_service ops, answers service calls with a
configurable handler (None from it: the connection is dropped without an answer) and pushes
messages to subscribed clients. ``kick_all`` drops every connection (link loss);
``stop``/``start`` on the same port simulate a bridge restart.
"""

import asyncio
import json
import threading

import websockets
from rbd_testkit import free_port, wait_for


class FakeBridge:
    def __init__(self, port=0):
        # Not port 0: the kernel's pick is an ephemeral port, which any ROS node started meanwhile
        # (bind to port 0) can take while the bridge is stopped for a restart on the same port.
        self.port = port or free_port()
        self.published = []  # (topic, msg)
        self.advertised = []
        self.subscribed = {}  # topic -> type
        self.subscribe_ops = []  # the subscribe ops as received (throttle_rate, queue_length, ...)
        self.service_calls = []  # (service, args)
        self.service_handler = lambda service, args: (True, {"success": True, "message": "ok"})
        self.connections = 0
        self._clients = set()
        self._subs = {}  # websocket -> {topic: id}
        self._loop = None
        self._server = None
        self._thread = None
        self._lock = threading.RLock()

    # -- control from the test thread
    def start(self):
        ready = threading.Event()

        def run():
            loop = self._loop = asyncio.new_event_loop()
            asyncio.set_event_loop(loop)

            async def main():
                # a client that does not answer the closing handshake holds stop() 2 s at most
                self._server = await websockets.serve(self._handle, "127.0.0.1", self.port, close_timeout=2)
                self.port = self._server.sockets[0].getsockname()[1]
                ready.set()
                await self._server.wait_closed()

            try:
                loop.run_until_complete(main())
            finally:
                loop.close()

        self._thread = threading.Thread(target=run, daemon=True)
        self._thread.start()
        assert ready.wait(5), "fake bridge did not start"
        return self

    def stop(self):
        if self._loop is None:
            return

        async def shutdown():
            self._server.close()
            await asyncio.gather(*(ws.close() for ws in list(self._clients)), return_exceptions=True)

        # (generous: under load the closing handshakes of several clients take seconds)
        try:
            asyncio.run_coroutine_threadsafe(shutdown(), self._loop).result(20)
            self._thread.join(20)
        finally:
            self._loop = None

    def kick_all(self):
        async def kick():
            await asyncio.gather(*(ws.close() for ws in list(self._clients)), return_exceptions=True)

        asyncio.run_coroutine_threadsafe(kick(), self._loop).result(20)

    def push(self, topic, msg):
        """Send msg to every client subscribed to topic."""

        async def send():
            for ws, subs in list(self._subs.items()):
                if topic in subs:
                    await ws.send(json.dumps({"op": "publish", "topic": topic, "msg": msg}))

        asyncio.run_coroutine_threadsafe(send(), self._loop).result(30)

    def wait_for(self, predicate, timeout=60.0):
        """The test kit's wait_for, with predicate evaluated under this bridge's lock."""

        def locked():
            with self._lock:
                return predicate()

        return wait_for(locked, timeout, 0.02)

    def published_on(self, topic):
        with self._lock:
            return [m for t, m in self.published if t == topic]

    # -- server side
    async def _handle(self, ws):
        self._clients.add(ws)
        self._subs[ws] = {}
        with self._lock:
            self.connections += 1
        try:
            async for raw in ws:
                try:
                    msg = json.loads(raw)
                except ValueError:
                    continue
                op = msg.get("op")
                with self._lock:
                    if op == "advertise":
                        self.advertised.append((msg["topic"], msg.get("type")))
                    elif op == "publish":
                        self.published.append((msg["topic"], msg.get("msg")))
                    elif op == "subscribe":
                        self._subs[ws][msg["topic"]] = msg.get("id")
                        self.subscribed[msg["topic"]] = msg.get("type")
                        self.subscribe_ops.append(msg)
                    elif op == "unsubscribe":
                        self._subs[ws].pop(msg["topic"], None)
                    elif op == "call_service":
                        self.service_calls.append((msg["service"], msg.get("args")))
                if op == "call_service":
                    answer = self.service_handler(msg["service"], msg.get("args"))
                    if answer is None:  # the link dies with the call in flight: no answer, dropped
                        await ws.close()
                        break
                    result, values = answer
                    reply = {"op": "service_response", "service": msg["service"], "result": result, "values": values}
                    if "id" in msg:
                        reply["id"] = msg["id"]
                    await ws.send(json.dumps(reply))
        except websockets.ConnectionClosed:
            pass
        finally:
            self._clients.discard(ws)
            self._subs.pop(ws, None)
