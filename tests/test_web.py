"""`tui-gym serve`: one server on a free loopback port; its page over HTTP, a keypress through
its websocket, and (where Debian's Chromium is installed) the page in a headless browser.

Every address used is a loopback one; each wait is bounded and ends on the condition it
waits for.
"""

from __future__ import annotations

import asyncio
import base64
import json
import os
import re
import select
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import aiohttp  # textual-serve's own client library; the test extra installs the web extra
import pytest

from tui_gym.cli import main

pytestmark = pytest.mark.xdist_group("serve")  # one server for the module, on one worker

CHROMIUM = Path("/usr/bin/chromium")
START_SECONDS = 60  # generous: the machine may be busy
WAIT_SECONDS = 60


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def read_line(stream: Any, deadline: float) -> str:
    """One line of a child's output, or "" when none came before `deadline`."""
    remaining = deadline - time.monotonic()
    if remaining <= 0 or not select.select([stream], [], [], remaining)[0]:
        return ""
    return stream.readline().decode("utf-8", "replace")


def stop(process: subprocess.Popen[bytes]) -> None:
    """End a server as ctrl+c does (killed if it does not end in time)."""
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=15)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """`tui-gym serve` on a free port; its URL."""
    port = free_port()
    folder = tmp_path_factory.mktemp("serve")
    process = subprocess.Popen(
        [sys.executable, "-m", "tui_gym", "--runner", "thread", "serve", "--port", str(port)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=folder,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])},
    )
    try:
        deadline = time.monotonic() + START_SECONDS
        said = ""
        while "Serving tui-gym" not in said and process.poll() is None:
            line = read_line(process.stdout, deadline)
            if not line:
                break
            said += line
        assert f"Serving tui-gym at http://127.0.0.1:{port} on this machine only." in said, said
        yield f"http://127.0.0.1:{port}"
    finally:
        stop(process)


async def read_until(ws: Any, wanted: bytes, seen: bytearray) -> None:
    """Add what the app draws to `seen` until `wanted` is in it."""
    async with asyncio.timeout(WAIT_SECONDS):
        while wanted not in seen:
            message = await ws.receive()
            if message.type == aiohttp.WSMsgType.BINARY:
                seen += message.data
            elif message.type != aiohttp.WSMsgType.TEXT:
                raise AssertionError(f"the websocket closed: {message!r}")


async def test_the_page_is_served_and_a_key_reaches_the_app(server: str) -> None:
    async with aiohttp.ClientSession() as client:
        async with client.get(server + "/") as response:
            assert response.status == 200
            page = await response.text()
        ws_url = server.replace("http://", "ws://") + "/ws"
        assert f'data-session-websocket-url="{ws_url}"' in page
        for origin in ("http://evil.example", None):  # another site's page, or no page
            with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                await client.ws_connect(ws_url, origin=origin)
            assert refused.value.status == 403
        async with client.ws_connect(ws_url + "?width=80&height=24", origin=server) as ws:
            seen = bytearray()
            await read_until(ws, b"tui-gym", seen)  # the app's title in its header
            seen.clear()
            await ws.send_str(json.dumps(["stdin", "?"]))
            await read_until(ws, b"tui-gym keys", seen)  # the help screen it opens


class Devtools:
    """Just enough of Chromium's DevTools protocol: calls, and the events they bring."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.calls = 0
        self.waiting: dict[int, asyncio.Future[dict[str, Any]]] = {}
        self.events: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
        self.reader = asyncio.ensure_future(self._read())

    async def _read(self) -> None:
        async for message in self.ws:
            data = json.loads(message.data)
            future = self.waiting.pop(data.get("id", -1), None)
            if future is not None:
                future.set_result(data)
            else:
                self.events.put_nowait(data)

    async def call(self, method: str, session: str | None = None, **params: Any) -> Any:
        self.calls += 1
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self.waiting[self.calls] = future
        request: dict[str, Any] = {"id": self.calls, "method": method, "params": params}
        if session:
            request["sessionId"] = session
        await self.ws.send_str(json.dumps(request))
        answer = await future
        assert "error" not in answer, answer
        return answer.get("result", {})


@pytest.mark.skipif(not CHROMIUM.exists(), reason="Debian's chromium is not installed")
async def test_the_page_shows_the_app_in_a_headless_browser(
    server: str, tmp_path: Path
) -> None:
    browser = await asyncio.create_subprocess_exec(
        str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        # Only this machine: every other name resolves to nothing (the page asks for a font).
        "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
        "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=0",
        f"--user-data-dir={tmp_path}", "--window-size=800,600", "about:blank",
        stdout=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.PIPE,
    )
    try:
        assert browser.stderr is not None
        endpoint = None
        async with asyncio.timeout(START_SECONDS):
            while endpoint is None:
                line = (await browser.stderr.readline()).decode("utf-8", "replace")
                assert line, "chromium ended before it listened"
                found = re.search(r"DevTools listening on (ws://127\.0\.0\.1:\d+/\S+)", line)
                endpoint = found.group(1) if found else None
        async with aiohttp.ClientSession() as client, client.ws_connect(
            endpoint, max_msg_size=0
        ) as ws:
            tools = Devtools(ws)
            target = (await tools.call("Target.createTarget", url="about:blank"))["targetId"]
            session = (await tools.call("Target.attachToTarget", targetId=target,
                                        flatten=True))["sessionId"]
            await tools.call("Network.enable", session)
            await tools.call("Page.navigate", session, url=server + "/")
            drawn = bytearray()
            async with asyncio.timeout(WAIT_SECONDS):
                while b"tui-gym" not in drawn:  # the app's title, drawn in the page
                    event = await tools.events.get()
                    if event.get("method") != "Network.webSocketFrameReceived":
                        continue
                    frame = event["params"]["response"]
                    if frame.get("opcode") == 2:
                        drawn += base64.b64decode(frame["payloadData"])
            await tools.call("Browser.close")
            tools.reader.cancel()
    finally:
        if browser.returncode is None:
            browser.kill()
        await browser.wait()


def test_serve_refuses_a_public_host_and_says_how_to_install_the_extra(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    assert main(["serve", "--host", "0.0.0.0"]) == 2
    assert capsys.readouterr().err == (
        "tui-gym: error: --host 0.0.0.0 is not a local address: anyone who can reach it "
        "could use the app, which reads and writes files here; add --public to serve it "
        "there anyway\n"
    )
    monkeypatch.setitem(sys.modules, "textual_serve.server", None)  # as if not installed
    assert main(["serve", "--host", "0.0.0.0", "--public"]) == 2
    assert capsys.readouterr().err == (
        "tui-gym: error: tui-gym serve needs textual-serve: pip install 'tui-gym[web]'\n"
    )
    assert main(["--record", "x.jsonl", "serve"]) == 2
    assert "does not go with serve" in capsys.readouterr().err
    assert main(["serve", "--host", "0.0.0.0", "--public", "--token", "short"]) == 2
    assert "--token must be at least 8 characters" in capsys.readouterr().err


def test_public_serves_with_a_token_it_makes_up_and_prints(tmp_path: Path) -> None:
    port = free_port()
    process = subprocess.Popen(
        [sys.executable, "-m", "tui_gym", "serve", "--host", "127.0.0.1", "--public",
         "--port", str(port)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])},
    )
    try:
        said = read_line(process.stdout, time.monotonic() + START_SECONDS)
        found = re.search(rf"at http://127\.0\.0\.1:{port}/\?token=([\w-]{{20,}}) on this "
                          r"machine only, with its token\.", said)
        assert found, said

        async def pages() -> tuple[int, int]:
            async with aiohttp.ClientSession() as client:
                base = f"http://127.0.0.1:{port}/"
                async with client.get(base) as without, \
                        client.get(base, params={"token": found.group(1)}) as with_token:
                    return without.status, with_token.status

        assert asyncio.run(pages()) == (401, 200)
    finally:
        stop(process)


@pytest.mark.parametrize(
    ("host", "local"),
    [("127.0.0.1", True), ("127.8.0.2", True), ("localhost", True), ("::1", True),
     ("[::1]", True), ("0.0.0.0", False), ("192.168.1.4", False), ("example.org", False),
     ("::", False)],
)
def test_which_hosts_are_this_machine_only(host: str, local: bool) -> None:
    from tui_gym.web import is_local

    assert is_local(host) is local


def test_each_tab_draws_its_own_seed_unless_one_is_given() -> None:
    from tui_gym.cli.main import build_parser
    from tui_gym.web import app_command

    parser = build_parser()
    assert "--seed" not in app_command(parser.parse_args(["serve"]))
    assert "--seed 7" in app_command(parser.parse_args(["--seed", "7", "serve"]))
