"""What every example shares: its command line (an output directory,
--force), outputs that are not overwritten without --force, and one-line
errors. Not an example itself (the gallery skips files starting with _)."""

from __future__ import annotations

import argparse
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
    args = parser.parse_args()
    args.out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="isoflow-example-"))
    args.out.mkdir(parents=True, exist_ok=True)
    return args


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
    as from the ``isoflow`` command."""
    try:
        main()
    except isoflow.IsoflowError as exc:
        print(f"{Path(sys.argv[0]).name}: error: {exc}", file=sys.stderr)
        sys.exit(2)
