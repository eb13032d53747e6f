"""Who may drive the apps `tui-gym serve` runs: `ServeGuard`, an aiohttp middleware letting a
websocket (an app that can touch files) through only from the page's own Origin, to a local
address when served locally (DNS rebinding), below `max_apps`, with the token if there is one."""

from __future__ import annotations

import html
import secrets
from collections.abc import Awaitable, Callable
from urllib.parse import urlsplit

from aiohttp import web

from tui_gym.core.text import visible

COOKIE = "tui_gym_token"
SOCKET_PATH = "/ws"
OPEN_PATHS = ("/static/",)  # the page's scripts, fonts and styles: nothing to guard

Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]


def _page(status: int, text: str) -> web.Response:
    body = (f"<!doctype html><meta charset=utf-8><title>tui-gym</title>"
            f"<p style='font:16px monospace;margin:2em'>{html.escape(text)}</p>\n")
    return web.Response(status=status, text=body, content_type="text/html")


class ServeGuard:
    """The middleware: `app.middlewares.append(ServeGuard(...).middleware)`."""

    def __init__(
        self, *, max_apps: int, token: str | None,
        host_allowed: Callable[[str], bool] | None = None,
    ) -> None:
        self.max_apps = max_apps
        self.token = token
        self.host_allowed = host_allowed
        self.live = 0  # apps running now (open sockets)

    @web.middleware
    async def middleware(self, request: web.Request, handler: Handler) -> web.StreamResponse:
        if request.path.startswith(OPEN_PATHS):
            return await handler(request)
        refusal = self._host_refusal(request) or self._token_refusal(request)
        if refusal is not None:
            return refusal
        if request.path == SOCKET_PATH:
            return await self._socket(request, handler)
        if request.path == "/" and self.live >= self.max_apps:
            return self._full()
        response = await handler(request)
        if self.token is not None and request.query.get("token") == self.token:
            response.set_cookie(COOKIE, self.token, httponly=True, samesite="Strict")
        return response

    async def _socket(self, request: web.Request, handler: Handler) -> web.StreamResponse:
        origin = request.headers.get("Origin")
        if origin is None or urlsplit(origin).netloc.lower() != request.host.lower():
            seen = "none" if origin is None else visible(origin, 60)
            return _page(403, f"tui-gym: only the page this server serves may open an app "
                              f"(the request's Origin: {seen})")
        if self.live >= self.max_apps:
            return self._full()
        self.live += 1
        try:
            return await handler(request)
        finally:
            self.live -= 1

    def _host_refusal(self, request: web.Request) -> web.Response | None:
        name = urlsplit(f"//{request.host}").hostname or ""  # `::1` of `[::1]:8000`
        if self.host_allowed is None or self.host_allowed(name):
            return None
        return _page(403, f"tui-gym serves this machine only; open it at a local address "
                          f"such as 127.0.0.1, not {visible(request.host, 60)}")

    def _token_refusal(self, request: web.Request) -> web.Response | None:
        token = self.token
        if token is None:
            return None
        given = request.query.get("token") or request.cookies.get(COOKIE) or ""
        if secrets.compare_digest(given.encode(), token.encode()):
            return None
        return _page(401, "tui-gym: this server needs its token: open the address "
                          "`tui-gym serve` printed, with ?token=... at its end")

    def _full(self) -> web.Response:
        noun = "app is" if self.max_apps == 1 else "apps are"
        return _page(503, f"tui-gym: {self.live} {noun} running, the most this server runs "
                          f"at once (--max-apps {self.max_apps}); close a tab with the app, "
                          "then reload this page")
