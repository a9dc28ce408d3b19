"""The served meshcat viewer keeps answering and never outlives the process that started it."""

import asyncio
import os
import signal
import subprocess
import sys
import time
import urllib.request

import pytest
from conftest import ROOT, TWO_LINK

pytest.importorskip("meshcat")
psutil = pytest.importorskip("psutil")


def _gone(pid: int, timeout_s: float = 15.0) -> bool:
    """Whether process ``pid`` has exited (zombies count as exited) within the timeout."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                return True
        except psutil.NoSuchProcess:
            return True
        time.sleep(0.1)
    return False


def test_viewer_answers_after_many_interrupted_page_loads():
    """After 700 dropped websocket connections the viewer still answers.

    Each connection logs two lines to the server's stderr; the output is drained, so the
    server never blocks on a full pipe.
    """
    from tornado.websocket import websocket_connect

    from pinflex.visualization import served_visualizer

    vis = served_visualizer()
    server = vis.window.pinflex_server
    url = vis.url()
    ws_url = url.replace("http://", "ws://").split("/static")[0] + "/"

    async def drop(n, batch=20):
        async def one():
            conn = await websocket_connect(ws_url)
            conn.close()

        for _ in range(n // batch):
            await asyncio.gather(*(one() for _ in range(batch)))

    try:
        asyncio.run(asyncio.wait_for(drop(700), 120))
        with urllib.request.urlopen(url, timeout=10) as page:
            assert page.status == 200 and b"MeshCat" in page.read()
        assert any(line.startswith("closed:") for line in server.tail)
    finally:
        server.close()
    assert not server.alive()


_SERVE = (
    "import sys, time\n"
    "from pinflex.visualization import served_visualizer\n"
    "vis = served_visualizer()\n"
    "print('serving the preview at', vis.url(), flush=True)\n"
    "time.sleep(600)\n"
)


def _serve(tmp_path, cli: bool):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    argv = ([sys.executable, "-m", "pinflex", "view", str(TWO_LINK), "--planar"] if cli
            else [sys.executable, "-c", _SERVE])
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                            cwd=tmp_path, text=True)
    for line in proc.stdout:
        if "serving the preview at" in line:
            break
    else:
        proc.wait()
        pytest.fail("the viewer did not start serving")
    children = psutil.Process(proc.pid).children(recursive=True)
    assert children, "no meshcat server process"
    return proc, [c.pid for c in children]


def _check_no_orphan(tmp_path, sig, cli):
    proc, servers = _serve(tmp_path, cli)
    try:
        proc.send_signal(sig)
        proc.wait(timeout=20)
        assert all(_gone(pid) for pid in servers)
    finally:
        for pid in servers:  # never leave a server behind, even when the test fails
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        if proc.poll() is None:
            proc.kill()
        proc.stdout.close()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_viewer_server_dies_with_its_process(tmp_path, sig):
    """Killing the process that serves a viewer stops the meshcat server: no orphan.

    SIGTERM goes through the cleanup handler, SIGKILL through the parent-death signal.
    """
    _check_no_orphan(tmp_path, sig, cli=False)


@pytest.mark.slow
def test_pinflex_view_leaves_no_orphan_on_sigterm(tmp_path):
    """The same through the `pinflex view` command (slow: it builds a model first)."""
    _check_no_orphan(tmp_path, signal.SIGTERM, cli=True)


def _listening(pid: int) -> set[str]:
    return {c.laddr.ip for c in psutil.Process(pid).net_connections(kind="inet")
            if c.status == psutil.CONN_LISTEN}


def test_served_viewer_listens_on_localhost_only():
    """The web and zmq ports listen on 127.0.0.1 only (meshcat's own: 0.0.0.0 and [::]);
    bind= chooses another address on request."""
    from pinflex.exceptions import ViewerServerError
    from pinflex.visualization import MeshcatServer

    server = MeshcatServer()
    try:
        assert server.web_url.startswith("http://127.0.0.1:")
        assert _listening(server.pid) == {"127.0.0.1"}
    finally:
        server.close()
    wide = MeshcatServer(bind="0.0.0.0")
    try:
        assert "0.0.0.0" in _listening(wide.pid)
    finally:
        wide.close()
    with pytest.raises(ViewerServerError):
        MeshcatServer(bind="")


def test_viewer_memory_is_bounded_under_dropped_connections():
    """5,000 websocket peers that vanish without closing: server RSS grows < 50 MB.

    Each peer completes the handshake and then never reads (a closed laptop lid, a dropped
    network): meshcat's server kept every such connection with the scene (here a 10,000-point
    cloud, ~240 kB) queued in its send buffer, about 14 MB per 1,000 peers for a scene half
    this size. pinflex's keeps at most 16 websockets and drops the oldest at once.
    """
    import base64
    import re
    import socket

    import meshcat.geometry as g
    import numpy as np

    from pinflex.visualization import served_visualizer

    vis = served_visualizer()
    server = vis.window.pinflex_server
    host, port = re.match(r"http://([^:/]+):(\d+)/", server.web_url).groups()
    rng = np.random.default_rng(0)
    cloud = rng.random((3, 10_000)).astype(np.float32)
    vis["cloud"].set_object(g.PointCloud(cloud, cloud))
    held: list[socket.socket] = []

    def rss_mb() -> float:
        return psutil.Process(server.pid).memory_info().rss / 2**20

    try:
        before = rss_mb()
        for _ in range(50):
            batch = [socket.create_connection((host, int(port)), timeout=30) for _ in range(100)]
            for s in batch:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
                key = base64.b64encode(os.urandom(16)).decode()
                s.sendall((f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           "Sec-WebSocket-Version: 13\r\n\r\n").encode())
            for s in batch:
                assert s.recv(12) == b"HTTP/1.1 101"
            held += batch
        growth = rss_mb() - before
        assert growth < 50.0, f"server RSS grew {growth:.1f} MB over 5,000 dropped peers"
        with urllib.request.urlopen(server.web_url, timeout=10) as page:  # still serving
            assert page.status == 200
    finally:
        for s in held:
            s.close()
        server.close()
