"""
``mi-brdfs explore``'s server: the page of :mod:`~mi_brdfs.explorer.app` served by Panel (a
Bokeh server) on 127.0.0.1 unless a host is given, one page and one session per browser tab;
the BSDFs are checked, and the port taken, before it starts, so that a bad BSDF or a port in
use ends in one line. Ctrl-C or SIGTERM stop it within a second.
"""

from __future__ import annotations

import signal
import socket
import sys

from ..errors import MiBrdfsError

LOCALHOST = "127.0.0.1"


def free_port(host: str, port: int | None) -> int:
    """``port`` where it can be bound on ``host`` (else MiBrdfsError, one line), or with None
    one the system gives."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((host, port or 0))
        except OSError as e:
            raise MiBrdfsError(f"explore: cannot listen on {host}:{port}: {e.strerror or e} "
                               f"(another program uses it? give another --port)") from None
        return s.getsockname()[1]


def serve(specs, port: int, host: str = LOCALHOST, browser: bool = True, scene=None,
          out=sys.stdout) -> int:
    """Serve the explorer of ``specs`` (checked already; ``scene``: see
    :func:`~mi_brdfs.explorer.app.build`) on ``port`` (:func:`free_port`) until Ctrl-C or
    SIGTERM; 0."""
    import panel as pn

    from .app import build

    url = f"http://{'localhost' if host == LOCALHOST else host}:{port}/"
    origins = [f"{h}:{port}" for h in ("localhost", LOCALHOST, host)]
    server = pn.serve({"/": lambda: build(specs, scene=scene)}, port=port, address=host,
                      websocket_origin=origins, show=False, start=False, verbose=False,
                      title="mi-brdfs explore")
    loop = server.io_loop
    previous = signal.signal(signal.SIGTERM,
                             lambda *_: loop.add_callback_from_signal(loop.stop))
    server.start()
    if host != LOCALHOST:
        print(f"explore: listening on {host}, not only this machine: anyone who reaches "
              f"{host}:{port} sees and drives the page", file=out)
    print(f"explore: {url} (Ctrl-C stops)", file=out, flush=True)
    if browser:
        import webbrowser
        webbrowser.open(url)
    try:
        loop.start()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
        signal.signal(signal.SIGTERM, previous)
    print("explore: stopped", file=out, flush=True)
    return 0
