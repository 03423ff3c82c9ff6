"""The commands in README.md and docs/*.md: every `python -m ...` command shown names options its parser
has (a concrete command parses as written), and the README's quick-start snippet and commands run."""
from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PLACEHOLDER = re.compile(r"^(N|S|J|K|DIR|FILE|NAME|T|R|A|H|ADDRESS|STUDY|SCENE)$")


def commands(page: Path) -> list[str]:
    """Every `python -m ...` command of a page: lines of its code blocks and inline code spans."""
    text = page.read_text()
    found = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        for line in block.splitlines():
            for part in line.removeprefix("$ ").split("&&"):
                part = part.strip()
                if part.startswith("python -m ") and not part.startswith("python -m pytest"):
                    found.append(part)
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    found += [span for span in re.findall(r"`([^`]+)`", prose)
              if span.startswith("python -m ") and not span.startswith("python -m pytest")]
    return found


def parser_and_args(words: list[str]):
    """The argparse parser that reads ``python -m MODULE WORDS...`` and the words it reads."""
    module, rest = words[0], words[1:]
    if module == "runtime":
        from runtime.cli import build_parser
        return build_parser(), rest
    if module == "codegen":
        from codegen.cli import build_parser
        return build_parser(), rest
    if module == "studies":
        import importlib
        from studies.cli import STUDIES, build_parser
        if not rest or rest[0] not in STUDIES:                      # --help, or the STUDY placeholder
            return build_parser(), rest
        return importlib.import_module(STUDIES[rest[0]][0]).build_parser(), rest[1:]
    if module.startswith("studies."):
        import importlib
        return importlib.import_module(module).build_parser(), rest
    raise AssertionError(f"unknown module in a documented command: python -m {module}")


def option_strings(parser) -> set[str]:
    """Every option of a parser and of its subcommands."""
    import argparse
    names = set()
    for action in parser._actions:
        names.update(action.option_strings)
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                names |= option_strings(sub)
    return names


CASES = [pytest.param(page, command, id=f"{page.name}: {command[:60]}") for page in PAGES for command in commands(page)]


def test_the_pages_show_commands():
    assert len(CASES) >= 15, [c.values[1] for c in CASES]


@pytest.mark.parametrize("page, command", CASES)
def test_documented_command_matches_its_parser(page, command):
    words = shlex.split(command, comments=True)[2:]                 # after "python -m"
    parser, args = parser_and_args(words)
    known = option_strings(parser)
    for option in re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", command):   # options named anywhere, comment too
        assert option in known, f"{page.name}: `{command}` names {option}, which the parser does not have"
    if any(w.startswith("[") or "|" in w or PLACEHOLDER.match(w) or "..." in w for w in args):
        return                                                     # a usage line: its options exist
    try:
        parser.parse_args(args)
    except SystemExit as exc:
        assert exc.code == 0, f"{page.name}: `{command}` does not parse (exit {exc.code})"


README_PYTHON = re.search(r"```python\n(from runtime import load_model, simulate\n.*?)```",
                          (ROOT / "README.md").read_text(), re.S)


def test_readme_python_snippet_runs(tmp_path):
    assert README_PYTHON, "README: the Python quick-start snippet is missing"
    out = subprocess.run([sys.executable, "-c", README_PYTHON.group(1)], cwd=tmp_path, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("reached t_end 7 energy"), out.stdout


def test_readme_use_commands_run(tmp_path):
    """The README's command-line examples, run as written in an empty folder."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"From the command line:\n\n```bash\n(.*?)```", text, re.S)
    assert block, "README: the command-line examples are missing"
    lines = [shlex.split(line, comments=True) for line in block.group(1).splitlines() if line.strip()]
    assert len(lines) >= 3
    for words in lines:
        assert words[:2] == ["python", "-m"], words
        out = subprocess.run([sys.executable, *words[1:]], cwd=tmp_path, capture_output=True, text=True,
                             timeout=600)
        assert out.returncode == 0, f"{shlex.join(words)}: {out.stderr[-2000:]}"
    assert (tmp_path / "case2.json").is_file()
    assert {"chain3.c", "chain3.h", "gac.h", "gac_sim.c", "Makefile", "CMakeLists.txt"} <= \
        {p.name for p in (tmp_path / "build" / "chain3").iterdir()}
