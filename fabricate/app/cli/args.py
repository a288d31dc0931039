"""The arguments several subcommands share, declared once: flag, metavar, default and destination
here, the one-line help (which says what the argument means to that command) from the command.
Light to import (``fabricate --help`` reads it): the defaults come from
:data:`fabricate.app.options.COMMAND`, read when the parser is built."""
from __future__ import annotations

from argparse import ArgumentParser


def add_config(p: ArgumentParser, help: str) -> None:
    """``CONFIG``: one YAML run configuration."""
    p.add_argument("config", help=help)


def add_sets(p: ArgumentParser, help: str, *, sweep: bool = False) -> None:
    """``--set KEY=VALUE`` (repeatable, into ``args.sets``); ``sweep``: comma lists are sweeps."""
    p.add_argument("--set", metavar="KEY=V1[,V2...]" if sweep else "KEY=VALUE", action="append", default=[],
                   dest="sets", help=help)


def add_out(p: ArgumentParser, folders: str = "run folder") -> None:
    """``--out DIR``: the parent folder of the run folder(s) (default ``COMMAND.out_root``)."""
    from fabricate.app import options

    root = options.COMMAND.out_root
    p.add_argument("--out", metavar="DIR", default=root, help=f"parent folder of the {folders} (default: ./{root})")


def add_force(p: ArgumentParser, help: str) -> None:
    """``--force``: replace an earlier finished run (``args.force``)."""
    p.add_argument("--force", action="store_true", help=help)


def add_quiet(p: ArgumentParser) -> None:
    """``-q`` / ``--quiet``: no progress bars."""
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")


def add_output(p: ArgumentParser, help: str, *, required: bool = True, metavar: str | None = None) -> None:
    """``-o`` / ``--output``: the file or folder a mesh command writes (``args.output``)."""
    p.add_argument("-o", "--output", required=required, metavar=metavar, help=help)


def one_value_sets(sets: list[str], command: str, hint: str = "") -> dict:
    """``{key: value}`` of the ``--set`` arguments of a command that runs one config: a key given
    several values (a sweep) is a ConfigError naming it (``hint`` added to the message)."""
    from fabricate.app.batch import parse_sets
    from optimize.errors import ConfigError

    parsed = parse_sets(sets)
    many = [k for k, v in parsed.items() if len(v) != 1]
    if many:
        raise ConfigError(f"--set {many[0]}: fabricate {command} takes one value per key{hint}")
    return {k: v[0] for k, v in parsed.items()}
