"""Who may open the browser app: the page the tool printed, and nobody else.

The app is a local server, so it is a door. As Jupyter Server does, every
run makes a random token; the address the tool prints and opens carries it
(``http://127.0.0.1:8080/?token=...``), and the page keeps it in a cookie
(``HttpOnly``, ``SameSite=Strict``, named after the port) for its later
requests and its websocket. Every request is checked before viser sees it:

* the token, from the query or the cookie (compared in constant time);
* the Host header: the bound address or a loopback name when the server
  listens on a loopback address (a DNS-rebinding page names its own host);
* the Origin of a websocket: the server's own (a page from another site
  never connects, even with the user's cookie).

A refused request gets 403 and one line, never the page or the scene.
"""

from __future__ import annotations

import contextlib
import hmac
import http
import ipaddress
import secrets
from http.cookies import SimpleCookie
from urllib.parse import parse_qs, urlsplit

__all__ = ["Guard", "accept_values_only", "guarded_serve", "is_loopback", "limit_uploads", "value_updates"]

LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")


def is_loopback(host: str) -> bool:
    """True for ``localhost`` and loopback addresses (127.0.0.0/8, ::1)."""
    host = host.strip("[]").lower()
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _hostname(value: str) -> str:
    """The name of a Host header or an Origin's netloc, port and brackets dropped, lower case."""
    return (urlsplit(f"//{value}").hostname or "").lower()


class Guard:
    """The checks of one server: its token, the names it answers to.

    Parameters
    ----------
    host : str
        The address the server is bound to.
    token : str, optional
        Default: 32 random URL-safe bytes (:func:`secrets.token_urlsafe`).
    """

    def __init__(self, host: str, token: str | None = None):
        self.host = host
        self.token = token or secrets.token_urlsafe(32)
        self.port: int | None = None  # known once the server listens: names the cookie

    @property
    def cookie_name(self) -> str:
        return f"supportless-token-{self.port}"

    def _host_allowed(self, header: str | None) -> bool:
        if not is_loopback(self.host):  # reachable from the network: the token alone decides (said when started)
            return True
        name = _hostname(header or "")
        return name in LOOPBACK_NAMES or name == self.host.strip("[]").lower() or is_loopback(name)

    def _token_of(self, request) -> tuple[str | None, bool]:
        """The token the request carries and whether it came in the query."""
        query = parse_qs(urlsplit(request.path).query).get("token")
        if query:
            return query[0], True
        cookie = SimpleCookie()
        try:
            cookie.load(request.headers.get("Cookie", ""))
        except Exception:  # noqa: BLE001 - a malformed cookie is no token
            return None, False
        morsel = cookie.get(self.cookie_name)
        return (morsel.value if morsel else None), False

    def refusal(self, request) -> str | None:
        """Why ``request`` is refused, or None when it may go on.

        Parameters
        ----------
        request : websockets.http11.Request
        """
        try:
            return self._refusal(request)
        except Exception:  # noqa: BLE001 - a header given twice, a malformed value: refused, never a 500
            return "malformed request headers"

    def _refusal(self, request) -> str | None:
        if not self._host_allowed(request.headers.get("Host")):
            return "this app answers only to its own address (Host header refused)"
        token, _ = self._token_of(request)
        if token is None or not hmac.compare_digest(token.encode(), self.token.encode()):
            return "open the address supportless printed, with its token"
        if request.headers.get("Upgrade", "").lower() == "websocket":
            origin = urlsplit(request.headers.get("Origin") or "")
            if origin.scheme not in ("http", "https") or \
                    origin.netloc.lower() != (request.headers.get("Host") or "").lower():
                return "a page from another origin may not connect"
        return None

    def wrap(self, process_request):
        """``process_request`` of websockets' server with the checks before it."""

        async def guarded(connection, request):
            why = self.refusal(request)
            if why is not None:
                return connection.respond(http.HTTPStatus.FORBIDDEN, f"supportless: {why}\n")
            response = process_request(connection, request) if process_request is not None else None
            if hasattr(response, "__await__"):
                response = await response
            token, from_query = self._token_of(request)
            if response is not None and from_query:  # the page keeps the token for its websocket
                response.headers["Set-Cookie"] = (f"{self.cookie_name}={token}; Path=/; HttpOnly; "
                                                  "SameSite=Strict")
            return response

        return guarded


@contextlib.contextmanager
def guarded_serve(guard: Guard):
    """While open, websockets servers started (by viser) check every request with ``guard`` first.

    viser starts its server inside :class:`viser.ViserServer`'s constructor
    and offers no hook for the handshake, so the constructor runs inside this
    block, which wraps the ``process_request`` viser passes to
    ``websockets.asyncio.server.serve``.
    """
    import websockets.asyncio.server as ws_server

    original = ws_server.serve

    def serve(*args, process_request=None, **kwargs):
        return original(*args, process_request=guard.wrap(process_request), **kwargs)

    ws_server.serve = serve
    try:
        yield
    finally:
        ws_server.serve = original


def value_updates(handle, updates: dict) -> dict:
    """What a client may change of a widget: its ``value``, unless the widget is disabled.

    Parameters
    ----------
    handle : viser GUI handle
    updates : dict
        Property name -> value, as the client sent them.

    Returns
    -------
    allowed : dict
        ``{"value": ...}`` or empty.
    """
    if getattr(handle._impl.props, "disabled", False):
        return {}
    return {k: v for k, v in updates.items() if k == "value"}


def accept_values_only(server) -> None:
    """A page may change a widget's value or click an enabled button, and nothing else.

    viser applies whatever property a client sends (a slider's limits,
    ``disabled``, ...), so a client could lift a limit or fire a disabled
    button. This puts a filter before viser's own handler of GUI updates: it
    keeps only ``value`` and drops any update of a disabled widget. (The values
    themselves are then checked by the app as the command line checks them.)

    Parameters
    ----------
    server : viser.ViserServer
    """
    from viser import _messages

    gui = server.gui
    interface = gui._websock_interface
    original = gui._handle_gui_updates

    async def values_only(client_id, message) -> None:
        handle = gui._gui_input_handle_from_uuid.get(message.uuid)
        updates = None if handle is None else value_updates(handle, message.updates)
        if updates:
            await original(client_id, _messages.GuiUpdateMessage(message.uuid, updates))

    interface.unregister_handler(_messages.GuiUpdateMessage, original)
    interface.register_handler(_messages.GuiUpdateMessage, values_only)


def limit_uploads(server, max_bytes: int, on_refused) -> None:
    """Refuse an upload larger than ``max_bytes`` before its first byte is kept.

    viser keeps every part of an upload in memory until the last arrives; a
    page could send any size. This puts a check before viser's handler of the
    start of a transfer: a file said larger than ``max_bytes`` is not
    registered (its parts are then dropped on arrival) and
    ``on_refused(filename, size_bytes)`` says so.

    Parameters
    ----------
    server : viser.ViserServer
    max_bytes : int
    on_refused : callable
        ``on_refused(filename: str, size_bytes: int)``.
    """
    from viser import _messages

    gui = server.gui
    interface = gui._websock_interface
    original = gui._handle_file_transfer_start

    def limited(client_id, message) -> None:
        if int(message.size_bytes) > max_bytes:
            on_refused(str(message.filename), int(message.size_bytes))
            return
        original(client_id, message)

    interface.unregister_handler(_messages.FileTransferStartUpload, original)
    interface.register_handler(_messages.FileTransferStartUpload, limited)
