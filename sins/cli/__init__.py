"""The ``sins`` command: one module per subcommand, each a thin shell over library calls.

Each command module has ``add(subparsers)``, which adds its parser and sets ``func`` to the function that
runs it; :mod:`~sins.cli.common` holds what they share. Bad input ends in one line on stderr
(``sins: error: …``) and exit status 2; never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import re
import signal
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from sins import __version__
from sins.cli import (
    bias,
    calibrate,
    campaign,
    characterise,
    check,
    correct,
    effects,
    evaluate,
    fit,
    gap,
    inspect,
    integrate,
    run,
    scenarios,
    simulate,
    strategies,
)
from sins.cli.common import Subparsers
from sins.cli.parser import Parser
from sins.cli.signals import Seen, Terminated, pipes_outliving_their_readers, signals_as_exceptions
from sins.errors import ArgumentError, MissingInputError, SinsInputError

#: Every subcommand, in the order ``sins --help`` lists them.
SUBCOMMANDS: tuple[Callable[[Subparsers], None], ...] = (
    run.add,
    integrate.add,
    simulate.add,
    calibrate.add,
    fit.add,
    evaluate.add,
    correct.add,
    check.add,
    campaign.add,
    gap.add,
    characterise.add,
    inspect.add,
    bias.add,
    effects.add,
    scenarios.add,
    strategies.add,
)

#: Commands whose outputs land as each is done, not together at the end (a campaign's parts: a resume
#: needs them; ``check`` runs campaigns), and those that write nothing.
_AS_DONE = ("campaign", "check", "scenarios", "effects", "strategies")
#: The flag of each argument of :func:`sins.io.read` an :class:`~sins.errors.ArgumentError` names.
_OPTION_FLAGS = {
    "topic": "--topic", "truth_topic": "--truth-topic", "columns": "--columns", "units": "--units",
    "frame": "--frame", "rate_hz": "--rate", "origin": "--origin", "truth": "--truth",
}  # fmt: skip
#: The flag that gives what a :class:`MissingInputError` says is missing.
_FLAG_FOR = {"truth": "--truth TRUTH.csv", "topic": "--topic TOPIC", "truth_topic": "--truth-topic TOPIC",
             "lat": "--lat DEG", "origin": "--origin LAT,LON,H", "heading": "--heading DEG"}  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    """The ``sins`` command's argument parser, one subcommand per action."""
    parser = Parser(prog="sins", description="Strapdown inertial navigation simulator.")
    parser.add_argument("--version", action="version", version=f"sins {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=Parser)
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def _together(command: str, discarded: list[Path]) -> contextlib.AbstractContextManager[None]:
    """A command's outputs land together or not at all (:func:`sins.core.deferred.all_or_nothing`), but
    for :data:`_AS_DONE`."""
    from sins.core.deferred import all_or_nothing  # plain os: nothing numerical before the work

    return contextlib.nullcontext() if command in _AS_DONE else all_or_nothing(discarded)


def parse(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """``argv`` parsed, recordings given after an option included: argparse gives a command's optional
    positional (``RECORDING``, ``RECORDING ...``) the words before the first option and takes any after
    it for unrecognised (``sins correct M.json --out c.csv r.npz`` was refused), so those are given to it
    here, converted by its own type; anything else unrecognised is refused as argparse refuses it."""
    parser = build_parser()
    words = _negatives_joined(parser, list(sys.argv[1:] if argv is None else argv))
    args, extra = parser.parse_known_args(words)
    command = _subparser(parser, args.command)
    _check_file_names(command, words)
    if not extra:
        return args
    late = next(
        (a for a in command._actions if not a.option_strings and a.nargs in ("?", "*") and a.dest != "help"),
        None,
    )
    taken = getattr(args, late.dest) if late is not None else None
    fits = late is not None and (late.nargs == "*" or (taken is None and len(extra) == 1))
    if not fits or any(word.startswith("-") for word in extra):
        command.error(f"unrecognized arguments: {' '.join(extra)}")
    assert late is not None
    convert = late.type if callable(late.type) else str
    values = [convert(word) for word in extra]
    setattr(args, late.dest, [*(taken or []), *values] if late.nargs == "*" else values[0])
    return args


#: A word that is a negative number or a list of numbers that starts with one (``-33.9,151.2,10``).
_NEGATIVE = re.compile(r"^-(\d|\.\d)")


def _negatives_joined(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``argv`` with each option that takes one value joined to a value that starts with a minus sign
    (``--origin -33.9,151.2,10`` as ``--origin=-33.9,151.2,10``): argparse takes a negative number alone
    for a value but a list of them for an option, and refused every southern origin and negative roll."""
    found = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    single = {
        o for command in found.choices.values() for a in command._actions
        if a.nargs is None and a.option_strings for o in a.option_strings
    }  # fmt: skip
    out: list[str] = []
    k = 0
    while k < len(argv):
        if argv[k] in single and k + 1 < len(argv) and _NEGATIVE.match(argv[k + 1]):
            out.append(f"{argv[k]}={argv[k + 1]}")
            k += 2
        else:
            out.append(argv[k])
            k += 1
    return out


#: The options that name a file sins writes (a campaign's ``--out DIR`` names a folder: not among them;
#: ``--imu`` and ``--truth`` are outputs of ``simulate`` alone; ``check``'s ``--baseline`` is read, or
#: written with ``--update-baseline``: a folder's name is neither).
_FILE_OUTPUTS = ("--out", "--json", "--plot", "--rerun", "--baseline")


def _check_file_names(command: argparse.ArgumentParser, argv: list[str]) -> None:
    """Refuse an output file's name that ends in ``/`` (a folder's): ``type=Path`` drops the slash, and
    ``--out model.json/`` wrote ``model.json``."""
    outputs = (*_FILE_OUTPUTS, "--imu", "--truth") if command.prog.endswith(" simulate") else _FILE_OUTPUTS
    files = {o for a in command._actions for o in a.option_strings if o in outputs and a.metavar != "DIR"}
    for i, word in enumerate(argv):
        flag, eq, value = word.partition("=")
        if not eq:
            flag, value = word, argv[i + 1] if i + 1 < len(argv) else ""
        if flag in files and value.endswith("/") and value.strip("/"):
            command.error(f"{flag} {value}: ends in /, a folder's name; {flag} names a file")


def _subparser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    """The parser of subcommand ``name``."""
    found = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return found.choices[name]


def main(argv: Sequence[str] | None = None, *, process: bool = False) -> int:
    """Run the ``sins`` command on ``argv`` (default ``sys.argv[1:]``); returns the exit status.
    ``process``: this process is the command (:func:`console`, the console script's): after it every
    signal is ignored until the process exits (:func:`sins.cli.signals.signals_as_exceptions`)."""
    args = parse(argv)
    discarded: list[Path] = []
    seen: Seen | None = None
    try:
        with (
            signals_as_exceptions(process=process) as seen,
            pipes_outliving_their_readers() as pipes,
            _together(args.command, discarded),
        ):
            status = int(args.func(args))
            pipes.flush()  # a reader gone is found here at the latest: the outputs land all the same
            seen.landing()  # its outputs land now, whatever signal comes (sins.cli.signals)
            status = 141 if pipes.broken and status == 0 else status
    except Exception as exc:  # what is not bad input is raised again by _failed
        status = _failed(exc, seen)
    except (KeyboardInterrupt, Terminated) as exc:
        status = _failed(exc, seen)
    finally:
        if discarded:
            _say(f"sins: none of its outputs written ({', '.join(map(str, discarded))}: not replaced)")
    for late in seen.late if seen is not None else []:  # held off while the outputs landed: the caller's
        signal.raise_signal(late)
    return status


def console() -> None:
    """The ``sins`` console script: :func:`main` on the command line, as this process's whole command."""
    sys.exit(main(process=True))


def _failed(exc: BaseException, seen: Seen | None) -> int:
    """The exit status of a command that raised ``exc``, its one line said. A signal seen before ends it
    as interrupted whatever it raised (a library swallowed the signal, then failed for want of it: a
    bag reader's error, numba's RuntimeError); anything else not bad input is raised again."""
    if seen is not None and seen.signums:
        return _ended(seen.signums[0])
    if isinstance(exc, KeyboardInterrupt | Terminated):
        return _ended(exc.signum if isinstance(exc, Terminated) else signal.SIGINT)
    if isinstance(exc, ArgumentError):  # the reader's arguments, said as this command's flags
        _say(f"sins: error: {exc.said(_OPTION_FLAGS)}")
        return 2
    if isinstance(exc, MissingInputError):
        flag = _FLAG_FOR.get(exc.needs)
        _say(f"sins: error: {exc}" + (f"; give it with {flag}" if flag else ""))
        return 2
    if isinstance(exc, SinsInputError):
        _say(f"sins: error: {exc}")
        return 2
    if isinstance(exc, BrokenPipeError):  # a stream not wrapped: nothing more to write to it
        return 141
    if isinstance(exc, OSError):  # a full disk or a permission while writing
        _say(f"sins: error: {exc.filename or ''}: {exc.strerror or exc}")
        return 2
    raise exc


def _say(line: str) -> None:
    """Print ``line`` on stderr, where a reader may have gone away (``2>&1 | head``): then nowhere."""
    with contextlib.suppress(BrokenPipeError):
        print(line, file=sys.stderr, flush=True)


def _ended(signum: int) -> int:
    """Say that a signal ended the command; its exit status, 128 + the signal's number."""
    said = {int(signal.SIGINT): "interrupted", int(signal.SIGTERM): "terminated"}.get(signum, "hung up")
    _say(f"sins: {said}")
    return 128 + int(signum)


__all__ = ["SUBCOMMANDS", "build_parser", "console", "main", "parse"]
