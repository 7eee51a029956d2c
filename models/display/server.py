"""The meshcat server behind a display: started on 127.0.0.1, every request with a timeout.

meshcat 0.3.2 facts handled: the server is a subprocess that :func:`stop_meshcat_server` ends; a
request to a dead server would wait for ever, so the sockets get receive and send timeouts and a
dead server raises :class:`TimeoutError`.
"""

from __future__ import annotations

import meshcat
import zmq
from meshcat.visualizer import ViewerWindow

__all__ = ["DEFAULT_TIMEOUT", "start_meshcat_server", "stop_meshcat_server"]

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


def stop_meshcat_server(vis: meshcat.Visualizer) -> None:
    """Close the visualizer's socket and end the server subprocess it started (if any)."""
    window = vis.window
    window.zmq_socket.close(linger=0)
    proc = getattr(window, "server_proc", None)
    if proc is None:
        return
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
