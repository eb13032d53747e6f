"""`tui-gym serve`: the app in a browser tab, through textual-serve (the `web` extra)."""

from __future__ import annotations

import argparse
import ipaddress
import secrets
import shlex
import sys
from typing import TYPE_CHECKING, Any

from rich.console import Console

from tui_gym.cli.flags import int_in as _int_in
from tui_gym.cli.output import CliError

if TYPE_CHECKING:
    from aiohttp import web

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8000
DEFAULT_MAX_APPS = 4
INSTALL_HINT = "pip install 'tui-gym[web]'"


def is_local(host: str) -> bool:
    """Whether `host` is this machine only: `localhost` or a loopback address."""
    name = host.strip().strip("[]").lower()
    if name == "localhost" or name.endswith(".localhost"):
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def add_serve_parser(sub: Any) -> None:
    """The `serve` sub-command."""
    serve = sub.add_parser(
        "serve", help="serve the app in a browser (needs the web extra)",
        description="Serve the app in a browser tab, one app per tab, through textual-serve. "
        "Options before `serve` (--env, --seed, --load, --map-file, --runner, --db, "
        "--no-history) open each tab's app.",
    )
    serve.add_argument("--host", default=DEFAULT_HOST,
                       help=f"address to listen on (default {DEFAULT_HOST}: this machine only)")
    serve.add_argument("--port", type=_int_in(1, 65535, "a port number from 1 to 65535"),
                       default=DEFAULT_PORT, help=f"port to listen on (default {DEFAULT_PORT})")
    serve.add_argument("--public", action="store_true",
                       help="allow a --host that other machines can reach (with a token)")
    serve.add_argument("--token", metavar="TOKEN",
                       help="the token the page needs (?token=TOKEN); --public makes one up "
                       "and prints it when none is given")
    serve.add_argument("--max-apps", type=_int_in(1, 64, "a number of apps from 1 to 64"),
                       default=DEFAULT_MAX_APPS, metavar="N",
                       help=f"apps (browser tabs) running at once, at most (default "
                       f"{DEFAULT_MAX_APPS})")


def app_command(args: argparse.Namespace) -> str:
    """The shell command that runs one app for one browser tab."""
    command = [sys.executable, "-m", "tui_gym", "--env", args.env, "--runner", args.runner]
    if args.seed is not None:  # else each tab draws its own
        command += ["--seed", str(args.seed)]
    for flag, value in (("--load", args.load), ("--map-file", args.app_map_file),
                        ("--db", args.db)):
        if value:
            command += [flag, str(value)]
    if args.no_history:
        command.append("--no-history")
    return shlex.join(command)


def cmd_serve(args: argparse.Namespace, out: Console) -> int:
    if args.record is not None:
        raise CliError("--record records the app in this terminal; it does not go with serve")
    if not args.host.strip():
        raise CliError("--host is empty: give an address such as 127.0.0.1")
    if not args.public and not is_local(args.host):
        raise CliError(
            f"--host {args.host} is not a local address: anyone who can reach it could use the "
            "app, which reads and writes files here; add --public to serve it there anyway"
        )
    token = args.token
    if token is not None and len(token.strip()) < 8:
        raise CliError("--token must be at least 8 characters: anyone could guess a shorter "
                       "one (leave it out and --public makes one up)")
    if token is None and args.public:
        token = secrets.token_urlsafe(16)  # 128 random bits, URL-safe
    from tui_gym.cli.flags import app_env

    app_env(args)  # a file that cannot be opened is said now, not in each tab
    if args.load:
        from tui_gym.session.session import Session

        Session.load(args.load)
    try:
        from textual_serve.server import Server
    except ImportError:
        raise CliError(f"tui-gym serve needs textual-serve: {INSTALL_HINT}") from None
    from tui_gym.web_guard import ServeGuard

    guard = ServeGuard(max_apps=args.max_apps, token=token,
                       host_allowed=None if args.public else is_local)

    class AppServer(Server):
        """textual-serve's server, saying what it serves and to whom in its own words."""

        async def on_startup(self, app: web.Application) -> None:
            """Nothing: what is served is said once the port listens (`serve`)."""

        def serve(self, debug: bool = False) -> None:
            import asyncio
            import logging
            import signal

            from aiohttp import web

            self.debug = debug
            logging.basicConfig(level=logging.WARNING, format="%(message)s")
            loop = asyncio.new_event_loop()
            for signal_number in (signal.SIGINT, signal.SIGTERM):
                loop.add_signal_handler(signal_number, self.request_exit)
            web.run_app(
                guarded_app(self, guard), host=self.host, port=self.port,
                handle_signals=False, loop=loop,
                print=lambda *_: say_serving(args.host, args.port, token),
            )

        async def handle_index(self, request: web.Request) -> Any:
            # The page's links (its websocket above all) go where the browser went; the
            # page is drawn with no await in between, so no other request sees this one's.
            self.public_url = f"{request.scheme}://{request.host}"
            return await super().handle_index(request)

    server = AppServer(app_command(args), host=args.host, port=args.port, title="tui-gym")
    server.serve()
    return 0


async def guarded_app(server: Any, guard: Any) -> web.Application:
    """textual-serve's aiohttp application with `guard`'s middleware in front."""
    # textual-serve's private `_make_app` builds its application (routes, templates); the
    # one private name used here. Without it, the same routes on its public handlers.
    make = getattr(server, "_make_app", None)
    app = await make() if make is not None else _public_app(server)
    app.middlewares.append(guard.middleware)
    return app


def _public_app(server: Any) -> web.Application:
    """textual-serve's routes, built from its public handlers (see `guarded_app`)."""
    import aiohttp_jinja2
    import jinja2
    from aiohttp import web

    app = web.Application()
    aiohttp_jinja2.setup(app, loader=jinja2.FileSystemLoader(server.templates_path))
    app.add_routes([
        web.get("/", server.handle_index, name="index"),
        web.get("/ws", server.handle_websocket, name="websocket"),
        web.get("/download/{key}", server.handle_download, name="download"),
        web.static("/static", server.statics_path, name="static"),
    ])
    return app


def say_serving(host: str, port: int, token: str | None = None) -> None:
    """The line that says the server listens: where, and to whom."""
    try:
        shown = f"[{host}]" if ipaddress.ip_address(host.strip("[]")).version == 6 else host
    except ValueError:
        shown = host
    url = f"http://{shown}:{port}" + (f"/?token={token}" if token else "")
    who = "on this machine only" if is_local(host) else (
        "to anyone who can reach this machine (--public)"
    )
    if token:
        who += ", with its token"
    sys.stdout.write(f"Serving tui-gym at {url} {who}. Open it in a browser; "
                     "each tab runs its own app. Ctrl+C stops.\n")
    sys.stdout.flush()
