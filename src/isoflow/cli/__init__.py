"""The ``isoflow`` command line: one module per command (its options, its
work, its wording), :mod:`~isoflow.cli.inputs` for what every command reads,
:mod:`~isoflow.cli.main` for the parser, signals and exit statuses."""

from .main import build_parser, console, main

__all__ = ["build_parser", "console", "main"]
