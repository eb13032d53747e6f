#!/usr/bin/env python3
"""A short MCP session with `tui-gym mcp`, through the MCP SDK's own client.

It starts the server over stdio, plays two Blackjack hands (one against the
hint, one with it), and prints each tool call and its answer, with a few
bookkeeping fields left out:

    python examples/mcp_client.py

Needs the mcp extra: pip install 'tui-gym[mcp]'.
"""

import json
import sys

import anyio
from mcp import Client, StdioServerParameters

LEFT_OUT = ("game", "info", "terminated", "truncated", "last_reward", "recent_episodes")


async def main():
    server = StdioServerParameters(command=sys.executable, args=["-m", "tui_gym", "mcp"])
    async with Client(server) as client:

        async def call(tool, **arguments):
            print(f"> {tool} {json.dumps(arguments)}")
            result = await client.call_tool(tool, arguments)
            if result.is_error:
                print(f"error: {result.content[0].text}")
                return None
            answer = result.structured_content
            shown = {k: v for k, v in answer.items() if k not in LEFT_OUT}
            print(json.dumps(shown)[:-1] + (", ...}" if len(shown) < len(answer) else "}"))
            return answer

        games = (await client.call_tool("list_games")).structured_content["games"]
        print("> list_games {}")
        print("games:", ", ".join(f"{g['name']} ({', '.join(g['actions'])})" for g in games))
        game = await call("start_game", game="blackjack", seed=7)
        game_id = game["game_id"]
        hint = await call("hint", game_id=game_id)
        worst = min(hint["action_values"], key=hint["action_values"].get)
        await call("step", game_id=game_id, action=worst)
        await call("step", game_id=game_id, action="stick")
        await call("score", game_id=game_id)
        await call("reset", game_id=game_id)
        hint = await call("hint", game_id=game_id)
        await call("step", game_id=game_id, action=hint["optimal_actions"][0])
        await call("end_game", game_id=game_id)


if __name__ == "__main__":
    anyio.run(main)
