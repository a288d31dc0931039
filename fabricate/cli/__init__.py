"""The ``fabricate`` command line.

Each subcommand lives in its own module ``fabricate/cli/cmd_<name>.py`` that
defines ``register(subparsers)``; the parser is assembled from whatever such
modules exist.  Subcommand modules keep heavy imports inside their handlers so
that ``fabricate --help`` is instant.

Errors of the package (:class:`optimize.errors.ConicalFabError`) become one
line on stderr and the error's exit code: 2 bad input, 3 tolerance not
reached, 4 export failed.
"""
from __future__ import annotations

import argparse
import importlib
import logging
import pkgutil
import sys

from .. import __version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fabricate",
        description="Conical and planar-quad meshes to glass panels, beams and cut files "
                    "(Liu, Pottmann, Wallner, Yang, Wang, SIGGRAPH 2006).",
        epilog="Exit codes: 0 ok, 2 bad input (file, mesh, config), 3 tolerance not reached "
               "(results written and marked), 4 export failed.")
    parser.add_argument("--version", action="version", version=f"conical-fab {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of unexpected errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    names = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name.startswith("cmd_"))
    for name in names:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from optimize.errors import ConicalFabError

    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "handler", None):
        parser.print_help()
        return 2
    try:
        return int(args.handler(args) or 0)
    except ConicalFabError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - last resort: one line, unless --debug
        if args.debug:
            raise
        print(f"error: unexpected {type(exc).__name__}: {exc} (run with --debug for details)",
              file=sys.stderr)
        return 1
