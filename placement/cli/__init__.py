"""The ``anchorplan`` command line. Each sub-command lives in its own module here and
exposes ``register(subparsers)``; only this package prints."""

from __future__ import annotations

import argparse
import importlib
import sys

#: sub-command modules of this package, in the order ``--help`` lists them
COMMANDS = (
    "plan",
    "bounds",
    "evaluate",
    "report",
    "peb_map",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="anchorplan",
        description="Anchor layout planning for ultrasonic time-of-flight indoor positioning.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"placement.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``anchorplan`` console script; returns the exit code.

    Bad input (``ValueError``, missing files) prints one line on stderr and exits 2.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileNotFoundError, KeyError) as exc:
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"anchorplan {args.command}: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
