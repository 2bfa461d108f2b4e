"""The command line's entry point: the parser, signals, warnings and the
exit statuses every command shares.

Every command reads its input through :func:`isoflow.cli.inputs.load_input`,
hands arrays to the core, and prints either a readable table or one JSON
object. Bad input becomes one line on stderr and exit status 2; heavy
libraries (trimesh, matplotlib) are imported only by the commands that need
them, so that ``isoflow info`` starts fast; so are tqdm (the progress bars,
only on a terminal) and shtab (only by ``isoflow completion``).
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import functools
import sys
from collections.abc import Iterable, Iterator

from ..errors import IsoflowError, terminal_text
from . import completion, flow, genus, info, surface, voxelize

#: the commands in the order ``isoflow`` lists them
COMMANDS = (info, surface, voxelize, genus, flow, completion)
#: a signal this soon (seconds) after the last one raised as KeyboardInterrupt
#: is taken as the same request: recorded, not raised again
REPEAT_SECONDS = 1.0


def installed_version() -> str:
    """The installed package's version (its metadata, as pip sees it)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("isoflow")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "(not installed: no package metadata; pip install -e .)"


class VersionAction(argparse.Action):
    """``--version``: the metadata is read only when asked, not at every start."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"isoflow {installed_version()}")
        parser.exit()


def command_list(parser: argparse.ArgumentParser) -> str:
    """What ``isoflow`` alone prints: usage and one line per command."""
    commands = parser.commands  # type: ignore[attr-defined]
    width = max(map(len, commands))
    lines = [parser.format_usage().rstrip(), "", parser.description or "", "", "commands:"]
    lines += [f"  {name:<{width}}  {p.description}" for name, p in commands.items()]
    lines += ["", "'isoflow COMMAND -h' lists a command's options; 'isoflow --version' prints the version."]
    return "\n".join(lines)


class StdoutParser(argparse.ArgumentParser):
    """A parser whose help (``-h``) fails as the commands' output does.

    argparse drops an error writing its help and still ends with exit
    status 0, so ``isoflow info -h > /dev/full`` lost the help without a
    word; written to standard output here, the failure reaches
    :func:`main`, which names standard output in one line (exit status 2).
    Its messages to stderr are written as argparse writes them.

    Examples
    --------
    >>> import contextlib, io
    >>> out = io.StringIO()
    >>> with contextlib.redirect_stdout(out):
    ...     StdoutParser(prog="tool").print_help()
    >>> out.getvalue().splitlines()[0]
    'usage: tool [-h]'
    """

    def _print_message(self, message, file=None):
        if message and file is not None and file is sys.stdout:
            file.write(message)
            return
        super()._print_message(message, file)


class CommandParser(StdoutParser):
    """A command's parser. A bad value of an option (argparse's
    ``argument --resolution: ...``: a type, a choice, options that exclude
    each other) is one line on stderr and exit status 2, as every other bad
    input; a command line of the wrong shape (an argument missing or not
    known) also shows the usage."""

    def parse_known_args(self, args=None, namespace=None):
        # error() reads what the options took: --labels' optional SPEC may have taken the input
        self.namespace = argparse.Namespace() if namespace is None else namespace
        twice = repeated_option(self, args or [])
        if twice:
            self.error(twice)
        return super().parse_known_args(args, self.namespace)

    def error(self, message: str):
        if message.startswith("argument "):  # names the option and what is wrong with its value
            self.exit(2, f"{self.prog}: error: {message}\n")
        from .labels import reads_as_choice

        taken = getattr(getattr(self, "namespace", None), "labels", None)
        if taken not in (None, "all") and message.endswith("required: input") and not reads_as_choice(taken):
            # `info --labels seg.nii.gz`: the optional SPEC took the input, which is then "missing"
            self.exit(2, f"{self.prog}: error: no input: --labels took {taken!r} as its labels; give the input "
                         f"before --labels ({self.prog} {taken} --labels) or a choice after it (--labels 3,7)\n")
        super().error(message)


#: the options that name a file a command writes (dests): given twice, the
#: first would be dropped unwritten
OUTPUT_OPTIONS = ("output", "out", "csv", "png")


def repeated_option(parser: argparse.ArgumentParser, words: list[str]) -> str | None:
    """argparse's message for the first option naming an output file that
    is given twice in ``words`` (``-o a.ply -o b.ply``), None where none is.
    argparse keeps the last and drops the first without a word, so the file
    asked for first was never written (a compiler refuses ``-o`` twice for
    the same reason). A setting given twice keeps its last value, as
    argparse and most tools do, so that an alias or a script can give a
    default that the command line then replaces
    (``info x --connectivity 6 --connectivity 26`` answers at 26)."""
    def option(word: str) -> tuple[str, argparse.Action | None]:
        name = word.split("=", 1)[0] if word.startswith("--") else word[:2]
        return name, parser._option_string_actions.get(name)  # (argparse's own table: exact, as allow_abbrev=False)

    seen: dict[argparse.Action, str] = {}
    for i, word in enumerate(words):
        if word == "--":  # what follows is positional
            break
        name, action = option(word)
        if action is None or action.dest not in OUTPUT_OPTIONS:
            continue
        value = words[i + 1] if word == name and i + 1 < len(words) and option(words[i + 1])[1] is None else None
        given = word if value is None else f"{word} {value}"
        if action in seen:
            return (f"argument {'/'.join(action.option_strings)}: given twice ({seen[action]}, then {given}); "
                    f"give it once")
        seen[action] = given
    return None


def unrecognized(parser: argparse.ArgumentParser, extra: list[str]) -> str:
    """argparse's "unrecognized arguments", with the command's option that
    an unknown one most likely meant (``-o`` of ``flow``: ``--out``)."""
    options = [o for action in parser._actions for o in action.option_strings]
    meant = []
    for word in extra:
        if not word.startswith("-") or word in options:
            continue
        name = word.split("=")[0]
        stem = name.lstrip("-")
        # a shortening (`--no`, `-o` of flow) names the options it begins; a typo the closest one
        begun = [o for o in options if o.startswith("--") and o[2:].startswith(stem)]
        close = begun if begun and (name.startswith("--") or len(stem) == 1) else difflib.get_close_matches(
            name, options, n=1, cutoff=0.7)
        if close:
            meant.append(f"{name}: did you mean {' or '.join(close[:2])}?")
    return f"unrecognized arguments: {' '.join(extra)}" + (f" ({'; '.join(meant)})" if meant else "")


def refuse_negative_choice(command: argparse.ArgumentParser | None, args: argparse.Namespace,
                           extra: list[str]) -> None:
    """One line for ``--labels -2,3``: argparse reads a choice that starts
    with a minus sign (other than one number) as an unknown option and
    leaves ``--labels`` without it; the choice is written ``--labels=-2,3``."""
    from .labels import reads_as_choice

    if command is None or getattr(args, "labels", None) != "all":
        return
    for word in extra:
        if word.startswith("-") and reads_as_choice(word):
            command.exit(2, f"{command.prog}: error: --labels {word}: a choice that starts with a minus sign is "
                            f"written --labels={word} (else it reads as an option)\n")


def add_command(sub: argparse._SubParsersAction, name: str, summary: str) -> argparse.ArgumentParser:
    """A sub-command whose one-line summary is both its entry in the command
    list and the description of its own -h."""
    # allow_abbrev=False: argparse took any unique prefix as the option (`surface --out` as --output, `info --no`
    # as --no-surfaces), so a script's shortening silently changed meaning when a later option shared it
    return sub.add_parser(name, help=summary, description=summary, allow_abbrev=False)


#: the help of -q/--quiet, which every command takes, after its name or before it
QUIET_HELP = ("no progress bars or notes on stderr (errors, warnings that the result differs from what was "
              "asked, and the note saying why a result is empty, are still printed)")


def build_parser() -> argparse.ArgumentParser:
    """The ``isoflow`` parser with every command's options (the docs' command
    line page is generated from it)."""
    parser = StdoutParser(
        prog="isoflow",
        description="Digital curvature, Euler characteristic, genus and curvature flow of voxel objects (Imiya 2013).",
        allow_abbrev=False,
    )
    parser.add_argument("--version", action=VersionAction, help="print the installed version and exit")
    # the options every command shares are taken before the command too (`isoflow -q info x.npy`), meaning the same
    parser.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands", parser_class=CommandParser)
    parser.commands = sub.choices  # type: ignore[attr-defined]  # name -> sub-command parser, in order
    for command in COMMANDS:
        command.add_parser(sub, add_command)
    for p in sub.choices.values():
        # no default of its own: a command's parser sets every default it has over what came before the command
        p.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help=QUIET_HELP)
    return parser


@contextlib.contextmanager
def quiet_stderr(quiet: bool) -> Iterator[None]:
    """--quiet: informational stderr (library warnings, log records below
    ERROR) is dropped while the command runs; errors still reach stderr as
    one line. Restored afterwards, for callers of :func:`main` in-process."""
    if not quiet:
        yield
        return
    import logging
    import warnings

    before = logging.root.manager.disable
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        logging.disable(logging.WARNING)
        try:
            yield
        finally:
            logging.disable(before)


def log_note(record) -> str:
    """A library's log record in one line: its logger, the message's first
    line and the exception it carried (never the traceback)."""
    lines = record.getMessage().strip().splitlines()
    text = f"{record.name}: {lines[0] if lines else record.levelname.lower()}"
    exc = record.exc_info[1] if record.exc_info else None
    return text + (f" ({type(exc).__name__}: {exc})" if exc is not None else "")


@contextlib.contextmanager
def log_records_as_notes(args: argparse.Namespace) -> Iterator[None]:
    """Log records of the libraries a command uses (trimesh's "unable to
    load image!" for a texture that is missing, with its traceback) as one
    ``note:`` line each, each said once; --quiet drops them. Without a
    handler, Python's last resort prints every record and its traceback."""
    import logging

    class Notes(logging.Handler):
        def __init__(self) -> None:
            super().__init__(logging.WARNING)
            self.said: set[str] = set()

        def emit(self, record: logging.LogRecord) -> None:
            text = log_note(record)
            if not args.quiet and text not in self.said:
                self.said.add(text)
                print(f"isoflow {args.command}: note: {terminal_text(text)}", file=sys.stderr)

    handler = Notes()
    logging.root.addHandler(handler)
    try:
        yield
    finally:
        logging.root.removeHandler(handler)


@contextlib.contextmanager
def termination_as_interrupt(received: list) -> Iterator[None]:
    """Treat SIGTERM (``kill``, a batch system's time limit, a closing
    terminal's SIGHUP) as Ctrl-C while a command runs: the same clean-up
    runs (temporary files and the flow's staging directory are removed, an
    existing output stays as it was) and the signal's number is appended
    to ``received``. Python's default for SIGTERM is to die at once, which
    leaves the temporary files behind. A signal within
    :data:`REPEAT_SECONDS` of the last one raised is recorded but not
    raised: it would interrupt the clean-up. Only the main thread may set
    handlers; elsewhere (a command run from a library thread) nothing
    changes."""
    import math
    import signal
    import threading
    import time

    from ..scale.cancel import request_stop

    wanted = [signal.SIGINT, signal.SIGTERM] + ([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    raised = [-math.inf]  # time.monotonic() of the last signal raised as KeyboardInterrupt

    def interrupt(signum, frame):
        # kept as well as raised: a library may swallow the KeyboardInterrupt
        # (trimesh's import guards), and no output is then renamed into place
        # (isoflow.mesh.outputs.SIGNALS) and the command still ends as
        # interrupted; compiled work on other threads stops at its next poll
        received.append(signum)
        request_stop()
        # one within a second of the last one raised is the same request
        # (`timeout` signals the command and then its process group; people
        # press Ctrl-C twice): raised again, it would cut short the clean-up
        # that the first began (a temporary file left behind)
        now = time.monotonic()
        if now - raised[0] >= REPEAT_SECONDS:
            raised[0] = now
            raise KeyboardInterrupt

    def unraisable(report):
        # the KeyboardInterrupt raised where Python cannot raise it (a weakref
        # callback, a finaliser during garbage collection) is reported with a
        # traceback and dropped; the signal is kept above, so the command
        # still ends as interrupted, and the report would only alarm
        if not (received and isinstance(report.exc_value, KeyboardInterrupt)):
            hook(report)

    before = {sig: signal.signal(sig, interrupt) for sig in wanted}
    hook, sys.unraisablehook = sys.unraisablehook, unraisable
    ended = False
    try:
        yield
        ended = True
    finally:
        sys.unraisablehook = hook
        restore_handlers(before, raise_late=ended)


def restore_handlers(before: dict, raise_late: bool = True) -> None:
    """Put back every signal handler of ``before`` (signal: handler).

    ``signal.signal`` first runs the handler of a signal still pending (one
    that came as the command ended), and :func:`termination_as_interrupt`'s
    raises KeyboardInterrupt: raised from the first handler put back, it
    left the others in place after the command had returned, and a later
    SIGTERM then raised KeyboardInterrupt as Python exited (status 130, not
    143). It is raised once all are back, where the command ended without
    an exception (``raise_late``); the signal is recorded either way."""
    import signal

    late = None
    for sig, handler in before.items():
        while True:
            try:
                signal.signal(sig, handler)
                break
            except KeyboardInterrupt as exc:  # the pending signal's handler ran; it is not pending any more
                late = exc
    if late is not None and raise_late:
        raise late


@contextlib.contextmanager
def warnings_as_lines(args: argparse.Namespace) -> Iterator[None]:
    """Each :class:`~isoflow.errors.IsoflowWarning` as one ``warning:`` line
    on stderr (a :class:`~isoflow.errors.MeshNote` as a ``note:`` line),
    without the source line Python adds; others as Python shows them.
    --quiet drops the notes and other libraries' warnings, not isoflow's
    warnings: each says the result differs from what was asked (a voxel
    size a format cannot keep, a rotation left out). A line said once is not
    said again."""
    import warnings

    from ..errors import IsoflowWarning, MeshNote

    with warnings.catch_warnings():
        shown = warnings.showwarning
        said: set[str] = set()  # (a file's metadata read twice, by two passes, says the same line once)

        def show(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, IsoflowWarning):
                text = (f"isoflow {args.command}: {'note' if issubclass(category, MeshNote) else 'warning'}: "
                        f"{terminal_text(str(message))}")
                if text not in said:
                    said.add(text)
                    print(text, file=sys.stderr)
            else:
                shown(message, category, filename, lineno, file, line)

        warnings.simplefilter("always", IsoflowWarning)
        if args.quiet:  # a warning says the result differs from what was asked: --quiet drops notes alone
            warnings.simplefilter("ignore", MeshNote)
        warnings.showwarning = show
        yield


#: the path arguments of the commands, by their attribute, as the command line spells them
PATH_ARGUMENTS = {"input": "input", "mesh": "mesh", "output": "-o/--output", "csv": "--csv", "png": "--png"}


def refuse_empty_paths(args: argparse.Namespace) -> None:
    """An empty path (an unset shell variable: ``--csv "$OUT"``) is refused
    in one line naming the argument: ``--csv ''`` and ``--png ''`` read as
    not given and wrote nothing with exit status 0, and an empty input or
    ``-o`` was named as ``.``, the directory ``Path('')`` is. (``flow --out
    ''`` says it in flow's own words.)"""
    for key, spelled in PATH_ARGUMENTS.items():
        value = getattr(args, key, None)
        if value == "" or isinstance(value, list) and "" in value:
            raise IsoflowError(f"{spelled} '': an empty file name; give the file's name")


def refuse_output_over_input(args: argparse.Namespace) -> None:
    """An output that is the command's own input (the same file, and the
    same dataset of an HDF5 or zarr file, or the whole file of which a
    dataset or a layer of a .seg.nrrd is read) is refused, --force or not:
    the file being read would be replaced by what was made from it."""
    import os

    from ..mesh.formats.registry import split_dataset
    from ..mesh.outputs import refuse_unusable_output

    meshes = getattr(args, "mesh", None)
    meshes_given = meshes if isinstance(meshes, list) else [meshes]
    inputs = [getattr(args, "input", None)] + meshes_given
    # (flow's --out too: a directory, which may be the input zarr store itself)
    for key in ("output", "csv", "png", "out"):
        out = getattr(args, key, None)
        if not out or out == "-":
            continue
        out_file, out_set = split_dataset(out)
        refuse_unusable_output(out_file, directory=key == "out")  # before exists() below raises on it
        for name in filter(None, inputs):
            in_file, in_set = split_dataset(name)
            # os.path's tests: an input that cannot be looked at is not the output, and its reader says why
            # (a directory is only ever an input as a zarr store: given as a mesh, its reader refuses it as such)
            if name not in meshes_given and os.path.isdir(in_file) and in_file.resolve() in out_file.resolve().parents:
                # a zarr store is a directory: files written into it (flow --out STORE/run, surface --labels
                # -o STORE/) change the input, --force or not
                raise IsoflowError(f"{out}: lies inside the input {name}; write the output elsewhere (--force "
                                   "replaces an output, never the input)")
            if out_set is not None and out_set != in_set:  # another dataset of the file: the input's is kept
                continue
            both = os.path.exists(out_file) and os.path.exists(in_file)
            if os.path.samefile(out_file, in_file) if both else out_file.resolve() == in_file.resolve():
                raise IsoflowError(f"{out}: is the input {name}; write the output to another file (--force "
                                   "replaces an output, never the input)")
    directory = getattr(args, "out", None) if args.command == "flow" else None
    if directory and args.input:
        # `flow DIR/step_003.npy --out DIR --force` would remove (or, with
        # --volumes, replace) its own input once the run is in place
        from ..flow.files import replaced_by_run

        if replaced_by_run(directory, split_dataset(args.input)[0]):
            raise IsoflowError(f"{args.input}: is the input, and flow --out {directory} replaces the step files, "
                               "flow.csv and pictures there; give --out another directory (--force replaces an "
                               "output, never the input)")


def interrupted(signals: list, what: str) -> int:
    """The last line of a signalled command (``isoflow: interrupted`` for
    SIGINT, ``isoflow: terminated`` for the others, with ``what`` where a
    write names its file) and its exit status: 128 + the signal's number,
    the shell's convention."""
    import signal

    sig = signals[0] if signals else signal.SIGINT
    how = "interrupted" if sig == signal.SIGINT else "terminated"
    print(f"isoflow: {how}" + (f": {terminal_text(what)}" if what else ""), file=sys.stderr)
    forget_escaped_interrupt()
    return 128 + int(sig)


def forget_escaped_interrupt() -> None:
    """Clear CPython's record that a KeyboardInterrupt left code it ran
    from source text, once the command has handled that interrupt.

    CPython marks the interrupt as unhandled when it leaves an ``exec`` or
    ``eval`` of a string, even though a caller catches it. A signal raised
    while a library is imported lands there often: dask.array imports
    scipy, whose ``exec("from numpy import *")`` runs numpy's imports, and
    namedtuples and dataclasses are made by ``eval``/``exec`` of their
    source. Under ``python -m`` the interpreter then ignores the exit status
    the command chose (143 for SIGTERM) and ends by SIGINT instead (130).
    The record is reset at the start of every evaluation of a string, so
    evaluating an empty one clears it; an interrupt that does escape the
    command later is recorded again."""
    exec("", {})


class StdoutError(OSError):
    """A write to standard output that failed, other than a closed pipe
    (a full disk or quota under a redirection, ``> /dev/full``): such an
    error names no file."""


class NamedStdout:
    """Standard output whose write errors are :class:`StdoutError`, so that
    the command line can name standard output as what failed."""

    def __init__(self, stream) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        return guard_stdout(self.stream.write, text)

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def write_ascii(self, pieces: Iterable) -> None:
        """Pieces of ASCII text, each bytes-like, written as they are to
        the stream's buffer of bytes where its encoding writes ASCII as
        ASCII (after the text written before them), else decoded and
        written as text; each piece is written before the next is asked
        for."""
        buffer = getattr(self.stream, "buffer", None)
        if buffer is None or not ascii_as_itself(getattr(self.stream, "encoding", None)):
            for piece in pieces:
                self.write(str(piece, "ascii"))
            return
        self.flush()
        for piece in pieces:
            guard_stdout(buffer.write, piece)

    def flush(self) -> None:
        guard_stdout(self.stream.flush)

    def __getattr__(self, name: str):
        return getattr(self.stream, name)


class ClosedStdout:
    """Standard output where the process started without one: each write
    fails as a write to a closed file descriptor does."""

    def write(self, text: str) -> int:
        import errno
        import os

        raise OSError(errno.EBADF, os.strerror(errno.EBADF))

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False


@functools.cache
def ascii_as_itself(encoding: str | None) -> bool:
    """Whether text in ``encoding`` holds printable ASCII as those bytes
    (UTF-8, Latin-1, cp1252; not UTF-16).

    Examples
    --------
    >>> ascii_as_itself("utf-8"), ascii_as_itself("utf-16"), ascii_as_itself(None)
    (True, False, False)
    """
    printable = bytes(range(32, 127))
    try:
        return encoding is not None and printable.decode("ascii").encode(encoding) == printable
    except (LookupError, UnicodeError):
        return False


def guard_stdout(call, *args):
    """``call(*args)``, a write to standard output, with its OSError raised
    as :class:`StdoutError` (BrokenPipeError as it is: ``| head`` is no error)."""
    try:
        return call(*args)
    except BrokenPipeError:
        raise
    except OSError as exc:
        raise StdoutError(exc.errno, exc.strerror) from None


@contextlib.contextmanager
def stdout_named() -> Iterator[None]:
    """Run a command with :class:`NamedStdout` in place of ``sys.stdout``,
    flushed before it is put back (block-buffered output to a file fails
    only when flushed, which would be as the interpreter exits), and a
    character its encoding lacks written as a backslash escape."""
    stream = sys.stdout
    if stream is None:
        # started with standard output closed (`>&-`): print() drops what it
        # is given when sys.stdout is None, and the command said nothing and
        # ended with exit status 0
        sys.stdout = NamedStdout(ClosedStdout())
        try:
            yield
        finally:
            sys.stdout = stream
        return
    errors = getattr(stream, "errors", None)
    if errors == "strict" and hasattr(stream, "reconfigure"):
        # an encoding without a character printed (the class (0,0,∅) in
        # cp1252, Windows' for a redirection; a path's ü in ASCII) ended the
        # command in UnicodeEncodeError: written escaped, as stderr does
        stream.reconfigure(errors="backslashreplace")
    sys.stdout = NamedStdout(stream)
    try:
        yield
        sys.stdout.flush()
    finally:
        sys.stdout = stream
        if errors == "strict" and hasattr(stream, "reconfigure"):
            stream.reconfigure(errors=errors)


class SparedStderr:
    """Standard error whose write failures are dropped, and which drops
    what it is given where the process started without one.

    A note, a warning or an error line that stderr cannot take (a full
    disk or quota under ``2> log``, a descriptor closed by ``2>&-``) is
    lost; raised where it was printed, it ended a command that had nothing
    wrong with its input or its result in a traceback, exit status 1 and
    no output (the report comes after a note). Where Python has no stderr
    at all (``sys.stderr`` None), ``print(file=sys.stderr)`` writes to
    standard output, into a ``--json`` report: that is dropped too.

    Examples
    --------
    >>> import io
    >>> class Full(io.StringIO):
    ...     def write(self, text):
    ...         raise OSError(28, "No space left on device")
    >>> SparedStderr(Full()).write("a note"), SparedStderr(None).write("a note"), SparedStderr(None).isatty()
    (6, 6, False)
    """

    def __init__(self, stream) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        if self.stream is None:
            return len(text)
        try:
            return self.stream.write(text)
        except OSError:
            self.lost()
            return len(text)

    def flush(self) -> None:
        if self.stream is None:
            return
        try:
            self.stream.flush()
        except OSError:
            self.lost()

    def isatty(self) -> bool:
        return self.stream is not None and self.stream.isatty()

    def lost(self) -> None:
        """Point the stream's descriptor at the null device: what the
        stream still buffers would fail again as the interpreter exits."""
        import os

        with contextlib.suppress(OSError, ValueError, AttributeError):  # a stand-in without a descriptor
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self.stream.fileno())
            os.close(null)

    def __getattr__(self, name: str):
        return getattr(self.stream, name)


@contextlib.contextmanager
def stderr_spared() -> Iterator[None]:
    """Run with :class:`SparedStderr` in place of ``sys.stderr``, put back
    afterwards (for callers of :func:`main` in-process)."""
    stream = sys.stderr
    sys.stderr = SparedStderr(stream)
    try:
        yield
    finally:
        sys.stderr = stream


def drop_stdout() -> None:
    """Point standard output at the null device: what it still buffers
    would fail again as the interpreter exits, with a second message."""
    import os

    if sys.stdout is not None:  # (None: the process started without one)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def parse_command_line(parser: argparse.ArgumentParser,
                       argv: list[str] | None) -> tuple[argparse.Namespace, list[str]] | int:
    """``parser.parse_known_args(argv)``, or the exit status where the
    command line is answered before any command runs: ``isoflow`` alone
    lists the commands (0), and what ``isoflow``, ``-h`` or ``--version``
    print that standard output cannot take (a full disk, ``>&-``) is one
    line naming standard output (2), as a command's output is, not a
    traceback nor a silent exit status 0. ``-h`` and ``--version`` end in
    SystemExit(0), as argparse ends them, once what they printed is
    flushed (block-buffered output fails only then).

    Examples
    --------
    >>> parser = build_parser()
    >>> args, extra = parse_command_line(parser, ["info", "x.npy", "--json"])
    >>> args.command, args.input, extra
    ('info', 'x.npy', [])
    """
    words = sys.argv[1:] if argv is None else argv
    named = next((word for word in words if word in parser.commands), None)  # type: ignore[attr-defined]
    try:
        with stdout_named():
            try:
                args, extra = parser.parse_known_args(argv)
            except SystemExit as done:
                if not done.code:
                    sys.stdout.flush()
                raise
            if args.command is None and not extra:  # `isoflow` alone: what it can do, not an error
                print(command_list(parser))
                return 0
    except BrokenPipeError:  # `isoflow -h | head`: not an error
        drop_stdout()
        return 0
    except StdoutError as exc:
        prog = "isoflow" if named is None else f"isoflow {named}"
        print(f"{prog}: error: standard output: cannot be written ({exc.strerror})", file=sys.stderr)
        drop_stdout()
        return 2
    return args, extra


def main(argv: list[str] | None = None) -> int:
    """Run one ``isoflow`` command line; returns its exit status (0 done,
    1 a written file did not read back as counted, 2 bad input, 128 + the
    signal's number when interrupted). What standard error cannot take is
    dropped (:class:`SparedStderr`): the exit status is the command's."""
    with stderr_spared():
        return command_line(argv)


def command_line(argv: list[str] | None) -> int:
    """:func:`main` with standard error as :func:`stderr_spared` leaves it."""
    from ..mesh import outputs
    from ..mesh.outputs import SIGNALS
    from ..scale import compiled
    from ..scale.cancel import clear_stop

    parser = build_parser()
    parsed = parse_command_line(parser, argv)
    if isinstance(parsed, int):
        return parsed
    args, extra = parsed
    if extra:  # the command's usage, not isoflow's, and the option meant where one is close
        command = parser.commands.get(args.command) if args.command else None  # type: ignore[attr-defined]
        refuse_negative_choice(command, args, extra)
        (command or parser).error(unrecognized(command or parser, extra))
    args.parser = parser
    terminated = SIGNALS  # the signals received (what the writers look at before renaming)
    terminated.clear()
    clear_stop()
    outputs.MADE = set()  # removed as the command ends where no writer's clean-up reached them

    def compiling(message):  # numba's first run after installing: a note, not silence
        print(f"isoflow {args.command}: note: {message}", file=sys.stderr, flush=True)

    before = compiled.on_first_compile
    compiled.on_first_compile = None if args.quiet else compiling
    try:
        with quiet_stderr(args.quiet), warnings_as_lines(args), log_records_as_notes(args), \
                termination_as_interrupt(terminated), stdout_named():
            if args.command != "completion" and getattr(args, "threads", None) is None:
                compiled.check_env_threads()  # the default of --threads, said before any file is read
            refuse_empty_paths(args)
            refuse_output_over_input(args)
            status = args.func(args)
            if terminated:  # a signal a library swallowed: the command still ends as interrupted
                raise KeyboardInterrupt
            return status
    except IsoflowError as exc:  # in the command line's words (its options) where they differ from Python's
        # one line, as the exit status 2 promises: a path's line break, tab or escape sequence is shown escaped,
        # not acted on by the terminal, and a name's byte that is not UTF-8 as \xNN, as the reports write it
        print(f"isoflow {args.command}: error: {terminal_text(str(exc.command_line or exc))}", file=sys.stderr)
        return 2
    except MemoryError:
        name = getattr(args, "input", None) or getattr(args, "mesh", "")
        print(f"isoflow {args.command}: error: out of memory on {terminal_text(name)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # a write names its file (mesh.outputs)
        return interrupted(terminated, str(exc))
    except BrokenPipeError:  # `isoflow info ... | head`: not an error
        drop_stdout()
        return 0
    except StdoutError as exc:
        print(f"isoflow {args.command}: error: standard output: cannot be written ({exc.strerror})", file=sys.stderr)
        drop_stdout()
        return 2
    except Exception:
        if not terminated:
            raise
        # a signal's KeyboardInterrupt raised where it cannot travel (in a
        # finaliser that runs while numba boxes a compiled pass's result)
        # surfaces as another exception, a SystemError: after a signal, the
        # command ends as signalled whatever the exception
        return interrupted(terminated, "")
    finally:
        outputs.remove_temporaries_left()
        compiled.on_first_compile = before
        terminated.clear()  # said: later writes in this process (a library's caller) are not held back
        clear_stop()


def console() -> None:
    """The ``isoflow`` command: :func:`main`, then exit without the
    interpreter's last garbage collection, which walks every object (numba's
    many, once it is loaded) only to find nothing to collect.

    What the start-up imports (Python's modules, NumPy, isoflow's, then
    numba's when a command loads it) lives until the process exits, so it
    is frozen as soon as it is made: otherwise each collection of the oldest
    generation walks all of it again (numba's, once loaded, most of all),
    and whether a short command pays one more such collection turns on a
    few allocations anywhere in it."""
    import gc

    from ..scale import compiled

    gc.freeze()
    compiled.on_numba_import = gc.freeze
    code = main()
    gc.freeze()
    sys.exit(code)
