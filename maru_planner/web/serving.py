"""The viser server the views run on: bound to 127.0.0.1 unless another address of this machine is given."""

from __future__ import annotations

import contextlib
import io
import socket

import viser

from maru_planner import errors

DEFAULT_HOST = "127.0.0.1"


def serve(host: str, port: int) -> viser.ViserServer:
    """A viser server on ``host`` (from ``port`` up to the first free one); InvalidRequest if ``host`` is not an
    address of this machine (viser would retry it forever). viser's banner is not printed: callers print the URL."""
    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as probe:
            probe.bind((host, 0))
    except OSError as exc:
        raise errors.InvalidRequest(f"cannot serve on host {host!r}: {exc.strerror or exc}") from None
    with contextlib.redirect_stdout(io.StringIO()):
        return viser.ViserServer(host=host, port=port, verbose=False)
