"""``isoflow completion``: a shell completion script made from the parser."""

from __future__ import annotations

import argparse

from ..errors import IsoflowError


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "completion", "print a shell completion script (bash, zsh, tcsh) made from these options")
    p.add_argument("shell", choices=("bash", "zsh", "tcsh"), help="the shell to complete in")
    p.set_defaults(func=cmd_completion)


def cmd_completion(args: argparse.Namespace) -> int:
    """Print a completion script made by shtab from this very parser."""
    try:
        import shtab
    except ImportError as exc:
        raise IsoflowError(f"shell completion needs shtab: pip install shtab ({exc})") from None
    parser = args.parser  # the parser that read this command line (cli.main)
    # paths complete as files (or directories for --out); everything else
    # (commands, options, choices) shtab reads from the parser itself
    for command in parser.commands.values():
        for action in command._actions:
            if action.dest in ("input", "mesh", "output", "png"):
                action.complete = shtab.FILE
            elif action.dest == "out":
                action.complete = shtab.DIRECTORY
    print(shtab.complete(parser, shell=args.shell), end="")
    return 0
