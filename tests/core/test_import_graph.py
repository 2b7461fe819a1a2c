"""The shape of the code: forensics_core has no import cycle, never imports a plugin, and plugins use its public API.

Imports are read from the source (every ``import`` statement, at module level
or inside a function, ``TYPE_CHECKING`` blocks included), so a cycle hidden
behind a deferred import counts as one.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PUBLIC = {"forensics_core", "forensics_core.report"}


def _modules(package: Path, name: str) -> dict[str, Path]:
    found = {}
    for path in package.rglob("*.py"):
        parts = [name, *path.relative_to(package).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _imports(module: str, path: Path, known: dict[str, Path] | None = None) -> set[str]:
    """Modules (or packages) ``module`` imports, as absolute dotted names.

    ``from P import X`` counts as importing the submodule P.X when there is
    one (``known``), else P itself.
    """
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(package[:len(package) - node.level + 1] + ([node.module] if node.module else [])) \
                if node.level else node.module
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                names.add(sub if known is not None and sub in known else base)
    return names


def _graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    return {m: {n for n in _imports(m, p, modules) if n in modules and n != m} for m, p in modules.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_forensics_core_has_no_import_cycle():
    modules = _modules(ROOT / "forensics_core", "forensics_core")
    assert len(modules) > 40
    assert _cycles(_graph(modules)) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_core_never_imports_a_plugin():
    for module, path in _modules(ROOT / "forensics_core", "forensics_core").items():
        assert not any(n.startswith("forensics_plugins") for n in _imports(module, path)), module


def test_plugins_import_only_the_public_api_of_the_core():
    for package in ("forensics_plugins", "examples"):
        for path in (ROOT / package).rglob("*.py"):
            used = {n for n in _imports("x.y", path) if n.split(".")[0] == "forensics_core"}
            assert used <= PUBLIC, f"{path.relative_to(ROOT)} imports {sorted(used - PUBLIC)}"
