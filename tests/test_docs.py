"""The generated reference stays current: docs/devices/<kind>.md is `devsim doc KIND`."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from devsim.cli import cli
from devsim.cli.docgen import reference_markdown, shared_vocabulary_markdown
from devsim.core.registry import device_class, kinds

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = tuple(sorted(kinds()))  # every registered kind ships its reference under docs/devices/


@pytest.mark.parametrize("kind", SHIPPED)
def test_generated_reference_is_current(kind: str) -> None:
    path = ROOT / "docs" / "devices" / f"{kind}.md"
    expected = reference_markdown(device_class(kind)) + "\n"
    assert path.read_text(encoding="utf-8") == expected, (
        f"{path} is stale: run `devsim doc {kind} > docs/devices/{kind}.md`"
    )


@pytest.mark.parametrize("kind", SHIPPED)
def test_doc_command_prints_it(kind: str) -> None:
    result = CliRunner().invoke(cli, ["doc", kind])
    assert result.exit_code == 0
    assert result.output == (ROOT / "docs" / "devices" / f"{kind}.md").read_text(encoding="utf-8")
    for heading in ("## Serial ports", "## Control names", "## Faults", "## Commands", "## Parameters",
                    "## Error codes", "## Configuration keys"):
        assert heading in result.output


def test_readme_shows_the_shared_vocabulary_and_links_the_reference() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "\n".join(shared_vocabulary_markdown()) in (ROOT / "docs" / "control.md").read_text(encoding="utf-8")
    for kind in SHIPPED:
        assert f"(docs/devices/{kind}.md)" in readme


def test_unknown_kind_is_one_line() -> None:
    result = CliRunner().invoke(cli, ["doc", "nokind"])
    assert result.exit_code == 2 and "unknown device kind 'nokind'" in result.output


def test_the_documentation_site_builds_strictly(tmp_path: Path) -> None:
    """docs/ is a mkdocs-material site (mkdocs.yml): every page in the nav, every link and anchor
    found (--strict turns a broken one into a failure)."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT, capture_output=True, text=True, env=env, timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "site" / "kinds" / "sers" / "index.html").exists()
    assert (tmp_path / "site" / "devices" / "pcd4h3" / "index.html").exists()


def test_the_readme_stays_a_front_page() -> None:
    """README.md is the front page (the quick start, one example, where to read on); the rest lives
    in docs/, and every docs page it links exists."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 320
    import re

    for target in re.findall(r"\]\((docs/[^)#]+)", readme):
        assert (ROOT / target).exists(), target


def test_the_quick_start_is_two_commands_in_a_virtualenv() -> None:
    """The README's quick start: two one-line commands, each making and entering the virtualenv
    (Debian's pip refuses `pip install .` outside one); the second is what .ci/run runs."""
    import re

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = [block.strip() for block in re.findall(r"```sh\n(.*?)```", section, re.S)]
    assert len(commands) == 2 and all("\n" not in command for command in commands), commands
    venv = "python3 -m venv .venv && . .venv/bin/activate && "
    assert all(command.startswith(venv) for command in commands), commands
    assert commands[0].endswith("pip install . && devsim run sers --pty")
    assert commands[1] == venv + "pip install '.[test]' && python -m pytest -n auto"
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "python3 -m venv .venv" in ci and "pip install '.[test]'" in ci and "python -m pytest -n auto" in ci


def _python_snippets() -> list[tuple[str, int, str]]:
    """Every ```python block of README.md and docs/**/*.md: (file, line, code)."""
    import re

    found = []
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        text = path.read_text(encoding="utf-8")
        for match in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M):
            found.append((str(path.relative_to(ROOT)), text.count("\n", 0, match.start()) + 1, match.group(1)))
    return found


@pytest.mark.parametrize(("page", "line", "code"), _python_snippets(),
                         ids=[f"{page}:{line}" for page, line, _code in _python_snippets()])
def test_every_python_snippet_compiles_and_its_devsim_imports_exist(page: str, line: int, code: str) -> None:
    """A user copies the snippets: each is Python, and what it imports from devsim is there (the
    monitor page imported ControlClient from a module that has none)."""
    import ast
    import importlib

    tree = ast.parse(code, f"{page}:{line}")
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "devsim":
            module = importlib.import_module(node.module)
            for alias in node.names:
                assert hasattr(module, alias.name) or importlib.util.find_spec(f"{node.module}.{alias.name}"), (
                    f"{page}:{line}: {node.module} has no {alias.name}")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "devsim":
                    importlib.import_module(alias.name)


def _pages() -> list[Path]:
    """README.md and the hand-written docs pages (not the generated references)."""
    return [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").rglob("*.md") if p.parent.name != "devices")]


def _command_lines() -> list[tuple[str, str]]:
    """Every `devsim ...` line of a sh, console or text block (a `$ ` prompt dropped): (page, line)."""
    import re

    found = []
    for path in _pages():
        text = path.read_text(encoding="utf-8")
        for block in re.findall(r"^```(?:sh|console|text)\n(.*?)^```", text, re.S | re.M):
            for line in block.splitlines():
                line = line.strip().removeprefix("$ ")
                if line.startswith("devsim "):
                    found.append((str(path.relative_to(ROOT)), line))
    return found


def test_every_devsim_command_of_a_code_block_has_its_commands_and_options() -> None:
    """A user copies a command: each names a command and options devsim has, with values of their
    type (a flag renamed in the code and not on the page fails here); what it needs at run time (a
    running simulator, the file) is not asked."""
    import shlex

    import click

    lines = _command_lines()
    assert len(lines) > 40  # the pages' commands are found
    for page, line in lines:
        words = shlex.split(line.split(" #")[0].split(";")[0].split(" | ")[0].split(" > ")[0].rstrip(" &"))
        command, name, parent, args = cli, "devsim", None, words[1:]
        while True:
            try:
                context = command.make_context(name, list(args), parent=parent)
            except click.MissingParameter:
                break
            except click.UsageError as error:
                raise AssertionError(f"{page}: {line}: {error.format_message()}") from None
            rest = [*context._protected_args, *context.args]
            if not isinstance(command, click.Group) or not rest:
                break
            name, command, args = command.resolve_command(context, rest)
            parent = context


def test_the_docs_front_page_installs_as_the_readme_does() -> None:
    """The site has no quick start of its own: its front page gives the README's first command."""
    import re

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    first = re.findall(r"```sh\n(.*?)```", readme.split("## Quick start", 1)[1], re.S)[0].strip()
    assert f"`{first}`" in (ROOT / "docs" / "index.md").read_text(encoding="utf-8").replace("\n", " ")


def test_the_runtime_snippet_of_the_control_page_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """docs/control.md's in-process example, as a user pastes it: a SERS on a pty in virtual time."""
    [code] = [code for page, _line, code in _python_snippets() if page == "docs/control.md" and "Runtime(" in code]
    exec(compile(code, "docs/control.md", "exec"), {})
    assert capsys.readouterr().out == "0.0\n"


def test_the_console_session_of_the_cli_page_prints_what_it_shows() -> None:
    """docs/cli.md's `devsim ctl` session against a simulator started as the page says (it used a
    control socket it never said how to serve): each command prints the lines shown, numbers aside."""
    import re
    import shlex
    import tempfile

    from tests.support.process import DevsimProcess

    page = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    started = re.search(r"started as `devsim (run [^`]+)`", page)
    assert started, "docs/cli.md says how the simulator of its examples is started"
    address = "unix:/tmp/sers.sock"
    assert address in started.group(1)
    session = re.search(r"```console\n(.*?)```", page, re.S).group(1)
    steps: list[tuple[list[str], list[str]]] = []  # (the command's words, the lines shown)
    for line in session.splitlines():
        if line.startswith("$ devsim "):
            steps.append((shlex.split(line[2:].split(" #")[0])[1:], []))
        else:
            steps[-1][1].append(line)

    def shape(lines: list[str]) -> list[str]:
        return [" ".join(re.sub(r"\d+(\.\d+)?", "N", line).split()) for line in lines]

    with tempfile.TemporaryDirectory(prefix="dsd") as folder:  # (Unix socket paths are short)
        ours = f"unix:{folder}/c.sock"
        proc = DevsimProcess(*shlex.split(started.group(1).replace(address, ours)))
        try:
            proc.next_match(proc.out, lambda line: line.startswith("control: "), 30, "the control line")
            for args, shown in steps:
                args = [ours if arg == address else arg for arg in args]
                result = CliRunner().invoke(cli, args)
                assert result.exit_code == 0, (args, result.output)
                assert shape(result.output.splitlines()) == shape(shown), args
        finally:
            assert proc.interrupt() == 0
