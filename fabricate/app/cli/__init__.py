"""The ``fabricate`` command line.

Each subcommand lives in its own module ``fabricate/app/cli/cmd_<name>.py`` that
defines ``register(subparsers)``; the parser is assembled from whatever such
modules exist.  Subcommand modules keep heavy imports inside their handlers so
that ``fabricate --help`` is instant.

Every exception becomes one line on stderr and an exit code
(:mod:`fabricate.app.cli.exits`): 2 bad input, 3 tolerance not reached, 4 export
failed, 1 internal error (traceback in a log file whose path is printed),
130 interrupted.
"""
from __future__ import annotations

import argparse
import importlib
import logging
import pkgutil
import signal
import sys
import threading

from ... import __version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fabricate",
        description="Conical and planar-quad meshes to glass panels, beams and cut files "
                    "(Liu, Pottmann, Wallner, Yang, Wang, SIGGRAPH 2006).",
        epilog="Exit codes: 0 ok, 2 bad input (file, mesh, config, path), 3 tolerance not reached "
               "(results written and marked), 4 export failed, 1 internal error (please report; the "
               "traceback is in the log file named), 130 interrupted.")
    parser.add_argument("--version", action="version", version=f"conical-fab {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    parser.add_argument("--debug", action="store_true", help="also print the traceback of an error on the screen")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    names = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name.startswith("cmd_"))
    for name in names:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """The ``fabricate`` command: its exit code.

    Called with ``argv=None`` (the console script, ``python -m fabricate``) the work runs under
    :func:`fabricate.app.cli.supervise.supervise` so that Ctrl-C always ends it within two seconds;
    called with a list (tests, scripts) it runs in this process.
    """
    from .supervise import supervise

    try:
        parser = build_parser()
        args = parser.parse_args(argv)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "handler", None):
        parser.print_help()
        return 2
    if argv is None:
        return supervise(lambda: run_handler(args, supervised=True), lambda: scratch_folders(args))
    if threading.current_thread() is not threading.main_thread():
        return run_handler(args)
    previous = signal.signal(signal.SIGTERM, _terminate)  # kill unwinds like Ctrl-C
    try:
        return run_handler(args)
    finally:
        signal.signal(signal.SIGTERM, previous)


def _terminate(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


def run_handler(args, supervised: bool = False) -> int:
    """Run the subcommand; every exception becomes one line and its exit code
    (:func:`fabricate.app.cli.exits.classify`: the one table from exception classes to codes).
    With ``--debug`` an internal error is raised on (in-process) or its traceback printed."""
    from .exits import BROKEN_PIPE, classify, quiet_broken_pipe

    try:
        return int(args.handler(args) or 0)
    except BaseException as exc:  # noqa: BLE001 - the one place that turns exceptions into exit codes
        if isinstance(exc, SystemExit):
            raise
        if args.debug and not isinstance(exc, KeyboardInterrupt):
            if not supervised:
                raise
            import traceback

            traceback.print_exc()
        code, line = classify(exc)
        if code == BROKEN_PIPE:
            quiet_broken_pipe()
        elif line:
            try:
                print(line, file=sys.stderr)
            except OSError:
                pass
        return code


def scratch_folders(args) -> list:
    """Folders where the command makes temporary folders (cleaned after it had to be killed)."""
    from pathlib import Path

    out = [getattr(args, key, None) for key in ("out", "output")]
    return [Path(p) if key == "out" else Path(p).parent for key, p in zip(("out", "output"), out) if p]
