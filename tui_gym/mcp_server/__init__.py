"""`tui-gym mcp`: the games as tools of a Model Context Protocol server over stdio.

`command` holds the sub-command (it runs without the MCP SDK installed, to say
how to install it); `server` builds the server on the SDK's `MCPServer`, with
the tools over a `GameTable` of the arena (`tui_gym.session.arena`).
"""

INSTALL_HINT = "tui-gym mcp needs the MCP SDK: pip install 'tui-gym[mcp]'"
