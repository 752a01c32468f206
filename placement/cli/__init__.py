"""The ``anchorplan`` command line. Each sub-command lives in its own module here and
exposes ``register(subparsers)``; only this package prints."""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

#: sub-command modules of this package, in the order ``--help`` lists them
COMMANDS = (
    "plan",
    "sweep",
    "bounds",
    "evaluate",
    "report",
    "peb_map",
    "export",
    "sheet",
    "stress",
    "serve",
)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors (exit code 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _Warnings(logging.Handler):
    """Library warnings (and the PSO's resume notice) as one line each on stderr."""

    def __init__(self, command: str):
        super().__init__(logging.INFO)
        self.command = command
        self.seen: set[str] = set()  # a sweep plans many times: say each warning once

    def emit(self, record: logging.LogRecord) -> None:
        if record.levelno < logging.WARNING and not record.name.startswith("placement.pso"):
            return
        kind = "warning" if record.levelno >= logging.WARNING else "note"
        try:
            text = record.getMessage().replace("\n", " ")
        except Exception:  # noqa: BLE001 - a bad log call must not end the run
            text = str(record.msg)
        if kind == "warning":
            if text in self.seen:
                return
            self.seen.add(text)
        print(f"anchorplan {self.command}: {kind}: {text}", file=sys.stderr, flush=True)


def build_parser() -> argparse.ArgumentParser:
    """The ``anchorplan`` argument parser with every subcommand."""
    parser = _Parser(
        prog="anchorplan",
        description="Anchor layout planning for ultrasonic time-of-flight indoor positioning.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"placement.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``anchorplan`` console script; returns the exit code.

    Bad input (``ValueError``, missing or unusable files) prints one line on stderr and
    exits 2; any other failure prints one line and exits 1 (130 on Ctrl-C).
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage errors (one line, 2) and --help (0)
        return exc.code if isinstance(exc.code, int) else 2
    return run_command(args)


def run_command(args) -> int:
    """Run parsed ``args`` (``args.func(args)``) as :func:`main` does: bad input prints one
    line on stderr and returns 2, any other failure one line and 1; the exit code."""
    prefix = f"anchorplan {args.command}"
    handler = _Warnings(args.command)
    loggers = [logging.getLogger(n) for n in ("placement", "analysis", "simulation")]
    saved = [(lg, lg.level) for lg in loggers]
    for lg in loggers:
        lg.addHandler(handler)
        if lg.getEffectiveLevel() > logging.INFO:
            lg.setLevel(logging.INFO)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileNotFoundError, KeyError) as exc:
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"{prefix}: error: {_one_line(msg)}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file argument that cannot be read or written
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"{prefix}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2 if exc.filename else 1
    except KeyboardInterrupt:
        print(f"{prefix}: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        print(f"{prefix}: error: out of memory; use smaller settings", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - no traceback for users: one line, exit 1
        print(f"{prefix}: error: {type(exc).__name__}: {_one_line(exc)}", file=sys.stderr)
        return 1
    finally:
        for lg, level in saved:
            lg.removeHandler(handler)
            lg.setLevel(level)


def _one_line(msg) -> str:
    return " ".join(str(msg).split())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
