"""Stdin and stdout as event-loop streams, for the MCP server's stdio transport."""

from __future__ import annotations

import asyncio
import os
import stat
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

MAX_LINE_BYTES = 16 << 20  # one JSON-RPC message a line; longer lines are dropped


async def pipe_lines(reader: asyncio.StreamReader) -> AsyncIterator[str]:
    """The lines of a pipe as text, for `async for` (the SDK reads stdin that way)."""
    while True:
        try:
            line = await reader.readuntil(b"\n")
        except asyncio.IncompleteReadError as exc:  # the end, maybe with an unended line
            if not exc.partial:
                return
            line = exc.partial
        except asyncio.LimitOverrunError as exc:  # too long to be a message: drop it
            await reader.readexactly(exc.consumed)
            continue
        yield line.decode("utf-8", errors="replace")


class PipeWriter:
    """Text written to a pipe; `flush` waits while the reader is behind."""

    def __init__(self, writer: asyncio.StreamWriter) -> None:
        self._writer = writer

    async def write(self, text: str) -> None:
        self._writer.write(text.encode("utf-8"))

    async def flush(self) -> None:
        await self._writer.drain()


def _is_pipe(fd: int) -> bool:
    try:
        return stat.S_ISFIFO(os.fstat(fd).st_mode)
    except OSError:
        return False


@asynccontextmanager
async def open_pipes() -> AsyncIterator[tuple[AsyncIterator[str], PipeWriter] | None]:
    """Stdin's lines and a writer on stdout, or None when they are not both pipes."""
    if not (_is_pipe(0) and _is_pipe(1)):
        yield None
        return
    loop = asyncio.get_running_loop()
    wire_in, wire_out = os.dup(0), os.dup(1)
    saved_in, saved_out = os.dup(0), os.dup(1)
    null = os.open(os.devnull, os.O_RDONLY)
    os.dup2(null, 0)
    os.close(null)
    os.dup2(2, 1)
    reader = asyncio.StreamReader(limit=MAX_LINE_BYTES)
    read_pipe = os.fdopen(wire_in, "rb", buffering=0)
    write_pipe = os.fdopen(wire_out, "wb", buffering=0)
    read_transport, _ = await loop.connect_read_pipe(
        lambda: asyncio.StreamReaderProtocol(reader), read_pipe
    )
    write_transport, protocol = await loop.connect_write_pipe(
        asyncio.streams.FlowControlMixin, write_pipe
    )
    writer = asyncio.StreamWriter(write_transport, protocol, None, loop)
    try:
        yield pipe_lines(reader), PipeWriter(writer)
    finally:
        read_transport.close()
        write_transport.close()
        os.dup2(saved_in, 0)
        os.dup2(saved_out, 1)
        os.close(saved_in)
        os.close(saved_out)
