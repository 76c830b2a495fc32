"""The shape of the code the kit promises (docs/kind-shape.md, issue 27): no import cycle in any
package (not even behind TYPE_CHECKING or inside functions), layers that import only downwards,
no private names of ``devsim.core`` in device code, no module over about 800 lines and no class
over about 400, every kind registered once, every device module's docstring citing its manual."""

from __future__ import annotations

import ast
import functools
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "devsim"
MAX_LINES = 800
MAX_CLASS_LINES = 400

#: The layers, lowest first.  A module imports its own package and the layers below it, nothing
#: beside or above (``devsim`` itself, for the version, from anywhere); a kind
#: (``devsim.devices.KIND``) imports only the core and itself.
LAYERS: list[tuple[str, ...]] = [
    ("devsim.core",),
    ("devsim.transports",),
    ("devsim.runtime", "devsim.devices"),
    ("devsim.facades",),
    ("devsim.fleet",),
    ("devsim.observe", "devsim.wireshark"),
    ("devsim.scenario",),
    ("devsim.web",),
    ("devsim.cli", "devsim.pytest_plugin"),
    ("devsim.__main__",),
]



def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The file's syntax tree, parsed once in a test process (every test here walks all of devsim)."""
    return ast.parse(path.read_text(encoding="utf-8"))


@functools.cache
def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """(module, imported names) of every import statement anywhere in the file."""
    tree = _tree(path)
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


def _packages() -> list[str]:
    return sorted({_module_name(p.parent / "__init__.py") for p in PACKAGE.rglob("*.py")})


def test_no_import_cycle_in_any_package() -> None:
    graph = _graph()
    cycles = {package: _cycle(graph, package) for package in _packages()}
    assert {p: " -> ".join(c) for p, c in cycles.items() if c} == {}


def _unit(module: str) -> str:
    """The package a module belongs to for the layer rules: ``devsim.devices.KIND`` for a
    kind, else the top-level package (or module) under ``devsim``."""
    parts = module.split(".")
    if len(parts) > 2 and parts[1] == "devices":
        return ".".join(parts[:3])
    return ".".join(parts[:2])


def _rank(unit: str) -> int:
    if unit == "devsim":
        return -1
    for rank, layer in enumerate(LAYERS):
        if any(unit == top or unit.startswith(top + ".") for top in layer):
            return rank
    raise AssertionError(f"{unit} is in no layer of LAYERS: add it where it belongs")


def test_layers_import_only_downwards() -> None:
    upward = []
    for module, targets in _graph().items():
        unit = _unit(module)
        for target in sorted(targets):
            other = _unit(target)
            if other == unit or other == "devsim":
                continue
            if unit.startswith("devsim.devices."):
                allowed = other == "devsim.core"  # a kind: the core and itself
            else:
                allowed = _rank(other) < _rank(unit)
            if not allowed:
                upward.append(f"{module} -> {target}")
    assert upward == []


def test_every_package_is_in_a_layer() -> None:
    for module in _graph():
        _rank(_unit(module))


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


@functools.cache
def _classes() -> dict[str, tuple[ast.ClassDef, Path]]:
    """Every class of devsim by its dotted name (module.Class)."""
    found = {}
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(_tree(path)):
            if isinstance(node, ast.ClassDef):
                found[f"{_module_name(path)}.{node.name}"] = (node, path)
    return found


def _long_classes() -> dict[str, int]:
    return {name: size for name, (node, _path) in _classes().items()
            if (size := (node.end_lineno or node.lineno) - node.lineno + 1) > MAX_CLASS_LINES}


def _mixers() -> list[str]:
    """Classes that inherit two or more classes of their own package (mixins sharing ``self``)."""
    classes = _classes()
    by_package: dict[str, set[str]] = {}
    for name in classes:
        package, _module, cls = name.rsplit(".", 2)
        by_package.setdefault(package, set()).add(cls)
    mixers = []
    for name, (node, _path) in classes.items():
        own = by_package[name.rsplit(".", 2)[0]]
        bases = [ast.unparse(b).split(".")[-1] for b in node.bases]
        if len([b for b in bases if b in own and b != "Protocol"]) > 1:
            mixers.append(name)
    return sorted(mixers)


def test_no_class_over_about_400_lines() -> None:
    assert _long_classes() == {}


def test_no_class_mixes_classes_of_its_package() -> None:
    assert _mixers() == []


def _kinds() -> list[str]:
    return sorted(p.name for p in (PACKAGE / "devices").iterdir() if (p / "__init__.py").exists())


def test_every_kind_is_registered_once() -> None:
    """One registration per kind: its entry point in pyproject.toml, and no table naming kinds
    anywhere else in devsim (a string naming a kind outside devsim/devices/, docstrings aside)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    points = project["entry-points"]["devsim.devices"]
    for kind in _kinds():
        assert [name for name, target in points.items() if target.startswith(f"devsim.devices.{kind}:")] == [kind]
    kinds = _kinds()
    assert sorted(points) == kinds
    named = []
    for path in PACKAGE.rglob("*.py"):
        if path.is_relative_to(PACKAGE / "devices"):
            continue
        tree = _tree(path)
        docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                      if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
                      and node.body and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                if node.value in kinds or any(f"devices.{kind}" in node.value for kind in kinds):
                    named.append(f"{path.relative_to(ROOT)}:{node.lineno}: {node.value[:60]!r}")
    assert named == []


def test_device_classes_cite_their_manual() -> None:
    missing = []
    for path in (PACKAGE / "devices").rglob("*.py"):
        if path.name == "__init__.py":
            continue
        tree = _tree(path)
        doc = ast.get_docstring(tree) or ""
        if "§" not in doc and "manual" not in doc.lower() and "spec" not in doc.lower():
            missing.append(path.name)
    assert missing == [], missing


def test_one_typed_data_library() -> None:
    """Configuration, scenario and plant files, table rows and value records are msgspec structs
    (devsim.core.typed, devsim.core.settings): no second way to declare typed data."""
    others = {"dataclasses", "pydantic", "attrs", "attr"}
    found = [
        f"{path.relative_to(ROOT)}: {module}"
        for path in PACKAGE.rglob("*.py")
        for module, _names in _imports(path)
        if module.split(".")[0] in others
    ]
    assert found == []
