"""Which port the viewer listens on, and the page's address.

``supportless view`` takes 8080 or the next free port; a port the user names
must be free, and a taken one is a clear error rather than a silent move.
"""

from __future__ import annotations

import errno
import socket

from ...base.errors import InputError
from .guard import Guard, accept_values_only, guarded_serve

__all__ = ["DEFAULT_PORT", "check_host", "find_free_port", "page_url", "port_is_free", "port_taken_message",
           "start_server"]

#: The first port tried when none is given.
DEFAULT_PORT = 8080


def check_host(host: str) -> None:
    """Refuse an address this machine cannot listen on, before any port is tried.

    Raises
    ------
    InputError
        For a name that does not resolve, or an address of another machine.
    """
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        raise InputError(None, f"--host {host!r} is not an address ({exc}); use 127.0.0.1, or 0.0.0.0 for "
                               "every interface") from None
    family, _, _, _, address = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as s:
        try:
            s.bind((address[0], 0))
        except OSError as exc:
            if exc.errno == errno.EADDRNOTAVAIL:
                raise InputError(None, f"--host {host!r} is not an address of this machine; use 127.0.0.1, or "
                                       "0.0.0.0 for every interface") from None
            raise InputError(None, f"cannot listen on --host {host!r}: {exc.strerror or exc}") from None


def port_is_free(host: str, port: int) -> bool:
    """True when a server could listen on ``host:port`` now.

    Parameters
    ----------
    host : str
        Address to bind (IPv4 or IPv6).
    port : int

    Returns
    -------
    free : bool
    """
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def find_free_port(host: str = "127.0.0.1", start: int = DEFAULT_PORT, attempts: int = 200) -> int:
    """The first port from ``start`` on which ``host`` can listen.

    Parameters
    ----------
    host : str
    start : int
        First port tried.
    attempts : int
        How many ports are tried, one after the other.

    Returns
    -------
    port : int

    Raises
    ------
    InputError
        When none of ``attempts`` ports is free.
    """
    for port in range(start, min(start + attempts, 65536)):
        if port_is_free(host, port):
            return port
    raise InputError(None, f"no free port in {start}..{start + attempts - 1} on {host}; use --port N")


def port_taken_message(host: str, port: int) -> str:
    """The error shown when the port the user asked for is taken."""
    return f"port {port} on {host} is taken; use --port N"


def page_url(host: str, port: int, token: str | None = None) -> str:
    """The address to open in a browser for a server bound to ``host:port`` (with its token).

    A server on every interface (``0.0.0.0``, ``::``) is shown as
    ``localhost``; IPv6 addresses are bracketed.
    """
    shown = "localhost" if host in ("0.0.0.0", "::", "") else f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}" + ("" if token is None else f"/?token={token}")


def start_server(host: str, port: int | None, label: str, verbose: bool = True, guard=None):
    """A viser server listening on ``host:port``, every request checked by ``guard``.

    Parameters
    ----------
    host : str
    port : int or None
        None: :data:`DEFAULT_PORT` or the next free port.
    label : str
        Title of the page.
    verbose : bool
        Let viser print its banner.
    guard : supportless.apps.ui.guard.Guard, optional
        Checks the token, Host and Origin of every request (default: a new
        one with a random token); its ``port`` is set.

    Returns
    -------
    server : viser.ViserServer

    Raises
    ------
    InputError
        When the host is not an address of this machine (:func:`check_host`),
        or the given port is taken (also when another program takes it
        while the server starts).
    """
    import viser

    check_host(host)
    if port is None:
        port = find_free_port(host, DEFAULT_PORT)
    elif not port_is_free(host, port):
        raise InputError(None, port_taken_message(host, port))
    guard = guard if guard is not None else Guard(host)
    guard.port = port
    with guarded_serve(guard):
        server = viser.ViserServer(host=host, port=port, label=label, verbose=verbose)
    accept_values_only(server)
    if server.get_port() != port:  # viser moved on by itself: the port was taken meanwhile
        server.stop()
        raise InputError(None, port_taken_message(host, port))
    return server
