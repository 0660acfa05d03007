"""
Writing outputs so that nothing is half-written: check a place first, replace a file in one step, publish a
directory of files as one set.

Every temporary this module makes is a hidden name beside its target that carries the writer's process id
(``.<name>.sb3aac-<pid>.tmp...``), so a later run can tell a dead writer's leftovers (removed by
:func:`remove_stale_temporaries`) from a live writer's files (never touched).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

_TEMPORARY = re.compile(r"^\..+\.sb3aac-(\d+)\.tmp")  # .<name>.sb3aac-<pid>.tmp<random>[suffix]; nobody else's
_RENAME_EXCHANGE = 2  # linux/fs.h: swap the two paths atomically (renameat2)
_AT_FDCWD = -100


def temporary_prefix(path: Path) -> str:
    """The prefix of this process's temporaries for ``path``: hidden, with the writer's pid."""
    return f".{path.name}.sb3aac-{os.getpid()}.tmp"


def pid_alive(pid: int) -> bool:
    """Whether a process with this id exists (it may belong to another user)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Remove the temporaries in ``folder`` whose writer is dead (a killed run); a live writer's stay. Returns them."""
    removed = []
    with contextlib.suppress(FileNotFoundError):
        for entry in folder.iterdir():
            match = _TEMPORARY.match(entry.name)
            if match is None or pid_alive(int(match.group(1))):
                continue
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry, ignore_errors=True)
            else:
                with contextlib.suppress(FileNotFoundError):
                    entry.unlink()
            removed.append(entry)
    return removed


def check_writable_file(path: str | os.PathLike[str], what: str) -> Path:
    """
    Check, before any work, that a file can be written at ``path``: its folder exists or can be created and takes a
    new file (probed by creating and removing a temporary; permission bits alone are not enough, e.g. as root).

    :raises ValueError: saying why not
    """
    out = Path(path)
    try:
        if out.is_dir():
            raise ValueError(f"{what} {str(out)!r} is a directory; give a file name")
        out.parent.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=out.parent, prefix=temporary_prefix(out))
        os.close(fd)
        os.unlink(probe)
    except (OSError, ValueError) as error:
        raise ValueError(_why_not(what, out, error)) from None
    return out


def check_writable_dir(path: str | os.PathLike[str], what: str) -> Path:
    """Like :func:`check_writable_file` for a directory: created if missing, then probed with a temporary file."""
    out = Path(path)
    try:
        if out.exists() and not out.is_dir():
            raise ValueError(f"{what} {str(out)!r} is an existing file; give a directory")
        out.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=out, prefix=".probe.")
        os.close(fd)
        os.unlink(probe)
    except (OSError, ValueError) as error:
        raise ValueError(_why_not(what, out, error)) from None
    return out


def _why_not(what: str, path: Path, error: Exception) -> str:
    if isinstance(error, ValueError) and str(error).startswith(what):
        return str(error)
    return f"cannot write {what} {str(path)!r}: {getattr(error, 'strerror', None) or error}"


def _fsync_dir(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextlib.contextmanager
def replaced_atomically(path: str | os.PathLike[str], suffix: str = "") -> Iterator[Path]:
    """
    Yield a temporary file name beside ``path``; when the block ends without error the file is flushed to disk and
    replaces ``path`` in one step (``os.replace``), on error it is removed. Readers see the old file or the whole
    new one, never a part.

    :param suffix: the temporary's suffix (some writers insist on one, e.g. ``.zip``)
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=temporary_prefix(path), suffix=suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux ``renameat2(RENAME_EXCHANGE)``); False where the system cannot."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(a), None, str(b))


def _link_tree(source: Path, target: Path, skip: set[str]) -> None:
    """Hard-link (or copy, where links fail) every entry of ``source`` except ``skip`` into ``target``."""
    for entry in source.iterdir():
        if entry.name in skip or _TEMPORARY.match(entry.name):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.copytree(entry, target / entry.name, symlinks=True, copy_function=_link_or_copy)
        else:
            _link_or_copy(entry, target / entry.name)


def _link_or_copy(source: str | os.PathLike[str], target: str | os.PathLike[str]) -> None:
    if os.path.islink(source):
        os.symlink(os.readlink(source), target)
        return
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)


class DirectoryPublisher:
    """
    Write a set of files into a directory as one unit: the files are written to a hidden staging directory beside
    ``out`` (its name carries this process's id), and :meth:`publish` swaps it with ``out`` in one step, so ``out``
    holds either its earlier complete set or the new complete set, never a mix or a part.

    Other entries of an existing ``out`` (a plot, a TensorBoard folder) are kept: they are hard-linked into the
    staging directory before the swap. Where the system cannot swap two directories in one step (not Linux, or a
    file system without ``RENAME_EXCHANGE``), the old directory is renamed aside and the new one renamed into place:
    a kill between the two renames leaves ``out`` missing and the old set in the hidden directory.

    :param out: the directory to publish
    :param what: how error messages name it (e.g. ``"--out directory"``)
    :raises ValueError: at construction, if ``out`` is an existing file, or cannot be written or swapped (checked
        by creating the staging directory and a probe file in ``out``)
    """

    def __init__(self, out: str | os.PathLike[str], what: str):
        self.out = Path(os.path.abspath(out))
        if not os.fspath(out) or Path.cwd().is_relative_to(self.out):
            raise ValueError(
                f"{what} {os.fspath(out)!r} holds the current directory; give a folder of its own, e.g. runs/name"
            )
        try:
            if self.out.exists() and not self.out.is_dir():
                raise ValueError(f"{what} {str(self.out)!r} is an existing file; give a directory")
            self.out.parent.mkdir(parents=True, exist_ok=True)
            remove_stale_temporaries(self.out.parent)
            self.staging = Path(tempfile.mkdtemp(dir=self.out.parent, prefix=temporary_prefix(self.out)))
        except (OSError, ValueError) as error:  # ValueError: a NUL byte in the name, or the checks above
            raise ValueError(_why_not(what, self.out, error)) from None
        if self.out.is_dir():
            try:
                fd, probe = tempfile.mkstemp(dir=self.out, prefix=".probe.")
                os.close(fd)
                os.unlink(probe)
                if os.stat(self.out).st_dev != os.stat(self.staging).st_dev:
                    raise OSError(errno.EXDEV, f"it is a mount point; give a folder inside it, e.g. {self.out / 'run'}")
            except OSError as error:
                self.discard()
                raise ValueError(f"cannot write {what} {str(self.out)!r}: {error.strerror or error}") from None

    def discard(self) -> None:
        """Remove the staging directory (nothing is published)."""
        shutil.rmtree(self.staging, ignore_errors=True)

    def publish(self) -> Path:
        """Swap the staging directory's files into ``out`` as one set; returns ``out``."""
        for entry in self.staging.iterdir():
            if entry.is_file():
                with open(entry, "rb+") as f:
                    os.fsync(f.fileno())
        if not self.out.exists():
            os.rename(self.staging, self.out)
            _fsync_dir(self.out.parent)
            return self.out
        _link_tree(self.out, self.staging, skip={entry.name for entry in self.staging.iterdir()})
        _fsync_dir(self.staging)
        if not _exchange(self.staging, self.out):
            aside = Path(tempfile.mkdtemp(dir=self.out.parent, prefix=temporary_prefix(self.out)))
            try:
                os.rename(self.out, aside / "old")
            except BaseException:
                aside.rmdir()
                raise
            os.rename(self.staging, self.out)
            self.staging = aside
        _fsync_dir(self.out.parent)
        self.discard()  # now the earlier directory
        return self.out
