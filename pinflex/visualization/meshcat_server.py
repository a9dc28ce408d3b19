"""meshcat's viewer server, listening on one address and bounded in its connections.

meshcat's own server (``python -m meshcat.servers.zmqserver``) binds its web port on every
network interface (``0.0.0.0`` and ``[::]``) while printing a ``127.0.0.1`` URL, so any
machine that can reach the host receives the scene; and it keeps every websocket until the
peer closes it, writing each scene update into the send buffer of connections whose peer has
vanished, so its memory grows with every dropped page.

This module runs the same server (:class:`meshcat.servers.zmqserver.ZMQWebSocketBridge`) with:

* the web port bound to one address, ``127.0.0.1`` unless ``--bind`` says otherwise (the zmq
  command socket always stays on ``127.0.0.1``);
* at most :data:`MAX_CLIENTS` websockets: a new page closes the oldest;
* websocket pings every :data:`PING_INTERVAL_S`, a peer that does not answer within
  :data:`PING_TIMEOUT_S` is closed;
* a send buffer of at most :data:`MAX_BUFFER_BYTES` per connection: a reader that falls
  that far behind is closed instead of growing the server.

:class:`pinflex.visualization.server.MeshcatServer` runs it as
``python .../meshcat_server.py [--bind ADDRESS]`` (by file name, so that the server process
imports meshcat and tornado only).
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import sys

import tornado.web
from meshcat.servers import zmqserver as _z

#: Most websockets served at once; a new one closes the oldest.
MAX_CLIENTS = 16
#: Pending bytes allowed in one connection's send buffer.
MAX_BUFFER_BYTES = 64 * 2**20
#: Websocket keep-alive ping interval and the time allowed for its answer [s].
PING_INTERVAL_S = 5.0
PING_TIMEOUT_S = 15.0


class _Handler(_z.WebSocketHandler):
    """meshcat's websocket handler with a bounded pool and send buffer."""

    def open(self):
        bridge = self.bridge
        order = bridge.pinflex_order
        while len(order) >= MAX_CLIENTS:
            bridge.drop(order[0])
        order.append(self)
        bridge.websocket_pool.add(self)
        conn = self.ws_connection
        stream = getattr(conn, "stream", None)
        if stream is not None:
            stream.max_write_buffer_size = MAX_BUFFER_BYTES
        print("opened:", self, file=sys.stderr)
        try:
            bridge.send_scene(self)
        except Exception:  # noqa: BLE001 - a connection that cannot take the scene is dropped
            bridge.drop(self)

    def on_close(self):
        self.bridge.forget(self)
        print("closed:", self, file=sys.stderr)


class _Application(tornado.web.Application):
    """A tornado application that listens on :attr:`address` only."""

    address = "127.0.0.1"

    def listen(self, port, *args, **kwargs):
        kwargs.setdefault("address", self.address)
        return super().listen(port, *args, **kwargs)


class Bridge(_z.ZMQWebSocketBridge):
    """The zmq-to-websocket bridge of meshcat, bound to ``bind`` and bounded (see module)."""

    def __init__(self, bind: str = "127.0.0.1", **kwargs):
        self.pinflex_bind = bind
        self.pinflex_order: collections.deque = collections.deque()
        super().__init__(host="127.0.0.1", **kwargs)

    def make_app(self):
        app = _Application(
            [
                (r"/static/(.*)", _z.StaticFileHandlerNoCache,
                 {"path": _z.VIEWER_ROOT, "default_filename": _z.VIEWER_HTML}),
                (r"/", _Handler, {"bridge": self}),
            ],
            websocket_ping_interval=PING_INTERVAL_S,
            websocket_ping_timeout=PING_TIMEOUT_S,
            websocket_max_message_size=MAX_BUFFER_BYTES,
        )
        app.address = self.pinflex_bind
        return app

    def forget(self, websocket) -> None:
        """Remove a websocket from the pool (it closed)."""
        self.websocket_pool.discard(websocket)
        with contextlib.suppress(ValueError):
            self.pinflex_order.remove(websocket)

    def drop(self, websocket) -> None:
        """Close a websocket at once (its unsent data discarded) and remove it from the pool.

        No closing handshake: a peer that stopped reading would never answer it, and its
        send buffer would be kept until a timeout.
        """
        self.forget(websocket)
        stream = getattr(websocket.ws_connection, "stream", None)
        with contextlib.suppress(Exception):
            if stream is not None:
                stream.close()
            else:
                websocket.close()

    def forward_to_websockets(self, frames):
        _cmd, _path, data = frames
        for websocket in list(self.websocket_pool):
            try:
                websocket.write_message(data, binary=True)
            except Exception:  # noqa: BLE001 - closed or over its buffer: drop it
                self.drop(websocket)


def main(argv: list[str] | None = None) -> None:
    """Start the server and print ``zmq_url=`` and ``web_url=`` lines, as meshcat's does."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--zmq-url", default=None)
    parser.add_argument("--bind", default="127.0.0.1",
                        help="address the web port listens on (default 127.0.0.1: this "
                        "machine only)")
    args = parser.parse_args(argv)
    bridge = Bridge(bind=args.bind, zmq_url=args.zmq_url)
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}")
    sys.stdout.flush()
    with contextlib.suppress(KeyboardInterrupt):
        bridge.run()


if __name__ == "__main__":
    main()
