"""Every file sewgen writes, written one way: whole or not at all, onto a regular file, never into sewgen itself.

* :func:`replacing` (and :func:`write_text`, :func:`write_bytes` on it) writes a file into a temporary file in
  the target's own folder, flushes it to the disk (``fsync``) and renames it over the target (``os.replace``):
  a reader sees the old file or the whole new one, and a full disk, a read-only file system or an interrupted
  run leaves the old file as it was. A symbolic link is followed: the file it points to is replaced and the link
  stays. A target that is not a regular file — a folder, a FIFO, a device such as ``/dev/null``, a socket — is
  refused, and so is any path inside sewgen's own installed package (:data:`PACKAGE_DIR`: its code and built-in
  models are never written by a command).
* :func:`staged_folder` writes a folder of results as a whole: the run's files go into a temporary folder and
  replace the previous run's set only when all of them are written. A folder holds one run: files of the run
  before that this one does not write are removed (the list of a run's files is kept in the folder, in
  :data:`MANIFEST`); files sewgen did not write are left alone. A failing run leaves the folder as it was.
* :func:`check_file` and :func:`check_folder` check an output path before any work is done.

Every failure is an :class:`~sewgen.errors.OutputPathError` naming the path (and the command-line option that
gave it, ``option``), never a traceback; ``problem`` says what is wrong ("No space left on device", "is a
FIFO, not a regular file", ...).
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import stat
import tempfile
from pathlib import Path

from sewgen.errors import OutputPathError

#: sewgen's own installed package (this file's folder): never written (its code, its built-in models).
PACKAGE_DIR = Path(__file__).resolve().parent
#: The list of the files a run wrote into its folder (:func:`staged_folder`), kept in that folder.
MANIFEST = ".sewgen-run.json"
#: Characters of a target's name kept in its temporary file's name (a name near the file system's limit of
#: 255 bytes must still leave room for the temporary name's prefix and suffix).
_STEM = 60


def umask() -> int:
    """The process's file-creation mask (read without changing it)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _fail(path, option: str | None, problem: str) -> OutputPathError:
    return OutputPathError(option or "", problem, file=str(path))


def _os_problem(path, exc: OSError) -> str:
    return f"cannot write {path}: {exc.strerror or exc}"


_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a device"), (stat.S_ISBLK, "a device"),
          (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str:
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def _stat(path: Path, option: str | None):
    """``os.stat`` of ``path`` following links; None where nothing is there (or a link points nowhere)."""
    try:
        return os.stat(path)
    except FileNotFoundError:
        return None
    except NotADirectoryError:
        raise _fail(path, option, f"cannot write {path}: a part of the path is a file, not a folder") from None
    except OSError as exc:  # a name too long, a loop of links, no permission to look
        raise _fail(path, option, _os_problem(path, exc)) from None


def _inside_package(path: Path) -> bool:
    try:
        return path.is_relative_to(PACKAGE_DIR)
    except (OSError, ValueError):
        return False


def _named(text, option: str | None) -> Path:
    raw = os.fspath(text)
    if not str(raw).strip():
        raise _fail(raw, option, "an empty name")
    if str(raw) == "-":
        raise _fail(raw, option, "- (standard output) cannot take this output: give a file name (./- for a file "
                                 "named -)")
    return Path(raw)


def _real(path: Path, option: str | None) -> Path:
    """Where writing ``path`` writes: links followed; refused inside sewgen's installed package."""
    try:
        real = Path(os.path.realpath(path))
    except OSError as exc:
        raise _fail(path, option, _os_problem(path, exc)) from None
    if _inside_package(real):
        raise _fail(path, option, f"{path} is inside sewgen's installed package ({PACKAGE_DIR}): sewgen never "
                                  "writes there (its code and built-in models); write elsewhere, e.g. "
                                  f"./{path.name}")
    return real


def check_file(path, option: str | None = None) -> Path:
    """The file that writing ``path`` replaces (a link followed), checked before any work: a regular file or
    nothing yet, in an existing folder, outside sewgen's package. Raises :class:`OutputPathError` otherwise."""
    path = _named(path, option)
    st = _stat(path, option)
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise _fail(path, option, f"{path} is a folder: give a file name, e.g. {path / 'results.csv'}")
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise _fail(path, option, f"{path} is {_kind(st.st_mode)}, not a regular file: sewgen writes a file whole "
                                  "(a temporary file renamed over it) and cannot write there")
    real = _real(path, option)
    parent = _stat(real.parent, option)
    if parent is None or not stat.S_ISDIR(parent.st_mode):
        raise _fail(path, option, f"cannot write {path}: no folder {real.parent}")
    if not os.access(real.parent, os.W_OK):
        raise _fail(path, option, f"cannot write into {real.parent}: permission denied")
    return real


def check_folder(folder, option: str | None = None) -> Path:
    """``folder`` usable as an output folder (a link followed): an existing folder, or a new one whose parent
    exists, outside sewgen's package. Raises :class:`OutputPathError` otherwise (before any work is done)."""
    folder = _named(folder, option)
    st = _stat(folder, option)
    if st is not None and not stat.S_ISDIR(st.st_mode):
        raise _fail(folder, option, f"{folder} exists and is not a folder")
    real = _real(folder, option)
    home = real if st is not None else real.parent
    if st is None:
        parent = _stat(home, option)
        if parent is None or not stat.S_ISDIR(parent.st_mode):
            raise _fail(folder, option, f"cannot make {folder}: no folder {home}")
    if not os.access(home, os.W_OK):
        raise _fail(folder, option, f"cannot write into {home}: permission denied")
    return real


def _fsync_folder(folder: Path) -> None:
    """Make a rename in ``folder`` durable (best effort: not every file system lets a folder be opened)."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextlib.contextmanager
def replacing(path, option: str | None = None, *, text: bool = False, newline: str | None = None):
    """A file handle (binary, or UTF-8 text with ``text=True``) whose contents replace ``path`` when the block
    ends without an error: written to a temporary file beside the target, flushed to the disk and renamed over
    it. The target is checked first (:func:`check_file`); an error of the disk (full, read-only, ...) while
    writing is an :class:`OutputPathError` naming ``path``, and leaves the old file as it was."""
    real = check_file(path, option)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{real.name[:_STEM]}.", suffix=".part", dir=real.parent)
    except OSError as exc:
        raise _fail(path, option, _os_problem(path, exc)) from None
    try:
        try:
            old = os.stat(real)
            mode = stat.S_IMODE(old.st_mode) if stat.S_ISREG(old.st_mode) else 0o666 & ~umask()
        except OSError:
            mode = 0o666 & ~umask()
        with (os.fdopen(fd, "w", encoding="utf-8", newline=newline) if text else os.fdopen(fd, "wb")) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, real)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise _fail(path, option, _os_problem(path, exc)) from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_folder(real.parent)


def write_text(path, text: str, option: str | None = None) -> Path:
    """``text`` as the UTF-8 file ``path``, whole or not at all (:func:`replacing`); returns ``path``."""
    with replacing(path, option, text=True) as fh:
        fh.write(text)
    return Path(path)


def write_bytes(path, data: bytes, option: str | None = None) -> Path:
    """``data`` as the file ``path``, whole or not at all (:func:`replacing`); returns ``path``."""
    with replacing(path, option) as fh:
        fh.write(data)
    return Path(path)


# -- folders ---------------------------------------------------------------------------------------------------

def previous_run(folder: Path) -> list[str]:
    """The files of the run that last wrote ``folder`` (its :data:`MANIFEST`): plain names of regular files still
    there; [] for a folder no run of sewgen wrote."""
    try:
        names = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return []
    if not isinstance(names, list):
        return []
    out = []
    for name in names:
        if (isinstance(name, str) and name not in ("", ".", "..", MANIFEST) and "/" not in name
                and "\\" not in name and "\0" not in name):
            with contextlib.suppress(OSError):
                if stat.S_ISREG(os.lstat(folder / name).st_mode):
                    out.append(name)
    return out


def _keep(path: Path, copy: Path) -> None:
    """``copy`` of the file ``path`` (a hard link where the file system has them)."""
    try:
        os.link(path, copy)
    except OSError:
        shutil.copy2(path, copy)


def _swap_in(folder: Path, staged: Path, names: list, option: str | None) -> None:
    """Move the staged files into ``folder`` over the previous run's set, as one step that is undone on an error:
    every file replaced is kept aside first, the previous run's files this run does not write are moved aside,
    the manifest comes last; on any error the new files are taken out and the old ones put back."""
    stale = [n for n in previous_run(folder) if n not in names]
    for name in names:  # what cannot be replaced is refused before anything moves
        st = _stat(folder / name, option)
        if st is not None and not stat.S_ISREG(os.lstat(folder / name).st_mode):
            raise _fail(folder / name, option, f"cannot replace {folder / name}: it is not a regular file")
    aside = staged / ".previous"
    aside.mkdir()
    moved_in, moved_out = [], []
    try:
        for name in names:
            target = folder / name
            if os.path.lexists(target):
                _keep(target, aside / name)
            moved_in.append(name)
            os.replace(staged / name, target)
        for name in stale:
            os.replace(folder / name, aside / name)
            moved_out.append(name)
    except BaseException:
        for name in reversed(moved_in):
            with contextlib.suppress(OSError):
                if (aside / name).exists():
                    os.replace(aside / name, folder / name)
                else:
                    os.unlink(folder / name)
        for name in moved_out:
            with contextlib.suppress(OSError):
                os.replace(aside / name, folder / name)
        raise
    _fsync_folder(folder)


@contextlib.contextmanager
def staged_folder(folder, option: str | None = None):
    """Write a folder's files into a temporary folder (yielded); when the block ends without an error they become
    the folder's run: a new folder is renamed into place in one step; in an existing one they replace the
    previous run's files (:func:`_swap_in`), files of that run which this one does not write are removed, files
    sewgen did not write stay. On an error the temporary folder is removed and ``folder`` is left as it was."""
    path = Path(folder)
    real = check_folder(folder, option)
    existed = real.is_dir()
    home = real if existed else real.parent
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{(real.name or 'out')[:_STEM]}.", suffix=".part", dir=home))
    except OSError as exc:
        raise _fail(path, option, f"cannot write into {home}: {exc.strerror or exc}") from None
    try:
        try:
            yield tmp
        except OutputPathError as exc:  # a file of the run: named where it was going, with the folder's option
            if not (exc.file or "").startswith(str(tmp)):
                raise
            raise _fail(path / Path(exc.file).relative_to(tmp), option, exc.problem.replace(str(tmp), str(path))) \
                from None
        names = sorted(p.name for p in tmp.iterdir() if p.is_file() and not p.name.startswith("."))
        names.sort(key=lambda n: n == "summary.json")  # summary.json last: its presence marks a complete run
        # (every file is on the disk already: replacing() flushed each before renaming it into the folder)
        write_text(tmp / MANIFEST, json.dumps({"files": names}, indent=1) + "\n")
        names.append(MANIFEST)
        if not existed:
            os.chmod(tmp, 0o777 & ~umask())
            try:
                os.rename(tmp, real)
                _fsync_folder(real.parent)
                return
            except OSError:  # made meanwhile: its files are replaced as an existing folder's
                real.mkdir(exist_ok=True)
        _swap_in(real, tmp, names, option)
    except OSError as exc:
        raise _fail(path, option, f"cannot write {path}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["MANIFEST", "PACKAGE_DIR", "check_file", "check_folder", "previous_run", "replacing", "staged_folder",
           "umask", "write_bytes", "write_text"]
