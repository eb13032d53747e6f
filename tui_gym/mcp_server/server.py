"""The MCP server: each tool a thin call into a `GameTable` of the arena (coroutines that
never wait, so the table needs no lock; with `hints` off, verdicts hide until an episode ends)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Annotated, Any

import anyio
from mcp.server.mcpserver import MCPServer
from mcp.server.mcpserver.exceptions import ToolError
from mcp.server.stdio import stdio_server
from mcp.types import CallToolResult, TextContent
from pydantic import Field, StrictInt, StrictStr, ValidationError

from tui_gym import __version__
from tui_gym.core.params import shown_value
from tui_gym.core.text import visible
from tui_gym.mcp_server.pipes import open_pipes
from tui_gym.session.arena import GameTable, Seat, SeatError, TableError, catalog

INSTRUCTIONS = """\
Games of tui-gym (Blackjack, GridWorld, ...) to play move by move, scored against the exact
optimum. Call list_games for the games, their parameters and action names; start_game returns
a game id and the first observation; step plays an action (by name or number); reset deals a
new episode; score gives the returns per episode and the exact decision regret (the expected
return each move gave up against the optimal move). Idle games expire."""

GameId = Annotated[StrictInt, Field(description="the id start_game returned")]
Seed = StrictInt | None
MESSAGE_CHARS = 300  # a refusal's length at most: it may quote what the call sent


def _result(data: dict[str, Any]) -> CallToolResult:
    """A tool's answer: the data as structured content, and as compact JSON text for
    clients that read text (no output schema, so neither side re-validates it)."""
    return CallToolResult(
        content=[TextContent(type="text", text=json.dumps(data))], structured_content=data
    )


@contextmanager
def _refusing(*errors: type[Exception]) -> Iterator[None]:
    """One of `errors` raised in the block, as the tool's refusal in one line."""
    try:
        yield
    except errors as exc:
        raise ToolError(visible(" ".join(str(exc).split()), MESSAGE_CHARS)) from None


class _Server(MCPServer):
    """The SDK's server, answering arguments of the wrong type in one line."""

    async def call_tool(self, name: str, arguments: dict[str, Any], context: Any = None) -> Any:
        try:
            return await super().call_tool(name, arguments, context)
        except ToolError as exc:
            if not isinstance(exc.__cause__, ValidationError):
                raise
            raise ToolError(await self._argument_error(name, exc.__cause__)) from None

    async def _argument_error(self, tool: str, error: ValidationError) -> str:
        """`step: argument action takes an action's name or number, not True`."""
        first = error.errors()[0]
        argument = str(first["loc"][0]) if first["loc"] else "?"
        schema = next((t.input_schema for t in await self.list_tools() if t.name == tool), {})
        properties = schema.get("properties", {})
        described = properties.get(argument, {}).get("description")
        if first["type"] == "missing":
            what = f"is missing ({described})" if described else "is missing"
        elif described is None:
            what = f"is not one this tool takes ({', '.join(properties)})"
        else:
            what = f"takes {described}, not {shown_value(first.get('input'))}"
        return f"Error executing tool {tool}: argument {visible(argument, 40)} {what}"


def build_server(table: GameTable, *, hints: bool = True) -> MCPServer:
    """An `MCPServer` whose tools play the games of `table`."""
    server: MCPServer = _Server(
        name="tui-gym", instructions=INSTRUCTIONS, version=__version__, log_level="WARNING",
    )

    def seat_of(game_id: int) -> Seat:
        with _refusing(TableError):
            return table.get(game_id)

    def state(game_id: int, seat: Seat) -> dict[str, Any]:
        return {"game_id": game_id, "game": seat.entry.name, **seat.observe()}

    def final(game_id: int, seat: Seat) -> CallToolResult:
        return _result({"game_id": game_id, "game": seat.entry.name,
                        **seat.score.to_json(running=hints)})

    @server.tool()
    async def list_games() -> CallToolResult:
        """The games: name, parameters (type, default, range) and action names."""
        return _result({
            "games": [entry.to_json() for entry in catalog()], "hints": hints,
            "max_games": table.max_games, "idle_timeout_seconds": table.idle_timeout,
        })

    @server.tool()
    async def start_game(
        game: Annotated[
            StrictStr, Field(description="a game name from list_games, e.g. 'blackjack'")
        ],
        parameters: Annotated[
            dict[str, Any] | None,
            Field(description="the game's parameters by name, e.g. {'size': 6}; defaults if "
                  "omitted"),
        ] = None,
        seed: Annotated[Seed, Field(
            description="a whole number >= 0, the first episode's seed (random if omitted)", ge=0,
        )] = None,
        wrappers: Annotated[
            list[StrictStr] | None,
            Field(description="a list of Gymnasium wrappers as 'Name' or 'Name:key=value', "
                  "innermost first"),
        ] = None,
    ) -> CallToolResult:
        """Start a game and deal its first episode; its game id and first observation."""
        with _refusing(TableError, SeatError, ValueError):
            game_id, seat = table.start(game, parameters, seed, wrappers or ())
        return _result(state(game_id, seat))

    @server.tool()
    async def observe(game_id: GameId) -> CallToolResult:
        """The state: as data and as text, the legal actions, and whether the episode is done."""
        return _result(state(game_id, seat_of(game_id)))

    @server.tool()
    async def step(
        game_id: GameId,
        action: Annotated[StrictInt | StrictStr, Field(description="an action's name or number")],
    ) -> CallToolResult:
        """Play one action; returns the new state, the reward and whether the episode is done."""
        seat = seat_of(game_id)
        with _refusing(SeatError):
            answer, verdict = seat.step(action)
        data = state(game_id, seat)
        data["reward"] = answer["reward"]
        if hints:
            data["verdict"] = verdict.to_json()
        return _result(data)

    @server.tool()
    async def reset(
        game_id: GameId,
        seed: Annotated[
            Seed, Field(description="a whole number >= 0, the new episode's seed (the game's own "
                  "sequence goes on if omitted)", ge=0)
        ] = None,
    ) -> CallToolResult:
        """Deal a new episode of the game (an unfinished one is left out of the score)."""
        seat = seat_of(game_id)
        with _refusing(SeatError):
            seat.reset(seed)
        return _result(state(game_id, seat))

    @server.tool()
    async def hint(game_id: GameId) -> CallToolResult:
        """The exact optimum here: the optimal actions and each action's exact expected return."""
        if not hints:
            raise ToolError("hints are off on this server (it was started with --no-hints)")
        seat = seat_of(game_id)
        with _refusing(SeatError):
            return _result({"game_id": game_id, **seat.hint()})

    @server.tool()
    async def score(game_id: GameId) -> CallToolResult:
        """Returns per episode, exact decision regret so far, decisions and agreement."""
        return final(game_id, seat_of(game_id))

    @server.tool()
    async def end_game(game_id: GameId) -> CallToolResult:
        """End a game and free its place; returns its final score."""
        with _refusing(TableError):
            seat = table.end(game_id)
        return final(game_id, seat)

    return server


async def serve_stdio(server: MCPServer) -> None:
    """Serve on stdin/stdout until the client closes them: on the event loop where they
    are pipes (`pipes`), else through the SDK's own stdio transport."""
    lowlevel = getattr(server, "_lowlevel_server", None)
    async with open_pipes() as pipes:
        if pipes is None or lowlevel is None:
            await server.run_stdio_async()
            return
        lines, writer = pipes
        async with stdio_server(stdin=lines, stdout=writer) as (read_stream, write_stream):  # type: ignore[arg-type]
            await lowlevel.run(read_stream, write_stream, lowlevel.create_initialization_options())


def run(max_games: int, idle_timeout: float, hints: bool) -> None:
    """Serve on stdin/stdout until the client closes them."""
    table = GameTable(max_games=max_games, idle_timeout=idle_timeout)
    try:
        anyio.run(serve_stdio, build_server(table, hints=hints))
    finally:
        table.close()
