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
    """The README's command-line examples, run as written in an empty folder (the studies, which are not
    installed, from the repository's root)."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"From the command line:\n\n```bash\n(.*?)```", text, re.S)
    assert block, "README: the command-line examples are missing"
    lines = [shlex.split(line, comments=True) for line in block.group(1).splitlines() if line.strip()]
    assert len(lines) >= 3
    for words in lines:
        assert words[:2] == ["python", "-m"], words
        out = subprocess.run([sys.executable, *words[1:]], cwd=ROOT if words[2] == "studies" else tmp_path,
                             capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, f"{shlex.join(words)}: {out.stderr[-2000:]}"
    assert (tmp_path / "case2.json").is_file()
    assert {"chain3.c", "chain3.h", "gac.h", "gac_sim.c", "Makefile", "CMakeLists.txt"} <= \
        {p.name for p in (tmp_path / "build" / "chain3").iterdir()}


# ---------------------------------------------------------------------------------------------------
# measured figures: a table of timings names the command that measured it; the link cap is the code's
# ---------------------------------------------------------------------------------------------------
TIME_UNIT = re.compile(r"(?<![\w/])(s|ms|µs|ns)(?![\w/])|runs/s|ns/rhs")


def tables_with_context(page: Path):
    """(header line, the text of its section up to the table: from the previous heading on) of every table."""
    lines = page.read_text().splitlines()
    found, context, in_code = [], [], False
    for k, line in enumerate(lines):
        in_code ^= line.startswith("```")
        if line.startswith("|") and k + 1 < len(lines) and lines[k + 1].startswith("|---"):
            found.append((line, "\n".join(context)))
        context = [] if line.startswith("#") and not in_code else context + [line]
    return found


# a column of wall-clock time: ms, µs, ns (not "1 ms samples"), runs/s, or a build stage in s
WALL_TIME = re.compile(r"(?<![\w/])(?<!\d )(ms|µs|ns)(?![\w/])|runs/s|ns/rhs|"
                       r"\b(derive|CSE|render|compile|cold total|generate \(wall\)) s\b")
DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")
MACHINE = re.compile(r"\b\d+-core\b|\b\d+ cores\b")


def tables_where(unit: re.Pattern) -> list:
    return [pytest.param(page, header, context, id=f"{page.name}: {header[:50]}")
            for page in PAGES for header, context in tables_with_context(page)
            if any(unit.search(cell) for cell in header.strip("|").split("|"))]


TIMED_TABLES, WALL_TIME_TABLES = tables_where(TIME_UNIT), tables_where(WALL_TIME)


def test_the_pages_show_timed_tables():
    assert len(WALL_TIME_TABLES) >= 10, [c.values[1] for c in WALL_TIME_TABLES]
    assert len(TIMED_TABLES) > len(WALL_TIME_TABLES)


@pytest.mark.parametrize("page, header, context", TIMED_TABLES)
def test_a_table_of_timings_names_its_command(page, header, context):
    """A table with a column in s, ms, µs or ns has the `python -m ...` command that measured it in its section,
    before it."""
    assert "python -m " in context, f"{page.name}: no `python -m ...` command before the table {header[:80]}"


@pytest.mark.parametrize("page, header, context", WALL_TIME_TABLES)
def test_a_table_of_wall_times_says_when_and_where(page, header, context):
    """A table of wall-clock times (they change with the machine and its load) states, in its section before
    it, the date it was measured (YYYY-MM-DD) and the machine (its cores)."""
    assert DATE.search(context), f"{page.name}: no date (YYYY-MM-DD) before the table {header[:80]}"
    assert MACHINE.search(context), f"{page.name}: no machine (N-core / N cores) before the table {header[:80]}"


def test_the_link_cap_stated_in_the_pages_is_the_code_s():
    """Every statement of the largest chain (`--links N` ranges, "at most N links", "up to N links are
    accepted", "the largest accepted") gives codegen.scene.MAX_LINKS, the cap codegen's --links and the
    scene loader check."""
    from codegen.cli import build_parser
    from codegen.scene import MAX_LINKS
    assert f"1 <= N <= {MAX_LINKS}" in build_parser().format_help().replace("\n", " ").replace("  ", " ")
    patterns = [r"--links N[^\n]*\(1\.\.([\d,]+)\)", r"at most \**([\d,]+) links", r"up\s+to\s+([\d,]+)\s+links\s+are\s+accepted",
                r"n = ([\d,]+) \(the largest accepted\)"]
    stated = [(page.name, int(number.replace(",", ""))) for page in PAGES for pattern in patterns
              for number in re.findall(pattern, page.read_text())]
    assert len(stated) >= 4, stated
    assert all(number == MAX_LINKS for _, number in stated), stated


def scaling_table() -> dict:
    """performance.md's `python -m studies scaling` table: n -> cold total build time in s."""
    text = (ROOT / "docs" / "performance.md").read_text()
    header = next(line for line in text.splitlines() if line.startswith("|") and "cold total s" in line)
    columns = [c.strip() for c in header.strip("|").split("|")]
    rows = text[text.index(header):].splitlines()[2:]
    table = {}
    for row in rows:
        if not row.startswith("|"):
            break
        cells = dict(zip(columns, (c.strip() for c in row.strip("|").split("|"))))
        table[int(cells["n"])] = float(cells["cold total s"])
    return table


def test_build_times_agree_across_pages():
    """Every page that states a build time ("X s at n = N", "n = N [builds] in [about] X s") states the same
    one: for an n of performance.md's scaling table its cold total (as rounded in the prose), otherwise the same
    figure as the other pages."""
    table = scaling_table()
    stated = {}
    for page in PAGES:
        text = page.read_text()
        for seconds, n in re.findall(r"([\d.]+)\s+s\s+at\s+n\s+=\s+([\d,]+)", text):
            stated.setdefault(int(n.replace(",", "")), []).append((page.name, float(seconds)))
        for n, seconds in re.findall(r"\bn\s+=\s+([\d,]+)\s+(?:builds\s+)?in\s+(?:about\s+)?([\d.]+)\s+s\b",
                                     text):
            stated.setdefault(int(n.replace(",", "")), []).append((page.name, float(seconds)))
    assert {64, 256} <= set(stated), stated
    for n, figures in stated.items():
        reference = table.get(n, figures[0][1])
        for page, seconds in figures:
            assert abs(seconds - reference) <= 0.05 * reference, \
                f"{page}: n = {n} builds in {seconds} s, but {reference} s elsewhere ({figures}, table {table.get(n)})"


def rendered_tables() -> dict[Path, str]:
    """The tables the docs render from the interfaces' one description: docs/generated-c.md's functions
    (codegen.interface), docs/fmi.md's FMU variables (gac_fmi2.h's rows)."""
    from codegen.fmu import variable_table
    from codegen.interface import function_table
    from runtime.header import fmi2_rows, library_constants
    return {ROOT / "docs" / "generated-c.md": function_table(),
            ROOT / "docs" / "fmi.md": variable_table(fmi2_rows(), library_constants())}


TABLE_START = re.compile(r"^<!-- the table below is rendered from .*-->\n", re.M)
TABLE_END = "<!-- end of the rendered table -->\n"


@pytest.mark.parametrize("page", sorted(rendered_tables(), key=str), ids=lambda page: page.name)
def test_rendered_tables_are_up_to_date(page):
    """The committed table between the page's markers is what its description renders now; GAC_UPDATE_DOCS=1
    rewrites it."""
    import os
    text = page.read_text()
    start = TABLE_START.search(text)
    assert start is not None and TABLE_END in text[start.end():], f"{page.name}: no rendered-table markers"
    end = text.index(TABLE_END, start.end())
    table = rendered_tables()[page]
    if os.environ.get("GAC_UPDATE_DOCS") == "1":
        page.write_text(text[:start.end()] + table + text[end:])
        return
    assert text[start.end():end] == table, f"{page.name}: the rendered table is out of date (GAC_UPDATE_DOCS=1 " \
        f"python -m pytest tests/test_docs.py -k rendered rewrites it)"
