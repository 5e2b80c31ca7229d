"""The README's command table and ``sins COMMAND --help`` come from one source, the argparse parsers: each
row names a command the parser has, its options are exactly that command's (the reading options shown as
``FORMAT OPTIONS``), and its description is the command's help; every command of the parser has a row."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from sins.cli import build_parser

README = Path(__file__).resolve().parents[1] / "README.md"
#: The token standing for the reading options every command that takes a recording has.
FORMAT = "FORMAT OPTIONS"


def _subparsers() -> dict[str, tuple[argparse.ArgumentParser, str]]:
    """Each command's parser and its one-line help, from the parser ``sins`` runs."""
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
    return {name: (sub, helps[name]) for name, sub in action.choices.items()}


def _table() -> dict[str, tuple[str, str]]:
    """The README's command table: command → (its synopsis, its description), one row each."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("| command | what it does |") :]
    rows: dict[str, tuple[str, str]] = {}
    for line in section.splitlines()[2:]:
        if not line.startswith("| `sins "):
            break
        cells = re.split(r"(?<!\\)\|", line.strip().strip("|"))
        synopsis, description = cells[0].strip().strip("`"), cells[1].strip()
        name = synopsis.split()[1]
        assert name not in rows, f"two README rows for sins {name}"
        rows[name] = (synopsis.replace("\\|", "|"), description)
    return rows


def _format_flags() -> set[str]:
    """The reading options: the flags of the argument group every recording-reading command adds."""
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    group = next(g for g in action.choices["inspect"]._action_groups if g.title == "recording formats")
    return {a.option_strings[-1] for a in group._group_actions}


def _flags(parser: argparse.ArgumentParser) -> set[str]:
    return {a.option_strings[-1] for a in parser._actions if a.option_strings and a.dest != "help"}


def test_every_command_has_one_row_and_every_row_a_command() -> None:
    assert set(_table()) == set(_subparsers())


@pytest.mark.parametrize("name", sorted(_subparsers()))
def test_a_rows_options_are_its_commands_both_ways(name: str) -> None:
    synopsis, _ = _table()[name]
    parser, _ = _subparsers()[name]
    written = set(re.findall(r"--[a-z][a-z0-9-]*", synopsis))
    if FORMAT in synopsis:
        written |= _format_flags()
    assert written == _flags(parser), (
        f"README row of sins {name}: missing {sorted(_flags(parser) - written)}, "
        f"unknown {sorted(written - _flags(parser))}"
    )


@pytest.mark.parametrize("name", sorted(_subparsers()))
def test_a_rows_description_is_its_help(name: str) -> None:
    assert _table()[name][1] == _subparsers()[name][1]


@pytest.mark.parametrize("name", sorted(_subparsers()))
def test_a_rows_metavars_are_its_commands(name: str) -> None:
    """Each value a row shows after a flag is what ``--help`` shows (``--out MODEL.json``), or its
    choices written out (``--vertical free|hold|damp``)."""
    synopsis, _ = _table()[name]
    parser, _ = _subparsers()[name]
    for action in parser._actions:
        flag = action.option_strings[-1] if action.option_strings else None
        if (
            flag is None
            or action.nargs == 0
            or flag not in synopsis
            or flag in _format_flags() - {"--origin"}
        ):
            continue
        shown = re.search(re.escape(flag) + r" ([^\s\]\)]+)", synopsis)
        assert shown, f"sins {name}: README shows no value after {flag}"
        expected = action.metavar or ("|".join(action.choices) if action.choices else action.dest.upper())
        assert shown.group(1) == expected or expected == action.dest.upper(), (name, flag, shown.group(1))


def test_the_format_note_lists_the_reading_options() -> None:
    text = README.read_text(encoding="utf-8")
    note = text[text.index(f"`{FORMAT}` say how") :].split("\n\n")[0]
    assert set(re.findall(r"--[a-z][a-z-]*", note)) - {"--dataset", "--help"} == _format_flags()


CLI_GUIDE = README.parent / "docs" / "guide" / "cli.md"


@pytest.mark.parametrize("name", sorted(_subparsers()))
def test_the_cli_guides_synopsis_holds_every_option_both_ways(name: str) -> None:
    """docs/guide/cli.md's synopsis lines of each command hold every option its ``--help`` has (the reading
    options once, in the prose under it) and none it lacks: a docs walk found ``fit``'s lines six options
    short, ``gap``'s four."""
    text = CLI_GUIDE.read_text(encoding="utf-8")
    block = text.split("```sh", 1)[1].split("```", 1)[0]
    lines = [line.split("#")[0] for line in block.splitlines() if re.match(rf"sins {name}( |$)", line)]
    assert lines, f"docs/guide/cli.md has no synopsis of sins {name}"
    written = set(re.findall(r"--[a-z][a-z0-9-]*", " ".join(lines)))
    expected = _flags(_subparsers()[name][0]) - _format_flags()
    assert written - _format_flags() == expected, (
        f"cli.md of sins {name}: missing {sorted(expected - written)}, unknown {sorted(written - expected)}"
    )
