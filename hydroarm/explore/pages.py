"""What both pages of ``hydroarm explore`` (the arm's and a system's) share: the runs of a
page's changes on a thread, the latest value of each control first, the checks of what a
client sends, and the server with its guard (docs/explore.md "Who may connect").

The guard (`Guard`, an ASGI middleware in front of every request, the socket.io
connection included): a request whose ``Host`` does not name the address the server listens
on (127.0.0.1, localhost, the ``--host`` given; any port) is refused with 403, as is one whose
``Origin`` names another host (a web page elsewhere driving the session: DNS rebinding,
cross-site requests); socket.io's own allowed origins are the same. Listening on anything
but the loopback interface, the server also asks for a per-session token (as Jupyter does):
the URL it prints carries ``?token=…``; the first request with it sets a cookie, and every
request without the token or the cookie is refused."""

from __future__ import annotations

import asyncio
import hmac
import ipaddress
import logging
import math
import secrets
import socket
import unicodedata
import webbrowser
from collections.abc import Awaitable, Callable
from http.cookies import SimpleCookie
from typing import Any
from urllib.parse import parse_qs, urlsplit

from ..errors import HydroarmError

log = logging.getLogger("hydroarm.explore")
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
TOKEN_COOKIE = "hydroarm_explore_token"
MAX_LOGGED = 300  # characters of a client's text logged at most


async def run_latest(
    pending: dict,
    lock: asyncio.Lock,
    io_bound: Callable[..., Awaitable],
    setter: Callable[[str, Any], object],
    before: Callable[[], None] | None = None,
) -> str | None:
    """Apply the changes in ``pending`` (control name → its latest value) with
    ``setter(name, value)`` run by ``io_bound`` (NiceGUI's ``run.io_bound``: a thread; the
    numba kernels release the GIL), one after another under ``lock``. Values arriving
    meanwhile replace the pending one of their control, so a dragged slider runs its latest
    value next and skips the ones in between. ``before()`` is called before each run (a
    status line). Returns None when another call already holds the lock (it will run the
    new value), else the last refusal's one-line message ('' if every value was taken)."""
    if lock.locked():
        return None
    async with lock:
        refused = ""
        while pending:
            name, value = next(iter(pending.items()))
            del pending[name]
            if before is not None:
                before()
            try:
                await io_bound(setter, name, value)
            except HydroarmError as exc:  # a refused value: the setting is kept
                refused = str(exc)
        return refused


def is_loopback(host: str) -> bool:
    """Whether ``host`` is the loopback interface (``localhost`` or a loopback address)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def allowed_hosts(host: str) -> frozenset[str]:
    """The host names a request's ``Host`` (and ``Origin``) may carry: the loopback names and
    ``host``; a wildcard address (0.0.0.0, ::) adds the machine's name and addresses."""
    names = {*LOOPBACK_NAMES, host.lower()}
    if host in ("0.0.0.0", "::"):
        try:
            name, aliases, addresses = socket.gethostbyname_ex(socket.gethostname())
            names.update(n.lower() for n in (name, *aliases, *addresses))
        except OSError:  # pragma: no cover - a machine without a resolvable name
            names.add(socket.gethostname().lower())
    return frozenset(names)


def host_name(value: str) -> str:
    """The host part of a ``Host`` header's value (``name``, ``name:port``, ``[v6]:port``),
    lower case; '' when it cannot be read."""
    value = value.strip().lower()
    if value.startswith("["):
        end = value.find("]")
        return value[1:end] if end > 0 else ""
    return value.rsplit(":", 1)[0] if value.count(":") == 1 else value


def printable(text: object) -> str:
    """A client's text made safe for the terminal: control characters (escape sequences
    included) shown as ``\\xNN``/``\\uNNNN`` escapes, cut to `MAX_LOGGED` characters."""
    s = text if isinstance(text, str) else repr(text)
    out = "".join(
        c if unicodedata.category(c)[0] != "C" else c.encode("unicode_escape").decode("ascii")
        for c in s[: MAX_LOGGED + 1]
    )
    return out if len(out) <= MAX_LOGGED else out[:MAX_LOGGED] + "…"


def client_number(field: str, value) -> float:
    """A number sent by the page (a slider, a field): a finite int or float, else a
    [`HydroarmError`][hydroarm.HydroarmError] naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise HydroarmError(field, f"must be a finite number, got {printable(repr(value))}")
    return float(value)


def refused(field: str, problem: str) -> None:
    """One logged line for a value a client sent that was refused (the page goes on)."""
    log.warning("hydroarm explore: refused %s: %s", printable(field), printable(problem))


class Guard:
    """ASGI middleware: only requests whose ``Host`` and ``Origin`` name an allowed host (and,
    with a ``token``, that carry it or its cookie) reach the app (module doc)."""

    def __init__(self, app, hosts: frozenset[str], token: str | None = None):
        self.app = app
        self.hosts = hosts
        self.token = token

    def origin_allowed(self, origin: str | None) -> bool:
        """Whether an ``Origin`` header's value may connect (absent: a same-origin request)."""
        if origin is None:
            return True
        try:
            name = urlsplit(origin).hostname
        except ValueError:
            return False
        return name is not None and name.lower() in self.hosts

    def _why_not(self, scope) -> tuple[str, bool]:
        """(why the request is refused, '' if not; whether the token came in its query)."""
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        if host_name(headers.get("host", "")) not in self.hosts:
            return "this server answers only to its own address (Host)", False
        if not self.origin_allowed(headers.get("origin")):
            return "requests from other sites are refused (Origin)", False
        if self.token is None:
            return "", False
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        given = query.get("token", [""])[0]
        if given and hmac.compare_digest(given, self.token):
            return "", True
        cookie = SimpleCookie()
        try:
            cookie.load(headers.get("cookie", ""))
        except Exception:  # a malformed cookie header: no token
            return "the session's token is missing (use the URL the server printed)", False
        kept = cookie.get(TOKEN_COOKIE)
        if kept is not None and hmac.compare_digest(kept.value, self.token):
            return "", False
        return "the session's token is missing (use the URL the server printed)", False

    async def __call__(self, scope, receive, send):
        if scope["type"] not in ("http", "websocket"):
            return await self.app(scope, receive, send)
        why, with_token = self._why_not(scope)
        if why:
            refused("request", f"{why}: {scope.get('path', '')}")
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
                return
            body = f"hydroarm explore: {why}\n".encode()
            await send(
                {
                    "type": "http.response.start",
                    "status": 403,
                    "headers": [
                        (b"content-type", b"text/plain; charset=utf-8"),
                        (b"content-length", str(len(body)).encode()),
                    ],
                }
            )
            await send({"type": "http.response.body", "body": body})
            return
        if not with_token or scope["type"] != "http":
            return await self.app(scope, receive, send)
        cookie = f"{TOKEN_COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict".encode()

        async def send_with_cookie(message):
            if message["type"] == "http.response.start":
                message = {**message, "headers": [*message["headers"], (b"set-cookie", cookie)]}
            await send(message)

        return await self.app(scope, receive, send_with_cookie)


def session_token(host: str) -> str | None:
    """A fresh token when the server listens beyond the loopback interface, else None."""
    return None if is_loopback(host) else secrets.token_urlsafe(24)


def page_url(host: str, port: int, token: str | None) -> str:
    """The URL the server prints (with its token, when it asks for one)."""
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}/" + (f"?token={token}" if token else "")


def _guard_socketio(sio, hosts: frozenset[str]) -> None:
    """socket.io (NiceGUI's ``core.sio``): its allowed origins are the guard's; a page's
    ``log`` event is printed escaped; a malformed ``event`` message is one logged line."""
    guard = Guard(None, hosts)
    sio.eio.cors_allowed_origins = lambda origin, environ=None: guard.origin_allowed(origin)
    handlers = sio.handlers["/"]
    on_event = handlers["event"]

    def _log(sid: str, msg) -> None:
        if not isinstance(msg, dict):
            refused("log", "not a message")
            return
        level = msg.get("level")
        level = level if level in ("debug", "info", "warning", "error") else "warning"
        getattr(log, level)("hydroarm explore: page log: %s", printable(msg.get("message", "")))

    def _event(sid: str, msg) -> None:
        if not (
            isinstance(msg, dict)
            and isinstance(msg.get("client_id"), str)
            and isinstance(msg.get("id"), int)
            and isinstance(msg.get("args", []), list)
            and all(a is None or isinstance(a, str) for a in msg.get("args", []))
        ):
            refused("event", f"a malformed message: {printable(msg)}")
            return
        try:
            on_event(sid, msg)
        except (ValueError, TypeError, KeyError) as exc:  # its arguments not JSON, …
            refused("event", f"{type(exc).__name__}: {exc}")

    sio.on("log", _log)
    sio.on("event", _event)
    on_connect = handlers.get("connect")
    if on_connect is not None:

        async def _connect(sid: str, environ, auth=None):
            try:
                result = on_connect(sid, environ, auth)
                return await result if asyncio.iscoroutine(result) else result
            except (KeyError, TypeError, ValueError, AttributeError) as exc:
                refused("connect", f"{type(exc).__name__}: {printable(str(exc))}")
                return False

        sio.on("connect", _connect)
    for name in ("handshake", "javascript_response", "ack"):  # NiceGUI's other messages
        if name in handlers:
            sio.on(name, _checked(name, handlers[name]))


def _checked(name: str, handler: Callable):
    """A socket.io handler that takes only a message with a string ``client_id``; a malformed
    one (or one its handler cannot read) is one logged line (a handshake: refused)."""

    async def checked(sid: str, msg=None, *rest):
        if not (isinstance(msg, dict) and isinstance(msg.get("client_id"), str)):
            refused(name, f"a malformed message: {printable(msg)}")
            return False if name == "handshake" else None
        try:
            result = handler(sid, msg, *rest)
            if asyncio.iscoroutine(result):
                result = await result
            return result
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            refused(name, f"{type(exc).__name__}: {printable(str(exc))}")
            return False if name == "handshake" else None

    return checked


def _one_line(exc: Exception) -> None:
    """NiceGUI's exception handler: one line, not a traceback, for what a handler raised."""
    refused("handler", f"{type(exc).__name__}: {exc}")


def serve_page(ui, *, port: int, show: bool, host: str = "127.0.0.1", token=None) -> None:
    """Serve the pages built on NiceGUI's ``ui`` on ``host``:``port`` until interrupted
    (``show``: open the default browser), behind the `Guard`."""
    from nicegui import app, core

    hosts = allowed_hosts(host)
    app.add_middleware(Guard, hosts=hosts, token=token)
    _guard_socketio(core.sio, hosts)
    handlers = getattr(app, "_exception_handlers", None)  # NiceGUI's default: a traceback
    if isinstance(handlers, list):
        handlers[:] = [_one_line]
    else:  # pragma: no cover - another NiceGUI: its traceback, and the line
        app.on_exception(_one_line)
    if not logging.getLogger().handlers:
        logging.basicConfig(format="%(message)s", level=logging.WARNING)
    if show and token:  # NiceGUI would open the page without its token: the URL with it
        app.on_startup(lambda: webbrowser.open(page_url(host, port, token)))
    ui.run(
        host=host,
        port=port,
        show=show and not token,
        reload=False,
        title="hydroarm explore",
        show_welcome_message=False,
        uvicorn_logging_level="warning",
    )
