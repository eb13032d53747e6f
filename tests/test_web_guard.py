"""Who may open an app through `tui-gym serve`: the guard in front of textual-serve's
application, with a real aiohttp server and client on loopback. A foreign or missing
Origin is refused, the cap on live apps holds, the token holds (page and socket), and a
name other than a local one is refused when serving this machine only."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable

import aiohttp
import pytest
from aiohttp import web
from aiohttp.test_utils import TestServer

from tui_gym.web import is_local
from tui_gym.web_guard import COOKIE, ServeGuard

pytestmark = pytest.mark.xdist_group("serve")
TOKEN = "a-token-of-sixteen"


async def _socket(request: web.Request) -> web.WebSocketResponse:
    """Stands for an app: a socket held open until the client closes it."""
    ws = web.WebSocketResponse()
    await ws.prepare(request)
    await ws.send_str("app")
    async for _ in ws:
        pass
    return ws


async def _page(request: web.Request) -> web.Response:
    return web.Response(text="the page")


@pytest.fixture
async def serve() -> AsyncIterator[Callable[..., object]]:
    servers: list[TestServer] = []

    async def start(**guard: object) -> TestServer:
        app = web.Application()
        app.add_routes([web.get("/", _page), web.get("/ws", _socket)])
        app.middlewares.append(ServeGuard(**guard).middleware)  # type: ignore[arg-type]
        server = TestServer(app, host="127.0.0.1")
        await server.start_server()
        servers.append(server)
        return server

    yield start
    for server in servers:
        await server.close()


def _origin(server: TestServer) -> str:
    return f"http://127.0.0.1:{server.port}"


async def _status(client: aiohttp.ClientSession, url: str, **kwargs: object) -> int:
    try:
        async with client.ws_connect(url, **kwargs) as ws:  # type: ignore[arg-type]
            assert (await ws.receive_str()) == "app"
            return 101
    except aiohttp.WSServerHandshakeError as error:
        return error.status


async def test_a_foreign_or_missing_origin_is_refused(serve: Callable[..., object]) -> None:
    server = await serve(max_apps=4, token=None, host_allowed=is_local)  # type: ignore[misc]
    url = str(server.make_url("/ws"))
    async with aiohttp.ClientSession() as client:
        assert await _status(client, url, origin="http://evil.example") == 403
        assert await _status(client, url, origin="http://127.0.0.1:1") == 403  # another port
        assert await _status(client, url) == 403  # no Origin at all
        assert await _status(client, url, origin=_origin(server)) == 101


async def test_a_name_that_is_not_local_is_refused_when_serving_this_machine(
    serve: Callable[..., object],
) -> None:
    server = await serve(max_apps=4, token=None, host_allowed=is_local)  # type: ignore[misc]
    rebound = f"evil.example:{server.port}"  # a site's name made to resolve to 127.0.0.1
    async with aiohttp.ClientSession() as client:
        async with client.get(server.make_url("/"), headers={"Host": rebound}) as response:
            assert response.status == 403 and "this machine only" in await response.text()
        assert await _status(client, str(server.make_url("/ws")), origin=f"http://{rebound}",
                             headers={"Host": rebound}) == 403


async def test_the_cap_on_live_apps_holds(serve: Callable[..., object]) -> None:
    server = await serve(max_apps=2, token=None, host_allowed=is_local)  # type: ignore[misc]
    url = str(server.make_url("/ws"))
    async with aiohttp.ClientSession() as client:
        first = await client.ws_connect(url, origin=_origin(server))
        second = await client.ws_connect(url, origin=_origin(server))
        results = await asyncio.gather(*(_status(client, url, origin=_origin(server))
                                         for _ in range(5)))
        assert results == [503] * 5
        async with client.get(server.make_url("/")) as response:
            assert response.status == 503
            assert "2 apps are running, the most this server runs at once (--max-apps 2)" \
                in await response.text()
        await first.close()
        async with asyncio.timeout(30):
            while await _status(client, url, origin=_origin(server)) != 101:
                await asyncio.sleep(0.01)  # the closed app's place frees as its socket ends
        await second.close()


async def test_the_token_holds_on_the_page_and_the_socket(
    serve: Callable[..., object],
) -> None:
    server = await serve(max_apps=4, token=TOKEN, host_allowed=None)  # type: ignore[misc]
    url = str(server.make_url("/ws"))
    origin = _origin(server)
    async with aiohttp.ClientSession(cookie_jar=aiohttp.CookieJar(unsafe=True)) as client:
        for query in ("", "?token=wrong", f"?token={TOKEN[:-1]}"):
            async with client.get(str(server.make_url("/")) + query) as response:
                assert response.status == 401 and "needs its token" in await response.text()
        assert await _status(client, url, origin=origin) == 401
        async with client.get(server.make_url("/"), params={"token": TOKEN}) as response:
            assert response.status == 200 and await response.text() == "the page"
            assert response.cookies[COOKIE].value == TOKEN
        assert await _status(client, url, origin=origin) == 101  # the page's cookie
        assert await _status(client, url, origin="http://evil.example") == 403
    async with aiohttp.ClientSession() as stranger:
        assert await _status(stranger, url, origin=origin) == 401
        assert await _status(stranger, url + f"?token={TOKEN}", origin=origin) == 101


async def test_textual_serves_routes_are_the_same_through_the_fallback() -> None:
    pytest.importorskip("textual_serve")
    from textual_serve.server import Server

    from tui_gym.web import guarded_app

    class WithoutPrivateNames(Server):
        _make_app = None  # as if a textual-serve without it

    guard = ServeGuard(max_apps=1, token=None, host_allowed=is_local)
    stock = await guarded_app(Server("true"), guard)
    fallback = await guarded_app(WithoutPrivateNames("true"), guard)

    def routes(app: web.Application) -> list[tuple[str, str]]:
        return sorted((r.method, r.resource.canonical) for r in app.router.routes()
                      if r.resource is not None)

    assert routes(fallback) == routes(stock) and guard.middleware in fallback.middlewares
    server = TestServer(fallback, host="127.0.0.1")
    await server.start_server()
    try:
        async with aiohttp.ClientSession() as client, client.get(server.make_url("/")) as page:
            assert page.status == 200 and "data-session-websocket-url" in await page.text()
    finally:
        await server.close()
