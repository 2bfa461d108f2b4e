"""Output files: checked before any work, written whole or not at all.

Every command checks each file it will write (``-o``, ``--png``, ``--out``)
up front: a bad picture path must not be found after minutes of meshing,
and an existing file is never replaced without ``force``.

Every file is then written through :func:`atomic_path` or
:func:`atomic_write`: into a temporary file beside the target, flushed to
the disk (``fsync``), and renamed over the target only when complete. A
full disk, a read-only or vanished directory or an interruption therefore
leaves the previous file byte for byte as it was and no partial or
temporary file behind; the error becomes one :class:`IsoflowError` line
naming the file and the cause. Writers of new formats (volumes, pictures,
zarr stores) should go through the same two functions.

Files that belong together (a mesh and its picture, a file per label) are
written inside one :func:`output_set`: each goes to its temporary name as
above (flushed with the others at the set's end, :func:`flush_set`), and
none is renamed into place until every one is written; a failure
or an interruption before then removes them all and leaves every previous
file as it was, so a folder never holds new files beside old ones.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import stat
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path

from ..errors import IsoflowError, NotAPath, check_switch, refuse_empty_path, value_kind, warn

#: marks temporary files and directories (``.NAME.isoflow-tmp-HOST-PID-RANDOM.SUFFIX``)
TEMP_MARK = ".isoflow-tmp-"
#: marks a previous output moved aside to make room for its replacement
#: (``.NAME.isoflow-old-HOST-PID-RANDOM.SUFFIX``, :func:`aside_name`): whole,
#: and where its name is empty the only copy of it (:func:`remove_abandoned`)
ASIDE_MARK = ".isoflow-old-"
#: suffixes of formats that are not written, each with the written one that
#: holds the same thing, named where the output's suffix is refused
NEAR_SUFFIXES = {".gltf": (".glb", "binary glTF, the same scene in one file")}


def check_output_path(
    path: str | os.PathLike, force: bool = False, suffixes: tuple[str, ...] = (), what: str = "output"
) -> Path:
    """The output file as a Path, checked before any work is done: it ends in
    one of ``suffixes`` (any case; none: any name), is not a directory, does
    not exist unless ``force``, and its directory exists and is writable."""
    if not isinstance(path, (str, os.PathLike)):  # (os.fspath's TypeError names no argument)
        raise NotAPath(f"the {what} path must be a str or os.PathLike, got {value_kind(path)}")
    refuse_empty_path(path, f"the {what} path")
    check_switch(force, "force", str(path))
    refuse_directory_spelling(path, what)  # before Path(), which drops the slash
    path = Path(path)
    remove_abandoned(path)  # an output a killed command left aside is put back: then it exists, as it did
    refuse_unusable_output(path)
    # a directory before its suffix: "out: surface must end in .ply or ..." named no directory
    if path.is_dir():  # --force must not mean "replace a directory"
        raise IsoflowError(f"{path}: is a directory; give a file name for the {what}")
    if suffixes and path.suffix.lower() not in suffixes:
        refuse_nameless(path, suffixes, what)
        raise IsoflowError(f"{path}: {what} must end in {' or '.join(suffixes)}{near_suffix_hint(path, suffixes)}")
    if (path.exists() or path.is_symlink()) and not force:  # a dangling link is there too
        raise IsoflowError.worded(f"{path}: exists; pass force=True to overwrite",
                                      f"{path}: exists; pass --force to overwrite")
    check_writable_dir(path.parent, f"the {what} {path.name}")
    return path


def refuse_nameless(path: str | os.PathLike, suffixes: Iterable[str], what: str = "output") -> None:
    """Refuse an output named ``-`` or by one of ``suffixes`` alone.

    ``-`` is the shell's word for stdout, which no file is streamed to; a
    name that is a suffix alone (``.ply``, an empty ``$name`` in
    ``$name.ply``) would be written as a hidden file of no suffix.

    Parameters
    ----------
    path : str or os.PathLike
        The output as given.
    suffixes : iterable of str
        The suffixes the output may end in, lower case with their dot; the
        first names the example in the refusal.
    what : str
        What is written (``"surface"``, ``"volume"``), named in the refusal.

    Raises
    ------
    IsoflowError
        For ``-`` or a name that is one of ``suffixes`` (any case).

    Examples
    --------
    >>> refuse_nameless("seg.nii.gz", (".nii.gz",), "volume")
    >>> refuse_nameless(".nii.gz", (".npy", ".nii.gz"), "volume")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: .nii.gz: is a suffix alone, with no name before it; give the file's name, e.g. volume.nii.gz
    """
    suffixes = tuple(suffixes)
    path = Path(path)
    if str(path) == "-":
        raise IsoflowError(f"-: a {what} is written to a file, not to stdout; give its name, e.g. "
                           f"{what.split()[-1]}{suffixes[0] if suffixes else ''}")
    if path.name.lower() in suffixes:
        raise IsoflowError(f"{path}: is a suffix alone, with no name before it; give the file's name, e.g. "
                           f"{path.with_name(what.split()[-1] + path.name)}")


def near_suffix_hint(path: Path, suffixes: tuple[str, ...]) -> str:
    """The written format that holds what a refused suffix names, as the end
    of the refusal, or "".

    Parameters
    ----------
    path : Path
        The output, whose suffix is not among ``suffixes``.
    suffixes : tuple of str
        The suffixes the output may have.

    Returns
    -------
    str
        ``"; write NAME.glb (binary glTF, ...)"`` where the suffix has a
        written near kin among ``suffixes`` (a ``.gltf`` is a ``.glb``'s
        JSON and buffers in separate files), else "".

    Examples
    --------
    >>> near_suffix_hint(Path("out.gltf"), (".ply", ".glb"))
    '; write out.glb (binary glTF, the same scene in one file)'
    >>> near_suffix_hint(Path("out.vtk"), (".ply", ".glb"))
    ''
    """
    near = NEAR_SUFFIXES.get(path.suffix.lower())
    if near is None or near[0] not in suffixes:
        return ""
    return f"; write {path.with_suffix(near[0]).name} ({near[1]})"


def refuse_directory_spelling(path: str | os.PathLike, what: str = "output") -> None:
    """Refuse a file output spelled as a directory, with a trailing slash.

    Parameters
    ----------
    path : str or os.PathLike
        The output as the user gave it.
    what : str
        What the file holds, for the message ("surface", "volume").

    Raises
    ------
    IsoflowError
        Naming the path: ``Path`` drops the slash, so ``-o out.npz/``
        quietly wrote a file ``out.npz`` where the user meant a directory.
    """
    text = str(path)
    if text.endswith(("/", os.sep)) and text.rstrip("/" + os.sep):  # "/" alone is the root, refused as a directory
        raise IsoflowError(f"{text}: a trailing slash names a directory, but the {what} is a file; "
                           "give its file name without the slash")


def file_suffix(name: str, others: Iterable[str] = ()) -> str | None:
    """The mesh or volume suffix (or one of ``others``, lower case) that
    ``name`` ends in (the longest, in lower case), None where it ends in
    none or is the suffix alone: a directory to be made under such a name
    (``flow --out X.ply``, ``surface --labels -o out.ply/``) was most
    likely meant as a file, and a program that lists ``*.ply`` would take
    it for one.

    Examples
    --------
    >>> file_suffix("steps.nii.gz"), file_suffix("OUT.PLY"), file_suffix("run"), file_suffix(".ply")
    ('.nii.gz', '.ply', None, None)
    >>> file_suffix("flow.CSV"), file_suffix("flow.CSV", others=(".csv",))
    (None, '.csv')
    """
    from .formats.registry import volume_suffixes
    from .load import MESH_SUFFIXES

    lower = name.lower()
    return max((s for s in (*MESH_SUFFIXES, *volume_suffixes(), *others) if lower.endswith(s) and lower != s),
               key=len, default=None)


def refuse_unusable_output(path: str | os.PathLike, directory: bool = False) -> None:
    """Refuse, in one line and before any work, an output whose name the
    file system cannot take (longer than its limit, 255 bytes on most) or
    that is a device, a pipe or a socket (or a link to one: ``/dev/stdout``).

    Parameters
    ----------
    path : str or os.PathLike
        The output.
    directory : bool
        ``path`` names a directory for the outputs (``flow --out DIR``):
        the line asks for one, not for a file name.

    Raises
    ------
    IsoflowError
        Naming the path and the cause: ``Path.exists`` raised the bare
        ``OSError`` (a traceback on the command line) for a name too long
        or one in a directory that may not be searched;
        a file is written beside its target and renamed over it, so
        ``-o /dev/null --force`` run as root replaced the system's
        ``/dev/null`` with a regular file.
    """
    try:
        mode = os.stat(path).st_mode  # the link's target: /dev/stdout is a link to a pipe or terminal
    except OSError as exc:
        if exc.errno not in (errno.ENOENT, errno.ENOTDIR):
            # a name too long, a directory on the way that may not be searched (permission denied)
            raise IsoflowError(f"{path}: cannot be an output ({exc.strerror})") from None
        return  # missing, or a dangling link: a new file is made
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        if directory:
            raise IsoflowError(f"{path}: is a device, pipe or socket, not a directory; give a directory")
        raise IsoflowError(f"{path}: is a device, pipe or socket, not a file; an output is written beside it and "
                           "renamed over it, which would replace it: give a file name")
    if names_open_file(path):
        if directory:
            raise IsoflowError(f"{path}: names an open file of this process (standard output, a descriptor), "
                               "not a directory; give a directory")
        # standard output redirected to a file is a regular file at the end
        # of the link: renamed over, /dev/stdout (run as root) became a file
        raise IsoflowError(f"{path}: names an open file of this process (standard output, a descriptor), not a "
                           "file; an output is written beside it and renamed over it, which would replace the "
                           "link: give a file name")


def names_open_file(path: str | os.PathLike) -> bool:
    """Whether ``path`` reaches a file through the kernel's links to a
    process's open files (``/dev/stdout``, ``/dev/fd/1``,
    ``/proc/self/fd/1``) rather than by its name.

    Examples
    --------
    >>> names_open_file("/proc/self/fd/1"), names_open_file("out.csv")
    (True, False)
    """
    absolute = os.path.abspath(path)
    if os.path.realpath(os.path.dirname(absolute)).startswith("/proc/"):
        return True
    return os.path.islink(absolute) and os.readlink(absolute).startswith("/proc/")


def check_writable_dir(directory: str | os.PathLike, purpose: str) -> Path:
    """Refuse a missing directory or one that cannot take new files (a
    read-only file system, no write permission) before any work is done.

    ``os.access`` answers for the real user: root passes permission bits
    but not a read-only mount, which the write itself then reports.
    """
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():  # the OS's own word, as open() would say it
        raise IsoflowError(f"{directory}: not a directory, a file (for {purpose})")
    if not directory.is_dir():
        raise IsoflowError(f"{directory}: no such directory (for {purpose})")
    if not os.access(directory, os.W_OK | os.X_OK):
        why = "read-only file system" if _read_only_fs(directory) else "permission denied"
        raise IsoflowError(f"{directory}: cannot write {purpose} here ({why})")
    return directory


def check_picture_path(path: str | os.PathLike, force: bool = False) -> Path:
    """A picture file (``--png``, matplotlib output) checked as
    :func:`check_output_path`; call it before the work that the picture shows."""
    return check_output_path(path, force, suffixes=(".png",), what="picture")


def _read_only_fs(directory: Path) -> bool:
    try:
        return bool(os.statvfs(directory).f_flag & os.ST_RDONLY)
    except OSError:
        return False


#: the longest file name most file systems take, in bytes
NAME_MAX = 255


def _temp_parts(path: Path, mark: str = TEMP_MARK) -> tuple[str, str]:
    """(prefix, suffix) of the temporary names (or with ``mark`` the
    asides) beside ``path``: all its suffixes are kept (nibabel reads
    ".nii.gz", not only ".gz"), the name shortened so that a temporary
    name fits where ``path`` does."""
    suffix = "".join(path.suffixes)
    # the mark, the host, a 7-digit pid and the random part: a 240-byte output name got a temporary
    # name the file system refused ("File name too long")
    added = len(os.fsencode(f".{mark}{'0' * 8}-{'0' * 7}-{'0' * 8}"))
    if added + len(os.fsencode(suffix)) > NAME_MAX:  # many dots: the format is named by the last suffix
        suffix = path.suffix
    stem = path.name[: len(path.name) - len(suffix)] if suffix else path.name
    while stem and added + len(os.fsencode(stem + suffix)) > NAME_MAX:
        stem = stem[:-1]
    return f".{stem}{mark}", suffix


def _owner() -> str:
    """This process in a temporary name: its host (8 hex digits of a hash
    of the host name) and its pid."""
    import hashlib  # (imported here: every command would pay socket's import at its start)
    import socket

    host = hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]
    return f"{host}-{os.getpid()}"


def temp_sibling(path: Path, directory: bool = False) -> Path:
    """A new, reserved temporary name beside ``path`` that keeps its suffix
    (writers such as ``np.savez`` and matplotlib choose the format by it):
    ``.NAME.isoflow-tmp-HOST-PID-RANDOM.SUFFIX``. The file is created empty
    with the usual permissions (0666 less the umask), or the directory made,
    so that no other writer can take it. What killed writers left beside
    ``path`` is removed first (:func:`remove_abandoned`)."""
    remove_abandoned(path)
    return _reserve(path, directory, TEMP_MARK)


def _reserve(path: Path, directory: bool, mark: str) -> Path:
    import secrets  # (imported here: its hmac loads OpenSSL, which a command that writes nothing need not)

    prefix, suffix = _temp_parts(path, mark)
    for _ in range(100):
        tmp = path.with_name(f"{prefix}{_owner()}-{secrets.token_hex(4)}{suffix}")
        if MADE is not None:  # recorded before it exists: see MADE
            MADE.add(tmp)
        try:
            if directory:
                tmp.mkdir()
            else:
                os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            return tmp
        except FileExistsError:
            if MADE is not None:
                MADE.discard(tmp)
            continue
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(path))


def aside_name(path: Path) -> Path:
    """A free hidden name beside ``path``,
    ``.NAME.isoflow-old-HOST-PID-RANDOM.SUFFIX``, that an entry of
    ``path``'s name (a file, a link, a directory) is renamed to, in the
    same directory and so at once, to make room for the new one: where the
    new one's rename fails, the old one is renamed back and is as it was.
    The name is not among the temporaries that the command's end removes
    (:data:`MADE`), and its mark is not theirs: until it is removed on
    purpose it holds the old output, and where a command killed between
    the two renames left ``path`` missing, the next write beside it puts
    the old output back (:func:`remove_abandoned`).

    Parameters
    ----------
    path : pathlib.Path
        The entry to be replaced.

    Returns
    -------
    pathlib.Path
        A name beside ``path`` that no entry holds.

    Examples
    --------
    >>> import tempfile
    >>> store = Path(tempfile.mkdtemp()) / "step_001.zarr"
    >>> (store / "c").mkdir(parents=True)
    >>> old = aside_name(store)
    >>> old.parent == store.parent, old.name.startswith(".step_001.isoflow-old-"), old.exists()
    (True, True, False)
    >>> os.replace(store, old); sorted(p.name for p in old.iterdir()), store.exists()
    (['c'], False)
    """
    remove_abandoned(path)
    old = _reserve(path, True, ASIDE_MARK)
    old.rmdir()  # free for the rename of a file or a link as of a directory
    if MADE is not None:
        MADE.discard(old)
    return old


def remove_abandoned(path: str | os.PathLike) -> list[Path]:
    """Settle what writers killed outright (SIGKILL, a crash, a power cut:
    no clean-up ran; SIGTERM and Ctrl-C clean up) left beside ``path``.

    An entry is abandoned when its name says it belongs to a process of
    this host that no longer runs; another host's (a shared file system),
    a running process's or one of another form is left alone.

    * A temporary (``.NAME.isoflow-tmp-...``), written in part or whole but
      never put in place, is removed, so that a killed 10 GB zarr write
      does not stay on the disk, hidden.
    * An aside (``.NAME.isoflow-old-...``, :func:`aside_name`) is the
      previous output, moved away to make room for a new one. Where
      ``path`` exists the new one was put in place and only the aside's
      removal was cut short: it is removed. Where ``path`` is missing the
      process was killed between the two renames and the aside is the only
      copy: it is renamed back to ``path``, as it was, with a warning line
      naming both. Of several for one missing path (two commands that
      replaced it at once, both killed) the newest by its modification
      time is put back: the others are earlier outputs, replaced on
      request since, and are removed.
      A name too long for an aside's to hold it whole (over about 215
      bytes) could be another output's shortened the same way: its asides
      are left alone.

    Parameters
    ----------
    path : str or os.PathLike
        The output whose temporaries and asides are looked for.

    Returns
    -------
    list of pathlib.Path
        The entries removed (an aside put back is not among them).

    Examples
    --------
    >>> import subprocess, sys, tempfile, warnings
    >>> d = Path(tempfile.mkdtemp())
    >>> ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    >>> prefix, _ = _temp_parts(d / "store.zarr", ASIDE_MARK)
    >>> aside = d / f"{prefix}{_owner().split('-')[0]}-{int(ended.stdout)}-0123abcd.zarr"
    >>> (aside / "c").mkdir(parents=True)
    >>> with warnings.catch_warnings(record=True):
    ...     remove_abandoned(d / "store.zarr")
    []
    >>> sorted(p.name for p in d.iterdir()), (d / "store.zarr" / "c").is_dir()
    (['store.zarr'], True)
    """
    path = Path(path)
    try:
        names = _names(path.parent)
    except OSError:
        return []
    removed = []
    asides = _abandoned(path, ASIDE_MARK, names)
    if asides and os.path.lexists(path):
        for old in asides:
            _remove(old)
        removed += asides
    elif asides:
        removed += _put_back(path, asides)
    for tmp in _abandoned(path, TEMP_MARK, names):
        _remove(tmp)
        removed.append(tmp)
    return removed


def abandoned_asides(directory: str | os.PathLike) -> list[Path]:
    """The outputs in ``directory`` whose previous entries killed commands
    left aside (:func:`aside_name`), for a caller that replaces many of a
    directory's outputs and cannot name each in advance (a flow's steps
    of an earlier, longer run): :func:`remove_abandoned` of each puts its
    previous entry back or removes it. Each is its aside's name without
    the mark; a name shortened to fit its aside's (over about 215 bytes)
    comes shortened, so match them against the names the caller writes.

    Parameters
    ----------
    directory : str or os.PathLike
        The directory looked in (none, or unreadable: nothing is found).

    Returns
    -------
    list of pathlib.Path
        Sorted, each once however many asides stand for it.

    Examples
    --------
    >>> import subprocess, sys, tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    >>> host = _owner().split("-")[0]
    >>> _ = (d / f".step_003{ASIDE_MARK}{host}-{int(ended.stdout)}-0123abcd.ply").write_text("old")
    >>> _ = (d / f".step_004{ASIDE_MARK}{host}-{os.getpid()}-0123abcd.ply").write_text("running")
    >>> [p.name for p in abandoned_asides(d)]
    ['step_003.ply']
    """
    directory = Path(directory)
    try:
        names = os.listdir(directory)
    except OSError:
        return []
    host = _owner().split("-")[0]
    found = set()
    for name in names:
        stem, mark, rest = name[1:].partition(ASIDE_MARK)
        parts = re.fullmatch(r"([0-9a-f]{8}-\d+-[0-9a-f]{8})(.*)", rest, re.DOTALL)
        if name.startswith(".") and mark and parts and _dead_owner(parts[1], host) is not None:
            found.add(directory / (stem + parts[2]))
    return sorted(found)


def _abandoned(path: Path, mark: str, names: list[str]) -> list[Path]:
    """The entries of ``names`` (in ``path``'s directory) that are
    temporaries (asides, by ``mark``) of ``path`` left by a process of this
    host that no longer runs."""
    prefix, suffix = _temp_parts(path, mark)
    if mark == ASIDE_MARK and prefix[1: -len(mark)] + suffix != path.name:  # shortened: it may be another's
        return []
    host = _owner().split("-")[0]
    found = []
    for name in names:
        if not (name.startswith(prefix) and name.endswith(suffix) and len(name) > len(prefix) + len(suffix)):
            continue
        pid = _dead_owner(name[len(prefix): len(name) - len(suffix)], host)
        if pid is not None:
            found.append(path.parent / name)
    return found


def _dead_owner(owner: str, host: str) -> int | None:
    """The pid of ``HOST-PID-RANDOM`` where it is ``host``'s and no longer
    runs, else None. The random part is 8 hex digits: ``.a.isoflow-tmp-...``
    of ``a.b.zarr`` ends in ``RANDOM.b.zarr``, and is not ``a.zarr``'s."""
    parts = owner.split("-")
    if len(parts) != 3 or parts[0] != host or not parts[1].isdigit():
        return None
    if re.fullmatch(r"[0-9a-f]{8}", parts[2]) is None:
        return None
    pid = int(parts[1])
    # (kill(0) would ask about the process group)
    return None if pid <= 0 or _running(pid) else pid


def _put_back(path: Path, asides: list[Path]) -> list[Path]:
    """Rename the newest of ``asides`` back to the missing ``path`` and
    remove the others (see :func:`remove_abandoned`); returns those
    removed. Where the rename fails (another writer's ``path`` came
    meanwhile, a read-only directory) every aside is left for the next."""
    def mtime(p: Path) -> int:
        try:
            return os.lstat(p).st_mtime_ns
        except OSError:
            return -1

    newest = max(asides, key=mtime)
    try:
        if newest.is_dir() and not newest.is_symlink():
            os.rename(newest, path)  # refused where a file or a non-empty directory took path meanwhile
        else:
            _link_back(newest, path)
    except OSError:
        return []
    warn(f"{path}: put back the previous {path.name} from {newest.name}, where a command killed while replacing "
         "it had left it")
    rest = [old for old in asides if old != newest]
    for old in rest:
        _remove(old)
    return rest


def _link_back(aside: Path, path: Path) -> None:
    """Give a file or a link at ``aside`` the name ``path`` unless an entry
    took it: a hard link refuses an existing name, where a rename would
    replace it (a file system without hard links: renamed where ``path``
    is still missing)."""
    try:
        os.link(aside, path, follow_symlinks=False)
    except OSError:
        if os.path.lexists(path):
            raise
        os.rename(aside, path)
        return
    os.unlink(aside)


def _names(directory: Path) -> list[str]:
    """The names of temporaries and asides in ``directory``, listed once
    for the output set being written (:func:`output_set`), at every call
    outside one: a set of 10,000 label files listed their directory for
    each, 10,000 times 10,000 names. A writer killed while the set is
    written is swept by the next."""
    if not _LISTINGS:
        return [n for n in os.listdir(directory) if TEMP_MARK in n or ASIDE_MARK in n]
    listed = _LISTINGS[-1]
    if directory not in listed:
        listed[directory] = [n for n in os.listdir(directory) if TEMP_MARK in n or ASIDE_MARK in n]
    return listed[directory]


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)  # signal 0: only asks whether the process exists
    except ProcessLookupError:
        return False
    except PermissionError:  # it exists, as another user's
        return True
    return True


def write_error(path: Path, exc: BaseException, existed: bool) -> IsoflowError:
    """One line naming the file and the cause of a failed write."""
    cause = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc) or type(exc).__name__
    cause = short_write_cause(cause, path.parent) or cause
    cause = " ".join(cause.split())  # one line: a library's message (HDF5's) may hold line breaks
    return IsoflowError(f"{path}: could not write ({cause}); {_kept(path, existed)}")


#: what a failed set says of its files (:func:`output_set`)
NOTHING_REPLACED = "nothing was replaced"


def _kept(path: Path, existed: bool) -> str:
    """What a failed write left of ``path``: within a set, none of the set's
    files was replaced, whichever of them failed."""
    if _SETS:
        return NOTHING_REPLACED
    return f"the previous {path.name} is unchanged" if existed else "nothing was written"


#: numpy's words for a short write (``ndarray.tofile``, which ``np.save`` and tifffile use): the OS's cause is lost
_SHORT_WRITE = re.compile(r"(\d+) requested and (\d+) written")


def short_write_cause(cause: str, directory: Path) -> str | None:
    """The cause of a short write in the OS's words, for a library that
    reports only its byte counts.

    Parameters
    ----------
    cause : str
        The library's message: numpy's ``"887808 requested and 28544
        written"``.
    directory : Path
        Where the file was written: its file system's free space tells a
        full disk from a file size limit.

    Returns
    -------
    str or None
        ``"No space left on device (28544 bytes of 887808 written)"`` (or
        ``File too large``, with the limit, under ``ulimit -f``); None for
        any other message.
    """
    m = _SHORT_WRITE.fullmatch(cause)
    if m is None:
        return None
    requested, done = int(m[1]), int(m[2])
    counts = f"{done} bytes of {requested} written"
    try:
        import resource  # Unix only
        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        limited = limit != resource.RLIM_INFINITY
    except ImportError:
        limit, limited = -1, False
    try:
        fs = os.statvfs(directory)
        # root may write into the blocks kept back for it; called before the partial file is removed
        free = (fs.f_bfree if os.geteuid() == 0 else fs.f_bavail) * fs.f_frsize
    except OSError:
        free = None
    if limited and (free is None or free >= requested - done):
        return f"{os.strerror(errno.EFBIG)}: the file size limit (ulimit -f) is {limit} bytes; {counts}"
    if free is None or free < requested - done:
        return f"{os.strerror(errno.ENOSPC)}: {counts}"
    return f"the write stopped short: {counts}"


#: the signals a command has received (the command line's handlers append
#: them, :func:`isoflow.cli.termination_as_interrupt`). The handler raises
#: KeyboardInterrupt, but a library can swallow it (trimesh guards its
#: imports with ``except BaseException``), so no file is renamed into place
#: once a signal has come: the previous one stays, as the signal asks.
SIGNALS: list[int] = []

#: the temporaries :func:`temp_sibling` made while a command runs (None
#: outside one). A writer removes its own on an error or an interrupt, but
#: a signal handled in the instant between a temporary's making and the
#: writer's ``try`` (as the making returns) reaches no clean-up; the
#: command removes what is left of them as it ends
#: (:func:`remove_temporaries_left`). Their names hold this process's id
#: and a random part, so what exists under one is this command's.
MADE: set[Path] | None = None


def remove_entry(path: Path) -> None:
    """Remove ``path`` from its directory: a directory with what is in it,
    a file or a symbolic link by itself (what a link leads to is kept,
    even a directory: it is someone else's).

    Parameters
    ----------
    path : pathlib.Path
        The entry; OSError (FileNotFoundError too) as removing it raises.

    Examples
    --------
    >>> import tempfile
    >>> base = Path(tempfile.mkdtemp())
    >>> (base / "store" / "c").mkdir(parents=True)
    >>> (base / "link").symlink_to(base / "store")
    >>> remove_entry(base / "link"), (base / "store" / "c").is_dir()
    (None, True)
    >>> remove_entry(base / "store"), sorted(p.name for p in base.iterdir())
    (None, [])
    """
    shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()


def remove_temporaries_left() -> list[Path]:
    """Remove the temporaries of :data:`MADE` that still exist (a file,
    or a directory with what is in it) and stop recording them. Returns
    those removed.

    Examples
    --------
    >>> import tempfile
    >>> from isoflow.mesh import outputs
    >>> outputs.MADE = set()
    >>> left = temp_sibling(Path(tempfile.mkdtemp()) / "out.ply")
    >>> remove_temporaries_left() == [left], left.exists(), outputs.MADE
    (True, False, None)
    """
    global MADE
    made, MADE = MADE or set(), None
    removed = []
    for tmp in sorted(made):
        try:
            remove_entry(tmp)
        except FileNotFoundError:  # renamed into place, or removed by its writer
            continue
        except OSError:
            continue  # (what cannot be removed stays for the next run's remove_abandoned)
        removed.append(tmp)
    return removed


def interrupted_by_signal() -> None:
    """Raise KeyboardInterrupt if a signal came (see :data:`SIGNALS`)."""
    if SIGNALS:
        raise KeyboardInterrupt


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, directory: bool = False, sync: bool = True):
    """Give a temporary path beside ``path`` to write to; rename it over
    ``path`` when the block ends without error.

    For writers that take a file name (``np.savez``, ``fig.savefig``,
    trimesh's exporters, a zarr store with ``directory=True``). The file is
    flushed to the disk before the rename and the directory after it. On
    any error, or an interruption, the temporary file is removed and the
    target left as it was; an ``OSError`` becomes an :class:`IsoflowError`
    naming ``path``, anything else propagates. ``sync=False`` leaves the
    flushing to the caller (:func:`sync_file`, :func:`sync_directory`): a
    flow's step files are flushed on its worker thread.
    """
    path = Path(path)
    existed = path.exists()
    try:
        tmp = temp_sibling(path, directory)
    except OSError as exc:
        raise write_error(path, exc, existed) from None
    try:
        yield tmp
        if sync and not _SETS:  # a set's files are flushed together, before its renames (flush_set)
            _fsync_tree(tmp) if directory else sync_file(tmp)
        interrupted_by_signal()  # one a library swallowed while the file was written
        if _SETS:  # renamed with the rest of its set, by output_set
            _SETS[-1].append((tmp, path, directory))
            return
        _replace(tmp, path, directory)
        if sync:
            sync_directory(path.parent)
    except BaseException as exc:
        # worded before the partial file is removed, as the disk's free space tells a full disk from a size limit
        error = write_error(path, exc, existed) if isinstance(exc, OSError) else None
        _remove(tmp)
        if error is not None:
            raise error from None
        if isinstance(exc, KeyboardInterrupt):  # say which file, keep the exit status of an interrupt
            raise KeyboardInterrupt(f"{path}: interrupted while writing; {_kept(path, existed)}") from None
        raise


#: the sets of outputs open (:func:`output_set`), innermost last: each holds
#: the ``(temporary, target, directory)`` of the files written in it so far
_SETS: list[list[tuple[Path, Path, bool]]] = []
#: the directories each open set has listed, by :func:`_names`
_LISTINGS: list[dict[Path, list[str]]] = []


@contextlib.contextmanager
def output_set(name: str | os.PathLike, retire: Iterable[str | os.PathLike] = ()) -> Iterator[None]:
    """Replace the files written in the block (through :func:`atomic_path`
    or :func:`atomic_write`) together, when it ends without error.

    Each file is written whole to its temporary name as usual, but renamed
    into place only once the last one is written (and read back from
    :func:`staged`): an error or an interruption anywhere in the block
    removes every temporary and leaves each previous file byte for byte as
    it was, and its one line ends "nothing was replaced".

    Parameters
    ----------
    name : str or os.PathLike
        The set, as an interruption's line names it (the mesh, or the
        directory of a file per label).
    retire : iterable of str or os.PathLike
        Files of an earlier set that this one does not hold (``label_9.ply``
        where the new image has 8 labels): removed once the set is in
        place, so that what remains is the new set alone.

    Raises
    ------
    IsoflowError
        A write that failed, with "nothing was replaced".
    KeyboardInterrupt
        An interruption (Ctrl-C, SIGTERM) before the set was in place.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "a.txt").write_text("old a"), (d / "b.txt").write_text("old b")
    >>> try:
    ...     with output_set(d):
    ...         with atomic_write(d / "a.txt", "w") as fh:
    ...             _ = fh.write("new a")
    ...         raise OSError("the second write failed")
    ... except OSError:
    ...     pass
    >>> sorted((f.name, f.read_text()) for f in d.iterdir())
    [('a.txt', 'old a'), ('b.txt', 'old b')]
    >>> with output_set(d, retire=[d / "b.txt"]):
    ...     with atomic_write(d / "a.txt", "w") as fh:
    ...         _ = fh.write("new a")
    >>> sorted((f.name, f.read_text()) for f in d.iterdir())
    [('a.txt', 'new a')]
    """
    entries: list[tuple[Path, Path, bool]] = []
    _SETS.append(entries)
    _LISTINGS.append({})
    try:
        yield
        interrupted_by_signal()  # one a library swallowed after the last write
        if len(_SETS) == 1:  # the outermost set: its files, and those of the sets within it, go in place now
            flush_set(name, [tmp for tmp, _, _ in entries])
    except BaseException as exc:
        _SETS.pop()
        _LISTINGS.pop()
        for tmp, _, _ in entries:
            _remove(tmp)
        if isinstance(exc, KeyboardInterrupt):
            raise KeyboardInterrupt(f"{name}: {NOTHING_REPLACED}") from None
        if isinstance(exc, IsoflowError) and NOTHING_REPLACED not in str(exc):
            error = IsoflowError(f"{exc}; {NOTHING_REPLACED}")  # in both wordings
            if exc.command_line is not None:
                error.command_line = f"{exc.command_line}; {NOTHING_REPLACED}"
            raise error from None
        raise
    _SETS.pop()
    _LISTINGS.pop()
    if _SETS:  # an enclosing set renames these with its own
        _SETS[-1].extend(entries)
        return
    _put_in_place(entries, [Path(f) for f in retire])


# up to this many files a set is flushed file by file (flush_set)
FILES_PER_FSYNC = 8


def flush_set(name: str | os.PathLike, written: list[Path]) -> None:
    """Flush the temporaries of a set to the disk before any is renamed.

    A rename made durable before the data it names would leave, after a
    crash, an empty file where the previous one was. On Linux the set is
    flushed with one ``syncfs`` per file system: an ``fsync`` per file
    commits the file system's journal once per file, which with thousands
    of labels' files took a large share of the run. A set of a few files
    (a mesh and its picture) is flushed file by file all the same: ``syncfs``
    also waits for whatever else the file system holds unwritten, which
    another program's large write can make long. Elsewhere each file is
    flushed in turn (``sync`` need not wait for the disk there).

    Parameters
    ----------
    name : str or os.PathLike
        The set, as an error names it.
    written : list of Path
        The temporaries (files, or directories such as zarr stores).

    Raises
    ------
    IsoflowError
        A flush that failed (a disk's write error), naming the set.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "a.txt").write_text("a")
    >>> flush_set(d, [d / "a.txt"])
    """
    try:
        syncfs = _syncfs() if len(written) > FILES_PER_FSYNC else None
        if syncfs is None:
            for tmp in written:
                _fsync_tree(tmp) if tmp.is_dir() else sync_file(tmp)
            return
        devices = {os.stat(tmp.parent).st_dev: tmp.parent for tmp in written}
        for directory in devices.values():
            syncfs(directory)
    except OSError as exc:
        raise IsoflowError(f"{name}: could not flush the files to the disk ({exc.strerror or exc})") from None


def _syncfs():
    """Linux's ``syncfs`` as a function of a directory on the file system
    (None where there is none): Python's ``os`` does not offer it."""
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    try:
        call = ctypes.CDLL(None, use_errno=True).syncfs
    except (OSError, AttributeError):  # a C library without it
        return None

    def syncfs(directory: Path) -> None:
        fd = os.open(directory, os.O_RDONLY)
        try:
            if call(fd) != 0:
                code = ctypes.get_errno()
                raise OSError(code, os.strerror(code), str(directory))
        finally:
            os.close(fd)

    return syncfs


def staged(path: str | os.PathLike) -> Path:
    """Where the new ``path`` is while its :func:`output_set` is open.

    Parameters
    ----------
    path : str or os.PathLike
        An output, as it was written.

    Returns
    -------
    Path
        Its temporary, written and not yet renamed (to read it back), or
        ``path`` itself where no open set holds it.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> with output_set(d):
    ...     with atomic_write(d / "a.txt", "w") as fh:
    ...         _ = fh.write("new a")
    ...     staged(d / "a.txt").read_text(), (d / "a.txt").exists()
    ('new a', False)
    >>> staged(d / "a.txt") == d / "a.txt"
    True
    """
    path = Path(path)
    for tmp, target, _ in (entry for entry_set in reversed(_SETS) for entry in reversed(entry_set)):
        if target == path:
            return tmp
    return path


def _put_in_place(entries: list[tuple[Path, Path, bool]], retire: list[Path]) -> None:
    """Rename a set's temporaries over their targets, then remove the files
    it retires. A signal is held back meanwhile (raised after it): the
    renames take microseconds and, cut short, would leave the mix of new
    and old files that the set exists to prevent."""
    import signal

    held = {signal.SIGINT, signal.SIGTERM, *([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])}
    before = signal.pthread_sigmask(signal.SIG_BLOCK, held) if hasattr(signal, "pthread_sigmask") else None
    try:
        for done, (tmp, path, directory) in enumerate(entries):
            try:
                _replace(tmp, path, directory)
            except OSError as exc:
                for rest, _, _ in entries[done:]:
                    _remove(rest)
                cause = exc.strerror or str(exc)
                raise IsoflowError(f"{path}: could not put it in place ({cause}); {done} of the {len(entries)} "
                                   "files of its set were replaced before it") from None
        for old in retire:
            try:
                old.unlink(missing_ok=True)
            except OSError as exc:
                raise IsoflowError(f"{old}: could not remove this file of an earlier set ({exc.strerror or exc}); "
                                   "the new set is in place") from None
        for directory in dict.fromkeys(path.parent for _, path, _ in entries):
            sync_directory(directory)
    finally:
        if before is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, before)


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "wb", sync: bool = True, **open_kwargs):
    """Open a temporary file beside ``path`` for writing (``mode`` "w" or
    "wb", ``open`` keywords such as ``newline``) and rename it over
    ``path`` when the block ends without error (see :func:`atomic_path`)."""
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write writes new files: mode 'w' or 'wb', not {mode!r}")
    path = Path(path)
    with atomic_path(path, sync=sync) as tmp, open(tmp, mode, **open_kwargs) as fh:
        yield fh
        fh.flush()  # an error here, or in closing, is reported like one in writing


def sync_file(path: str | os.PathLike) -> None:
    """Flush a written file to the disk (``fsync``)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_tree(root: Path) -> None:
    for parent, _, files in os.walk(root):
        for name in files:
            sync_file(Path(parent) / name)
        sync_directory(Path(parent))


def make_output_dir(directory: str | os.PathLike) -> bool:
    """Make an output directory where there is none, and make its entry in
    its parent durable (``fsync`` of the parent, as :func:`sync_directory`
    does it): the renames of the files into it are flushed with the
    directory, but after a crash the directory itself, files and all,
    could be gone.

    Parameters
    ----------
    directory : str or os.PathLike
        The directory (``-o DIR/`` of a file per label, a flow's ``--out``).

    Returns
    -------
    bool
        Whether it was made (an existing one is left as it is).

    Raises
    ------
    OSError
        As ``Path.mkdir`` raises it: a file of that name, a missing or
        read-only parent.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp()) / "labels"
    >>> make_output_dir(d), make_output_dir(d), d.is_dir()
    (True, False, True)
    """
    directory = Path(directory)
    made = not directory.is_dir()
    directory.mkdir(exist_ok=True)
    if made:
        sync_directory(directory.parent)
    return made


def sync_directory(directory: str | os.PathLike) -> None:
    """Make the renames in a directory durable (``fsync`` of the directory;
    some file systems cannot sync one, and that is not an error)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _replace(tmp: Path, path: Path, directory: bool) -> None:
    if not (directory and path.is_dir()):
        os.replace(tmp, path)
        return
    # a directory cannot be renamed over a non-empty one: move the old one
    # aside, move the new one in, then delete the old one
    old = aside_name(path)
    os.replace(path, old)
    try:
        os.replace(tmp, path)
    except BaseException:
        os.replace(old, path)
        raise
    shutil.rmtree(old, ignore_errors=True)


def _remove(tmp: Path) -> None:
    with contextlib.suppress(OSError):
        if tmp.is_dir() and not tmp.is_symlink():
            from ..scale.chunks import settle_zarr_io  # a store's writes interrupted may still be under way

            settle_zarr_io()
            shutil.rmtree(tmp)
        else:
            tmp.unlink()
