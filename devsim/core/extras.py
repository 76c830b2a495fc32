"""What to type to install an optional extra (``plot``, ``monitor``, ``modbus`` …), where devsim runs.

Installed from a package index, the extra belongs to the distribution: ``pip install
'devsim-motion[plot]'``.  Run from a source checkout (``python -m devsim`` in it, an editable
install, or ``pip install .`` from a checkout that is still there), that command would fetch
another copy from the index; the checkout's own extra is ``pip install '.[plot]'`` (the
checkout's path instead of ``.`` when the current directory is elsewhere).
"""

from __future__ import annotations

import json
import os
from importlib import metadata
from pathlib import Path
from urllib.parse import unquote, urlparse

__all__ = ["DISTRIBUTION", "install_command", "source_tree"]

#: The distribution's name (``devsim`` on PyPI is an unrelated project).
DISTRIBUTION = "devsim-motion"
_PACKAGE = Path(__file__).resolve().parents[1]  # devsim/


def _is_tree(path: Path) -> bool:
    project = path / "pyproject.toml"
    return project.is_file() and f'name = "{DISTRIBUTION}"' in project.read_text(encoding="utf-8")


def source_tree() -> Path | None:
    """The checkout devsim runs from (its package imported from there, or installed from there
    by ``pip install .``), or None for an installed copy from a package index."""
    if _is_tree(_PACKAGE.parent):
        return _PACKAGE.parent
    try:
        dist = metadata.distribution(DISTRIBUTION)
        direct = json.loads(dist.read_text("direct_url.json") or "null")
        ours = Path(str(dist.locate_file("devsim/__init__.py"))).resolve() == _PACKAGE / "__init__.py"
    except (metadata.PackageNotFoundError, ValueError, OSError):
        return None
    if not ours or not isinstance(direct, dict) or "dir_info" not in direct:
        return None
    url = urlparse(str(direct.get("url", "")))
    tree = Path(unquote(url.path)) if url.scheme == "file" else None
    return tree if tree is not None and _is_tree(tree) else None


def install_command(extra: str) -> str:
    """``pip install …`` for one extra, right for where devsim runs."""
    tree = source_tree()
    if tree is None:
        return f"pip install '{DISTRIBUTION}[{extra}]'"
    where = "." if Path(os.getcwd()).resolve() == tree.resolve() else str(tree)
    return f"pip install '{where}[{extra}]'"
