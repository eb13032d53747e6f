"""The MCP SDK's own client, run on a thread of its own and called synchronously.

`McpProcess(args)` spawns `python -m tui_gym mcp ARGS` and talks to it over
stdio; `McpInProcess(server)` talks to a server object in this process (for
a table with an injected clock). `call(tool, **arguments)` returns the
`CallToolResult`; `data(...)` its structured content, failing on an error;
`error(...)` its message, failing if the call was not refused.
"""

from __future__ import annotations

import asyncio
import sys
import tempfile
import threading
from typing import Any

from mcp import Client, StdioServerParameters
from mcp.client.stdio import stdio_client

CALL_TIMEOUT_S = 60.0


class _McpThread:
    def __init__(self, target: Any) -> None:
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self._thread.start()
        self._stop: asyncio.Event | None = None
        self._client: Client | None = None
        ready = asyncio.run_coroutine_threadsafe(self._enter(target), self._loop)
        self._main = ready.result(CALL_TIMEOUT_S)

    async def _enter(self, target: Any) -> asyncio.Future[None]:
        entered = asyncio.get_running_loop().create_future()
        self._stop = asyncio.Event()

        async def main() -> None:
            try:
                async with Client(target) as client:
                    self._client = client
                    entered.set_result(None)
                    await self._stop.wait()  # type: ignore[union-attr]
            except BaseException as exc:
                if not entered.done():
                    entered.set_exception(exc)
                raise

        task = asyncio.ensure_future(main())
        await entered
        return task  # type: ignore[return-value]

    def call(self, tool: str, **arguments: Any) -> Any:
        assert self._client is not None
        future = asyncio.run_coroutine_threadsafe(
            self._client.call_tool(tool, arguments), self._loop
        )
        return future.result(CALL_TIMEOUT_S)

    def data(self, tool: str, **arguments: Any) -> dict[str, Any]:
        result = self.call(tool, **arguments)
        assert not result.is_error, result.content[0].text
        return result.structured_content

    def error(self, tool: str, **arguments: Any) -> str:
        result = self.call(tool, **arguments)
        assert result.is_error, f"{tool} {arguments} was not refused: {result.structured_content}"
        return result.content[0].text

    def tools(self) -> list[str]:
        assert self._client is not None
        listed = asyncio.run_coroutine_threadsafe(self._client.list_tools(), self._loop)
        return [tool.name for tool in listed.result(CALL_TIMEOUT_S).tools]

    def close(self) -> None:
        async def stop() -> None:
            self._stop.set()  # type: ignore[union-attr]
            await self._main  # type: ignore[misc]

        try:
            asyncio.run_coroutine_threadsafe(stop(), self._loop).result(CALL_TIMEOUT_S)
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(CALL_TIMEOUT_S)
            self._loop.close()


class McpProcess(_McpThread):
    """`python -m tui_gym mcp ARGS` over stdio; its stderr is kept in `stderr_text()`."""

    def __init__(self, *args: str) -> None:
        # Kept open while the server runs; `close` closes it.
        self._errlog = tempfile.TemporaryFile("w+", encoding="utf-8")  # noqa: SIM115
        self._stderr = ""
        params = StdioServerParameters(
            command=sys.executable, args=["-m", "tui_gym", "mcp", *args]
        )
        super().__init__(stdio_client(params, errlog=self._errlog))

    def stderr_text(self) -> str:
        """What the server wrote on stderr (all of it, once closed)."""
        if self._errlog.closed:
            return self._stderr
        self._errlog.flush()
        self._errlog.seek(0)
        return self._errlog.read()

    def close(self) -> None:
        try:
            super().close()
        finally:
            self._stderr = self.stderr_text()
            self._errlog.close()


class McpInProcess(_McpThread):
    """A server object of this process, through the SDK's in-process client."""
