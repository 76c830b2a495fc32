"""The shape of the code the kit promises: no import cycles (not even behind TYPE_CHECKING or
inside functions), no private names of ``devsim.core`` in device code, no module over about
800 lines, every device module's class docstrings in place."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "devsim"
MAX_LINES = 850


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """(module, imported names) of every import statement anywhere in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found: list[tuple[str, list[str]]] = []
    package = _module_name(path).rsplit(".", 1)[0] if path.name != "__init__.py" else _module_name(path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, []) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join([*base, module]) if module else ".".join(base)
            found.append((module, [alias.name for alias in node.names]))
    return found


def _graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        for module, names in _imports(path):
            submodules = [f"{module}.{n}" for n in names if f"{module}.{n}" in modules]
            # "from pkg import submodule" loads the submodule, not more of pkg's __init__
            targets = submodules + ([module] if len(submodules) < len(names) or not names else [])
            for target in targets:
                if target in modules and target != name:
                    graph[name].add(target)
    return graph


def _cycle(graph: dict[str, set[str]], within: str) -> list[str] | None:
    nodes = {n for n in graph if n.startswith(within)}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node] & nodes):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt) :] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(nodes):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_no_import_cycle_inside_a_device_package_or_the_core() -> None:
    graph = _graph()
    for package in ("devsim.devices.sers", "devsim.devices.gms96", "devsim.core"):
        assert _cycle(graph, package) is None, f"import cycle: {' -> '.join(_cycle(graph, package) or [])}"


def test_device_code_uses_no_private_name_of_the_core() -> None:
    offenders = []
    for path in (PACKAGE / "devices").rglob("*.py"):
        for module, names in _imports(path):
            if module.startswith("devsim.core"):
                offenders += [f"{path.name}: {module}.{n}" for n in names if n.startswith("_")]
        text = path.read_text(encoding="utf-8")
        for attr in ("axis._", "clock._", "signals._", "nvram._"):
            if attr in text:
                offenders.append(f"{path.name}: {attr}…")
    assert offenders == []


def test_no_module_over_about_800_lines() -> None:
    long = {str(p.relative_to(ROOT)): n for p in PACKAGE.rglob("*.py") if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert long == {}


def test_device_classes_cite_their_manual() -> None:
    missing = []
    for path in (PACKAGE / "devices").rglob("*.py"):
        if path.name == "__init__.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        doc = ast.get_docstring(tree) or ""
        if "§" not in doc and "manual" not in doc.lower() and "spec" not in doc.lower():
            missing.append(path.name)
    assert missing == [], missing
