"""The layers, read from the source: which package may import what, and no cycles.

Every module of `tui_gym` is parsed (not imported) and its imports collected,
those inside functions included (a lazy import is still a dependency) and
those under `if TYPE_CHECKING:` left out (they never run). Then:

- nothing under `core/`, `games/`, `algorithms/` or `envs/` imports `textual`;
- nothing under `ui/` imports `gymnasium`;
- the layers of DESIGN.md: `core/` imports neither games, algorithms, the
  composition (`session/`) nor a front end (`ui/`, `cli/`); `games/` and
  `algorithms/` import neither the composition nor a front end; `session/`
  imports no front end;
- nothing outside `games/` and `envs/` names a game: no game's module is
  imported from outside `games/` (the registry is the way in);
- the modules of `tui_gym` import one another without cycles.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

# One worker runs this module, so the import graph below is read once.
pytestmark = pytest.mark.xdist_group("imports")

ROOT = Path(__file__).resolve().parent.parent / "tui_gym"
NO_TEXTUAL = ("core", "games", "algorithms", "envs")
GAME_PACKAGES = ("blackjack", "gridworld", "frozenlake", "cliffwalking", "taxi")


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(path: Path) -> set[str]:
    """Every module `path` imports, at any depth, outside `if TYPE_CHECKING:` blocks."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path).rpartition(
        "."
    )[0]
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                module = f"{base}.{node.module}" if node.module else base
            else:
                module = node.module or ""
            found.add(module)
            # `from package import submodule` imports the submodule.
            found.update(f"{module}.{alias.name}" for alias in node.names)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for p in ROOT.rglob("*.py")}
    return {name: _imports(path) for name, path in modules.items()}


def _top(name: str) -> str:
    return name.split(".")[0]


def test_core_games_algorithms_and_envs_never_import_textual(graph) -> None:
    offenders = sorted(
        f"{module} imports {imported}"
        for module, imported_set in graph.items()
        for imported in imported_set
        if module.split(".")[1:2] and _layer(module) in NO_TEXTUAL and _top(imported) == "textual"
    )
    assert not offenders, offenders


def test_the_ui_never_imports_gymnasium(graph) -> None:
    offenders = sorted(
        f"{module} imports {imported}"
        for module, imported_set in graph.items()
        for imported in imported_set
        if _layer(module) == "ui" and _top(imported) == "gymnasium"
    )
    assert not offenders, offenders


def test_no_game_module_is_imported_from_outside_games(graph) -> None:
    offenders = sorted(
        f"{module} imports {imported}"
        for module, imported_set in graph.items()
        for imported in imported_set
        if _layer(module) != "games"
        and imported.startswith("tui_gym.games.")
        and imported.split(".")[2] in GAME_PACKAGES
    )
    assert not offenders, offenders


# Which layers each layer may not import (DESIGN.md's rules of the house).
FORBIDDEN = {
    "core": ("games", "algorithms", "session", "ui", "cli"),
    "games": ("session", "ui", "cli"),
    "algorithms": ("session", "ui", "cli"),
    "session": ("ui", "cli"),
}


def test_the_layers_import_only_downwards(graph) -> None:
    offenders = sorted(
        f"{module} imports {imported}"
        for module, imported_set in graph.items()
        for imported in imported_set
        if imported.startswith("tui_gym.") and _layer(imported) in FORBIDDEN.get(_layer(module), ())
    )
    assert not offenders, offenders


def _layer(module: str) -> str:
    parts = module.split(".")
    if len(parts) > 2 and parts[1] == "core":
        return "core"
    return parts[1] if len(parts) > 1 else ""


def test_the_modules_import_one_another_without_cycles(graph) -> None:
    # An import of a name that is not a module (`from tui_gym.games import GAMES`) is an
    # import of the package it comes from.
    def resolve(name: str) -> str | None:
        while name and name not in graph:
            name = name.rpartition(".")[0]
        return name or None

    edges = {
        module: {target for imported in imported_set
                 if (target := resolve(imported)) is not None and target != module}
        for module, imported_set in graph.items()
    }
    cycles = _strongly_connected(edges)
    assert not cycles, [" -> ".join(sorted(c)) for c in cycles]


def _strongly_connected(edges: dict[str, set[str]]) -> list[set[str]]:
    """Tarjan's algorithm: the components of more than one module."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    counter = [0]

    def connect(node: str) -> None:
        index[node] = low[node] = counter[0]
        counter[0] += 1
        stack.append(node)
        on_stack.add(node)
        for nxt in edges.get(node, ()):
            if nxt not in index:
                connect(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = set()
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.add(top)
                if top == node:
                    break
            if len(component) > 1:
                found.append(component)

    for node in edges:
        if node not in index:
            connect(node)
    return found
