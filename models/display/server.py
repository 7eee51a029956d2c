"""The meshcat server behind a display: started on 127.0.0.1, every request with a timeout.

meshcat 0.3.2 facts handled: the server is a subprocess that :func:`stop_meshcat_server` ends; a
request to a dead server would wait for ever, so the sockets get receive and send timeouts and a
dead server raises :class:`TimeoutError`.
"""

from __future__ import annotations

import atexit
import contextlib
import io
import subprocess

import meshcat
import zmq
from meshcat.servers.zmqserver import start_zmq_server_as_subprocess
from meshcat.visualizer import ViewerWindow

__all__ = ["DEFAULT_TIMEOUT", "connect_spawned", "spawn_meshcat_server", "start_meshcat_server", "stop_meshcat_server"]

DEFAULT_TIMEOUT = 60.0
"""Seconds a request to the meshcat server may take."""


def start_meshcat_server(zmq_url: str | None = None, timeout: float = DEFAULT_TIMEOUT) -> meshcat.Visualizer:
    """Start (or connect to) a meshcat server and return a visualizer with request timeouts.

    Parameters
    ----------
    zmq_url : str, optional
        Address of an already running ``meshcat-server``; ``None`` starts a local server
        subprocess on 127.0.0.1.
    timeout : float
        Seconds a request may wait for the server's answer before :class:`TimeoutError`.
    """
    if timeout <= 0:
        raise ValueError(f"timeout must be positive, got {timeout}")
    # Sockets take their options from the context when created: set them for the duration of the
    # construction only, so that even the first request (the web URL) cannot hang.
    context = ViewerWindow.context
    saved = dict(context.sockopts)
    context.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
    context.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
    context.setsockopt(zmq.LINGER, 0)
    try:
        return meshcat.Visualizer(zmq_url=zmq_url)
    except zmq.error.Again as e:
        raise TimeoutError(f"no meshcat server answered at {zmq_url} within {timeout} s") from e
    finally:
        context.sockopts.clear()
        context.sockopts.update(saved)


def spawn_meshcat_server() -> tuple[subprocess.Popen, str]:
    """Start a local meshcat server subprocess and return it with its ZMQ address, printing nothing (so that a
    thread may start it while other work runs); :func:`connect_spawned` connects to it.  It is ended at the
    latest when this process exits."""
    proc, zmq_url, _ = start_zmq_server_as_subprocess()
    atexit.register(_end_process, proc)
    return proc, zmq_url


def connect_spawned(spawned: tuple[subprocess.Popen, str], timeout: float = DEFAULT_TIMEOUT) -> meshcat.Visualizer:
    """A visualizer (:func:`start_meshcat_server`, its URL not printed) on a server from
    :func:`spawn_meshcat_server`, owning it: :func:`stop_meshcat_server` ends it."""
    proc, zmq_url = spawned
    with contextlib.redirect_stdout(io.StringIO()):
        vis = start_meshcat_server(zmq_url, timeout)
    vis.window.server_proc = proc
    return vis


def stop_meshcat_server(vis: meshcat.Visualizer) -> None:
    """Close the visualizer's socket and end the server subprocess it started (if any)."""
    window = vis.window
    window.zmq_socket.close(linger=0)
    proc = getattr(window, "server_proc", None)
    if proc is not None:
        _end_process(proc)


def _end_process(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except Exception:
            proc.kill()
            proc.wait(timeout=5)
    for stream in (proc.stdout, proc.stderr):
        if stream is not None:
            stream.close()
