"""The package's shape: no import cycle (function-level imports included), small modules."""

from __future__ import annotations

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent
PACKAGES = {
    "src/rrtdrive": "rrtdrive", "envs": "rrtdrive.envs", "controllers": "rrtdrive.controllers"
}
#: "About 600 lines at most" (STYLE, issue #11).
MAX_LINES = 600


def _modules() -> dict[str, pathlib.Path]:
    mods = {}
    for folder, package in PACKAGES.items():
        for path in (ROOT / folder).rglob("*.py"):
            parts = [p for p in path.relative_to(ROOT / folder).with_suffix("").parts]
            parts = [p for p in parts if p != "__init__"]
            mods[".".join([package, *parts])] = path
    return mods


def _imports(path: pathlib.Path, mods: dict[str, pathlib.Path]) -> set[str]:
    """Modules of the package that ``path`` imports anywhere (type-checking-only excluded)."""
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            node.body = []

    def resolve(name: str) -> str | None:
        while name:
            if name in mods:
                return name
            name = name.rpartition(".")[0]
        return None

    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            for alias in node.names:
                target = resolve(f"{node.module}.{alias.name}")
                if target:
                    out.add(target)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                target = resolve(alias.name)
                if target:
                    out.add(target)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            # A module loaded by name: importlib.import_module("rrtdrive.x") or a
            # "rrtdrive.x:function" builder string (the CLI's subcommands).
            name = node.value.partition(":")[0]
            if name in mods:
                out.add(name)
    return out


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle of ``graph`` (module -> imported modules), or ``None``."""
    colour: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        colour[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if colour.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in colour and (found := visit(nxt)):
                return found
        stack.pop()
        colour[node] = 2
        return None

    for name in sorted(graph):
        if name not in colour and (found := visit(name)):
            return found
    return None


def test_no_import_cycle_anywhere():
    mods = _modules()
    # A package importing its own submodules (re-exports) is not a dependency of
    # the package on itself; every other edge counts, lazy imports included.
    graph = {
        name: {t for t in _imports(path, mods) if t != name and not t.startswith(name + ".")}
        for name, path in mods.items()
    }
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_a_lazy_import_cycle_would_be_found(tmp_path):
    a = tmp_path / "a.py"
    b = tmp_path / "b.py"
    a.write_text("def f():\n    from rrtdrive.b import g\n")
    b.write_text("if True:\n    import rrtdrive.a\n")
    mods = {"rrtdrive.a": a, "rrtdrive.b": b}
    graph = {name: _imports(path, mods) for name, path in mods.items()}
    assert find_cycle(graph) == ["rrtdrive.a", "rrtdrive.b", "rrtdrive.a"]
    assert find_cycle({"x": {"y"}, "y": set()}) is None
    # Loaded by name (the CLI's subcommand builders), and imported back in a function.
    a.write_text('BUILDER = "rrtdrive.b:add_parser"\n')
    b.write_text("def add_parser():\n    from rrtdrive.a import BUILDER\n")
    graph = {name: _imports(path, mods) for name, path in mods.items()}
    assert find_cycle(graph) == ["rrtdrive.a", "rrtdrive.b", "rrtdrive.a"]


def test_modules_stay_small():
    big = {
        str(path.relative_to(ROOT)): n
        for path in _modules().values()
        if (n := len(path.read_text().splitlines())) > MAX_LINES
    }
    assert not big, f"modules over {MAX_LINES} lines: {big}"


def test_every_package_is_installed():
    # setuptools installs only the packages pyproject.toml lists: a new subpackage left
    # out works in the editable checkout and is missing from a regular `pip install .`.
    import tomllib

    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setuptools["packages"])
    found = set()
    for init in (ROOT / "src" / "rrtdrive").rglob("__init__.py"):
        rel = init.parent.relative_to(ROOT / "src")
        found.add(".".join(rel.parts))
    for top in ("envs", "controllers"):
        for init in (ROOT / top).rglob("__init__.py"):
            found.add(".".join(("rrtdrive", top, *init.parent.relative_to(ROOT / top).parts)))
    assert found - listed == set()
