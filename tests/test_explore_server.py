"""Who may connect to ``hydroarm explore`` and what a client may send (issue 31): the guard
in front of every request (Host, Origin, the token beyond loopback) tested in-process, then a
real server driven by plain HTTP and socket.io clients (no browser): a foreign ``Host`` and a
foreign ``Origin`` are refused; a malformed lever value (``"abc"``) gives one logged line and
the page goes on; a page's ``log`` event reaches the terminal escaped."""

from __future__ import annotations

import asyncio
import json
import re
import time
import uuid
from concurrent.futures import ThreadPoolExecutor
from urllib.error import HTTPError
from urllib.request import Request, urlopen

import pytest

from hydroarm.explore.pages import (
    TOKEN_COOKIE,
    Guard,
    allowed_hosts,
    host_name,
    page_url,
    printable,
    session_token,
)

pytest.importorskip("nicegui")  # the explore extra (in the test extra)
socketio = pytest.importorskip("socketio")


# ------------------------------------------------------------------ the guard ---
def _call(guard: Guard, headers: dict, kind: str = "http", query: str = "") -> tuple:
    """Run one request through the guard: (status or close code, response headers, whether
    the app behind it was reached)."""
    reached = []
    sent: list[dict] = []

    async def app(scope, receive, send):
        reached.append(scope["path"])
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"ok"})

    async def receive():  # pragma: no cover - the guard reads no body
        return {"type": "http.request"}

    async def send(message):
        sent.append(message)

    guard.app = app
    scope = {
        "type": kind,
        "path": "/",
        "query_string": query.encode(),
        "headers": [(k.lower().encode(), v.encode()) for k, v in headers.items()],
    }
    asyncio.run(guard(scope, receive, send))
    first = sent[0]
    code = first.get("status", first.get("code"))
    return code, dict(first.get("headers", [])), bool(reached)


LOCAL = allowed_hosts("127.0.0.1")


@pytest.mark.parametrize(
    "host",
    ["127.0.0.1", "127.0.0.1:8050", "localhost:8050", "LOCALHOST", "[::1]:8050"],
)
def test_own_addresses_are_served(host):
    assert _call(Guard(None, LOCAL), {"host": host})[0] == 200


@pytest.mark.parametrize(
    "host", ["evil.example", "evil.example:8050", "127.0.0.1.evil.example", "", "10.0.0.1:80"]
)
def test_foreign_hosts_are_refused(host):
    code, _, reached = _call(Guard(None, LOCAL), {"host": host})
    assert (code, reached) == (403, False)


def test_foreign_origins_are_refused_on_http_and_websocket():
    ok = {"host": "127.0.0.1:8050", "origin": "http://127.0.0.1:8050"}
    assert _call(Guard(None, LOCAL), ok)[0] == 200
    assert _call(Guard(None, LOCAL), {**ok, "origin": "http://localhost:9999"})[0] == 200
    for origin in ("http://evil.example", "null", "http://127.0.0.1.evil.example:8050"):
        bad = {**ok, "origin": origin}
        assert _call(Guard(None, LOCAL), bad)[0] == 403, origin
        # a websocket is closed with 1008 (policy violation) before the app sees it
        assert _call(Guard(None, LOCAL), bad, kind="websocket")[:3:2] == (1008, False)


def test_the_given_host_is_served():
    hosts = allowed_hosts("192.0.2.7")
    assert _call(Guard(None, hosts), {"host": "192.0.2.7:8050"})[0] == 200
    assert _call(Guard(None, hosts), {"host": "192.0.2.8:8050"})[0] == 403


def test_a_token_beyond_loopback():
    assert session_token("127.0.0.1") is None and session_token("localhost") is None
    token = session_token("192.0.2.7")
    assert token and len(token) >= 24
    assert page_url("192.0.2.7", 8050, token) == f"http://192.0.2.7:8050/?token={token}"
    guard = Guard(None, allowed_hosts("192.0.2.7"), token)
    host = {"host": "192.0.2.7:8050"}
    assert _call(guard, host)[0] == 403  # no token
    assert _call(guard, host, query="token=wrong")[0] == 403
    code, headers, reached = _call(guard, host, query=f"token={token}")
    assert code == 200 and reached
    cookie = headers[b"set-cookie"].decode()
    assert cookie.startswith(f"{TOKEN_COOKIE}={token};") and "HttpOnly" in cookie
    # the cookie stands for the token afterwards (the page's scripts, its socket.io)
    assert _call(guard, {**host, "cookie": f"{TOKEN_COOKIE}={token}"})[0] == 200
    assert _call(guard, {**host, "cookie": f"{TOKEN_COOKIE}=x"}, kind="websocket")[0] == 1008


def test_host_names_and_printable_text():
    assert host_name("LocalHost:80") == "localhost"
    assert host_name("[::1]:8050") == "::1" and host_name("[::1") == ""
    text = printable("red \x1b[31mALERT\x1b[0m\r\nbell\x07 " + "x" * 400)
    assert "\x1b" not in text and "\r" not in text and "\x07" not in text
    assert "\\x1b[31m" in text and text.endswith("…") and len(text) <= 301
    assert printable({"a": 1}) == "{'a': 1}"


# ------------------------------------------------------------------ a real server ---
from explore_server import ExploreServer  # noqa: E402  (tests/explore_server.py)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    srv = ExploreServer("--out", str(tmp_path_factory.mktemp("explore") / "attempts")).wait()
    try:
        yield srv
    finally:
        srv.stop()


def _get(url: str, headers: dict | None = None) -> int:
    try:
        with urlopen(Request(url, headers=headers or {}), timeout=60) as r:
            return r.status
    except HTTPError as exc:
        return exc.code


def _element(updates: list, testid: str) -> tuple[int, str] | None:
    """The id and value-change listener of the element with ``data-testid`` among the
    elements the server has pushed (socket.io ``update`` messages), or None."""
    stack = list(updates)
    while stack:
        item = stack.pop()
        if not isinstance(item, dict):
            continue
        for key, el in item.items():
            if isinstance(el, dict) and el.get("props", {}).get("data-testid") == testid:
                events = [e for e in el.get("events", []) if e["type"] == "update:modelValue"]
                if str(key).isdigit() and events:
                    return int(key), events[0]["listener_id"]
            if isinstance(el, dict):
                stack.append(el)
    return None


def _tabs(html: str) -> tuple[int, str]:
    m = re.search(
        r'"(\d+)":\{"tag":"q-tabs"[^\n]*?"listener_id":"([0-9a-f-]+)","type":"update:modelValue"',
        html,
    )
    assert m
    return int(m.group(1)), m.group(2)


@pytest.mark.slow
def test_foreign_host_and_origin_are_refused(server):
    base = f"http://127.0.0.1:{server.port}/"
    assert _get(base) == 200
    assert _get(base, {"Host": f"localhost:{server.port}"}) == 200
    assert _get(base, {"Host": "evil.example"}) == 403
    assert _get(base, {"Host": f"attacker.example:{server.port}"}) == 403
    polling = f"{base}_nicegui_ws/socket.io/?EIO=4&transport=polling"
    assert _get(polling, {"Origin": "http://evil.example"}) == 403
    assert _get(polling, {"Origin": f"http://127.0.0.1:{server.port}"}) == 200

    async def connect(origin: str, query: str = "") -> bool:
        sio = socketio.AsyncClient(reconnection=False)
        try:
            await sio.connect(
                base + query, headers={"Origin": origin}, transports=["websocket"],
                socketio_path="/_nicegui_ws/socket.io", wait_timeout=30,
            )  # fmt: skip
        except socketio.exceptions.ConnectionError:
            return False
        await sio.disconnect()
        return True

    assert not asyncio.run(connect("http://evil.example"))
    assert asyncio.run(connect(f"http://127.0.0.1:{server.port}"))
    # a connection that asks for a handshake with no client: refused with one line
    err_before = len(server.err)
    assert not asyncio.run(
        connect(f"http://127.0.0.1:{server.port}", "?implicit_handshake=true&tab_id=x")
    )
    time.sleep(0.5)
    err = "".join(server.err[err_before:])
    assert "Traceback" not in err and "refused connect: KeyError" in err, err


@pytest.mark.slow
def test_visitors_arriving_together_are_all_served(server):
    """20 visits at once (the page's states built on threads, the single joint's first run
    shared): every one gets the page."""
    url = f"http://127.0.0.1:{server.port}/"
    with ThreadPoolExecutor(20) as pool:
        codes = list(pool.map(lambda _: _get(url), range(20)))
    assert codes == [200] * 20


@pytest.mark.slow
def test_a_malformed_lever_value_leaves_the_page_working(server):
    base = f"http://127.0.0.1:{server.port}"
    with urlopen(base + "/", timeout=60) as r:
        html = r.read().decode()
    client_id = re.search(r"'client_id': '([0-9a-f-]+)'", html).group(1)
    tabs, tabs_listener = _tabs(html)
    texts: list[str] = []
    updates: list = []
    err_before = len(server.err)

    async def story() -> None:
        sio = socketio.AsyncClient(reconnection=False)

        @sio.on("update")
        def update(msg):  # element updates the server pushes: keep them and their texts
            updates.append(msg)
            texts.append(json.dumps(msg, ensure_ascii=False))

        query = (
            f"client_id={client_id}&next_message_id=0&implicit_handshake=true"
            f"&document_id={uuid.uuid4()}&tab_id={uuid.uuid4()}"
        )
        await sio.connect(
            f"{base}/?{query}", transports=["websocket"],
            socketio_path="/_nicegui_ws/socket.io", wait_timeout=30,
        )  # fmt: skip

        async def event(element: int, listener: str, value) -> None:
            await sio.emit(
                "event",
                {"id": element, "client_id": client_id, "listener_id": listener,
                 "type": "update:modelValue", "args": [json.dumps(value)]},
            )  # fmt: skip

        await event(tabs, tabs_listener, "Live arm and blocks")  # the live arm steps
        deadline = time.monotonic() + 120  # its content is built when the tab first opens
        while (found := _element(updates, "lever-elbow_reach")) is None:
            assert time.monotonic() < deadline, "the live tab was not built"
            await asyncio.sleep(0.2)
        lever, lever_listener = found
        await event(lever, lever_listener, "abc")
        await sio.emit("event", ["not", "a", "message"])
        await sio.emit(
            "log", {"client_id": client_id, "level": "error", "message": "\x1b[2J\x1b]0;x\x07"}
        )
        await asyncio.sleep(3.0)  # 90 timer ticks at 30 per second: none may raise
        texts.clear()
        await event(lever, lever_listener, 60)  # the page still answers a good value
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not any(
            re.search(r"elbow_reach=([1-9]\d*\.\d+)", t) for t in texts
        ):
            await asyncio.sleep(0.2)
        await sio.disconnect()

    asyncio.run(story())
    assert any(re.search(r"elbow_reach=([1-9]\d*\.\d+)", t) for t in texts), texts[-3:]
    err = "".join(server.err[err_before:])
    assert "Traceback" not in err and "TypeError" not in err, err
    refusals = [ln for ln in err.splitlines() if "refused lever.elbow_reach" in ln]
    assert len(refusals) == 1, err  # one line, not one per tick
    assert "must be a finite number, got 'abc'" in refusals[0]
    assert "refused event: a malformed message" in err
    assert "\x1b" not in err and "\x07" not in err  # the page's log escaped
    assert "page log: \\x1b[2J\\x1b]0;x\\x07" in err


def test_a_bad_host_is_one_line(capsys):
    from hydroarm.cli import main

    for bad in ("two words", ""):
        assert main(["explore", "--host", bad, "--no-browser"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"hydroarm: error: --host: must be a host name or address, got {bad!r}"]
