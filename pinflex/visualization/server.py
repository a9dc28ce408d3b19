"""meshcat's zmq/web server as a well-behaved child process.

meshcat starts its server with its stdout and stderr on pipes that nobody reads after the
first two lines. The server prints a line to stderr each time a browser's websocket opens or
closes, so after a few hundred (interrupted) page loads the pipe buffer is full, the server
blocks on ``print`` and the viewer freezes. It is also started in its own session and only
killed by an ``atexit`` hook, so a SIGTERM (or SIGKILL) of the parent leaves it orphaned.

:class:`MeshcatServer` starts the same server, listening on ``127.0.0.1`` only and with a
bounded set of websockets (:mod:`pinflex.visualization.meshcat_server`; meshcat's own binds
every network interface and keeps dropped connections), with its output drained by a daemon
thread (the last lines are kept for error messages), and stops it: on :meth:`close`, at
interpreter exit, on SIGTERM (a handler is installed when the main thread has none), and on
Linux also when the parent dies for any reason (``PR_SET_PDEATHSIG``).

``bind="0.0.0.0"`` (``pinflex view --bind 0.0.0.0``) serves the scene to every machine that
can reach this one: the viewer has no authentication, so do that only on a trusted network.
"""

from __future__ import annotations

import atexit
import collections
import contextlib
import queue
import re
import signal
import subprocess
import sys
import threading
import weakref
from pathlib import Path

from pinflex.exceptions import ViewerServerError

_SERVERS: weakref.WeakSet[MeshcatServer] = weakref.WeakSet()
_HANDLER_INSTALLED = False


def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGTERM))  # PR_SET_PDEATHSIG
    except Exception:  # noqa: BLE001 - best effort, Linux only
        pass


def _stop_all() -> None:
    for server in list(_SERVERS):
        server.close()


def _on_sigterm(signum, frame) -> None:
    _stop_all()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    raise SystemExit(128 + signum)


def _install_handlers() -> None:
    global _HANDLER_INSTALLED
    if _HANDLER_INSTALLED:
        return
    _HANDLER_INSTALLED = True
    atexit.register(_stop_all)
    if threading.current_thread() is threading.main_thread():
        with contextlib.suppress(ValueError, OSError):
            if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
                signal.signal(signal.SIGTERM, _on_sigterm)


class MeshcatServer:
    """A meshcat server child process whose output is drained and which dies with its parent.

    Args:
        zmq_url: zmq address for the server to bind (default: meshcat picks a free port).
        timeout_s: How long to wait for the server to print its URLs [s].
        bind: Address the web port listens on: ``"127.0.0.1"`` (default, this machine only),
            or e.g. ``"0.0.0.0"`` for every interface (anyone on the network sees the scene).

    Attributes:
        zmq_url: Address of the server's zmq socket.
        web_url: URL of the viewer page.
        process: The ``subprocess.Popen`` of the server.
    """

    def __init__(self, zmq_url: str | None = None, timeout_s: float = 30.0,
                 bind: str = "127.0.0.1"):
        """Start the server and wait for its URLs.

        Args:
            zmq_url: zmq address for the server to bind (default: meshcat picks a free port).
            timeout_s: How long to wait for the server to print its URLs [s].
            bind: Address the web port listens on (default ``127.0.0.1``).

        Raises:
            ViewerServerError: The server cannot start, exits at start-up, or prints no URL
                within ``timeout_s``.
        """
        if not isinstance(bind, str) or not bind or any(c.isspace() for c in bind):
            raise ViewerServerError(f"bind address {bind!r} is not an address")
        if bind != "localhost":
            import ipaddress

            try:  # an IP address of this machine; host names would be resolved (slowly)
                ipaddress.ip_address(bind)
            except ValueError:
                raise ViewerServerError(
                    f"bind address {bind!r} is not an IP address (give one such as "
                    "127.0.0.1, 0.0.0.0 or ::, or 'localhost')") from None
        # run by file name: the server process imports meshcat and tornado, not pinflex
        script = str(Path(__file__).with_name("meshcat_server.py"))
        args = [sys.executable, "-u", script, "--bind", bind]
        self.bind = bind
        if zmq_url is not None:
            args += ["--zmq-url", zmq_url]
        self.tail: collections.deque[str] = collections.deque(maxlen=50)
        try:
            self.process = subprocess.Popen(
                args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT, start_new_session=True,
                preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None,
            )
        except OSError as exc:
            raise ViewerServerError(f"cannot start the meshcat server: {exc}") from exc
        _install_handlers()
        _SERVERS.add(self)
        lines: queue.Queue[str | None] = queue.Queue()
        self._reader = threading.Thread(target=self._drain, args=(lines,), daemon=True,
                                        name="meshcat-server-output")
        self._reader.start()
        urls: dict[str, str] = {}
        while len(urls) < 2:
            try:
                line = lines.get(timeout=timeout_s)
            except queue.Empty:
                self.close()
                raise ViewerServerError(
                    f"the meshcat server printed no URL within {timeout_s:g} s"
                ) from None
            if line is None:
                self.close()
                raise ViewerServerError(
                    "the meshcat server exited at start-up: " + " | ".join(self.tail)
                )
            match = re.match(r"^(zmq_url|web_url)=(\S+)", line)
            if match:
                urls[match.group(1)] = match.group(2)
        self.zmq_url = urls["zmq_url"]
        self.web_url = urls["web_url"]

    def _drain(self, lines: queue.Queue | None) -> None:
        stream = self.process.stdout
        assert stream is not None
        for raw in iter(stream.readline, b""):
            text = raw.decode("utf-8", "replace").rstrip()
            self.tail.append(text)
            if lines is not None:
                lines.put(text)
                if text.startswith("web_url="):
                    lines = None  # after start-up, only keep the tail
        if lines is not None:
            lines.put(None)

    @property
    def pid(self) -> int:
        """Process id of the server."""
        return self.process.pid

    def alive(self) -> bool:
        """Whether the server process is running."""
        return self.process.poll() is None

    def close(self, timeout_s: float = 5.0) -> None:
        """Stop the server (SIGTERM, then SIGKILL after ``timeout_s``) and reap it.

        Args:
            timeout_s: How long to wait after SIGTERM before SIGKILL [s]. A no-op when the
                server has already exited.
        """
        _SERVERS.discard(self)
        if self.process.poll() is not None:
            return
        with contextlib.suppress(OSError):
            self.process.terminate()
        try:
            self.process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(OSError):
                self.process.kill()
            self.process.wait()

    def __enter__(self) -> MeshcatServer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def served_visualizer(zmq_url: str | None = None, bind: str = "127.0.0.1"):
    """A ``meshcat.Visualizer`` on a local meshcat server; its URL is ``vis.url()``.

    With ``zmq_url`` it connects to a server that is already running; otherwise it starts a
    :class:`MeshcatServer` (listening on ``bind``, drained output, stopped on exit and
    SIGTERM), available as ``vis.window.pinflex_server``. No browser is opened.

    Args:
        zmq_url: zmq address of a running meshcat server, or None to start one.
        bind: Address the new server's web port listens on (default ``127.0.0.1``, this
            machine only; ``"0.0.0.0"`` serves every network interface, without
            authentication).

    Returns:
        A ``meshcat.Visualizer``.

    Raises:
        MissingDependency: meshcat is not installed.
        ViewerServerError: A new server cannot be started.
    """
    from pinflex.visualization.offline import require_meshcat

    meshcat = require_meshcat()
    if zmq_url is not None:
        return meshcat.Visualizer(zmq_url=zmq_url)
    server = MeshcatServer(bind=bind)
    import io
    from contextlib import redirect_stdout

    try:
        with redirect_stdout(io.StringIO()):  # meshcat prints the URL; callers print it
            window = meshcat.visualizer.ViewerWindow(
                zmq_url=server.zmq_url, start_server=False, server_args=[]
            )
    except Exception as exc:
        server.close()
        raise ViewerServerError(f"cannot connect to the meshcat server: {exc}") from exc
    window.server_proc = server.process
    window.web_url = server.web_url
    window.pinflex_server = server
    return meshcat.Visualizer(window=window)

