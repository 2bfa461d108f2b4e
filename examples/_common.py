"""What every example shares: its command line (an output directory,
--force), outputs that are not overwritten without --force, isoflow's notes
on stderr, and one-line errors. Not an example itself (the gallery skips
files starting with _)."""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
from pathlib import Path

import isoflow


def parse_args(description: str, add_arguments=None) -> argparse.Namespace:
    """``OUT`` (default: a new temporary directory) and ``--force``, plus the
    example's own arguments. ``args.out`` is an existing directory."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("out", nargs="?", help="directory for the outputs (default: a new temporary directory)")
    parser.add_argument("--force", action="store_true", help="overwrite outputs already in OUT")
    if add_arguments is not None:
        add_arguments(parser)
    show_defaults(parser)
    args = parser.parse_args()
    if getattr(args, "mesh", None):
        args.mesh = sample_or_file(args.mesh)
    show_notes()
    args.out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="isoflow-example-"))
    args.out.mkdir(parents=True, exist_ok=True)
    return args


def sample_or_file(name: str) -> str:
    """A mesh argument: the file it names, else the sample of isoflow.data
    of that name (``--mesh eight.off``, as ``-h`` names the default), else
    as given (its reader then says the file is missing)."""
    if Path(name).exists() or name not in isoflow.data.names():
        return name
    return str(isoflow.data.path(name))


def show_defaults(parser: argparse.ArgumentParser) -> None:
    """Each option's help ends with its default, as ``isoflow -h`` says
    them: the gallery's pages name the defaults (the torus at 24 across),
    and ``-h`` is where a user looks for them. A sample mesh's default is
    named by its file in isoflow.data, not by where it is installed."""
    for action in parser._actions:
        default = action.default
        if not action.help or "default" in action.help or default in (None, False, argparse.SUPPRESS):
            continue
        if isinstance(default, str) and Path(default).is_absolute():
            shown = f"isoflow.data's {Path(default).name}"
        else:
            shown = " ".join(map(str, default)) if isinstance(default, list) else str(default)
        action.help += f" (default: {shown})"


class NoteFormat(logging.Formatter):
    """``NAME.py: note: MESSAGE``, NAME the script running when it is said."""

    def format(self, record: logging.LogRecord) -> str:
        return f"{Path(sys.argv[0]).name}: note: {record.getMessage()}"


class Once(logging.Filter):
    """Each message once: a cluster's worker processes each say that numba
    compiles, and one line says it for all."""

    def __init__(self) -> None:
        super().__init__()
        self.said: set[str] = set()

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        new = message not in self.said
        self.said.add(message)
        return new


def show_notes() -> None:
    """Print what isoflow logs at level INFO (its ``isoflow`` logger) on
    stderr, as ``NAME.py: note: ...``. Python's default handler drops
    such records, and the first run after installing waits while numba
    compiles isoflow's passes (up to minutes) with only that note to
    explain the wait. Once per process: the gallery runs every example in
    one."""
    log = logging.getLogger("isoflow")
    if any(h.get_name() == "examples" for h in log.handlers):
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.set_name("examples")
    handler.setFormatter(NoteFormat())
    handler.addFilter(Once())
    log.addHandler(handler)
    log.setLevel(logging.INFO)


def outputs(args: argparse.Namespace, *names: str) -> list[Path]:
    """The paths of the example's outputs in OUT, checked before any work:
    one that exists is refused unless --force."""
    paths = [args.out / name for name in names]
    for path in paths:
        if path.exists() and not args.force:
            raise isoflow.IsoflowError(f"{path}: exists; pass --force to overwrite")
    return paths


def run(main) -> None:
    """Run an example's ``main``; bad input (an existing output without
    --force, a mesh that is not closed ...) is one line and exit status 2,
    as from the ``isoflow`` command, and so is standard output that cannot
    take what the example prints (``> /dev/full``, ``>&-``), which the
    command's own handling of standard output names; a closed pipe
    (``| head``) is no error."""
    # the command line's standard output: its failed writes are StdoutError, flushed before the example ends
    from isoflow.cli.main import StdoutError, drop_stdout, stdout_named

    name = Path(sys.argv[0]).name
    try:
        with stdout_named():
            main()
    except isoflow.IsoflowError as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        sys.exit(2)
    except BrokenPipeError:
        drop_stdout()
    except StdoutError as exc:
        print(f"{name}: error: standard output: cannot be written ({exc.strerror})", file=sys.stderr)
        drop_stdout()
        sys.exit(2)
