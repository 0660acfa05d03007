"""
Writing outputs so that nothing is half-written and nothing of the user's is lost: check a place first, replace a file
in one step, write a run's files into a folder without touching anything else there.

Every temporary this module makes is a hidden name beside its target that carries the writer's process id
(``.<name>.sb3aac-<pid>.tmp...``), so a later run can tell a dead writer's leftovers (removed by
:func:`remove_stale_temporaries`) from a live writer's files (never touched).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

_TEMPORARY = re.compile(r"^\..+\.sb3aac-(\d+)\.tmp")  # .<name>.sb3aac-<pid>.tmp<random>[suffix]; nobody else's


def temporary_prefix(path: Path) -> str:
    """The prefix of this process's temporaries for ``path``: hidden, with the writer's pid."""
    return f".{path.name}.sb3aac-{os.getpid()}.tmp"


def current_umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


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
    new file (probed by creating and removing a temporary; permission bits alone are not enough, e.g. as root). The
    temporaries a killed earlier writer left in that folder are removed.

    :raises ValueError: saying why not
    """
    out = Path(path)
    try:
        if out.is_dir():
            raise ValueError(f"{what} {str(out)!r} is a directory; give a file name")
        out.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(out.parent)  # a killed earlier writer's
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
    Yield a temporary file name beside ``path``; when the block ends without error the file is flushed to disk, given
    the permissions a new file gets under the umask (``0o666 & ~umask``; the temporary was private while written),
    and replaces ``path`` in one step (``os.replace``); on error (or Ctrl-C) it is removed. Readers see the old file
    or the whole new one, never a part; a full disk leaves the old file as it was.

    The folder is created if missing; the temporaries a killed earlier writer left there are removed first
    (:func:`remove_stale_temporaries`).

    :param suffix: the temporary's suffix (some writers insist on one, e.g. ``.zip``)
    :raises NotADirectoryError: if the folder, or one above it, is a file
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise NotADirectoryError(
            errno.ENOTDIR, f"cannot write {path}: its folder, or one above it, is a file, not a folder", str(path.parent)
        ) from None
    remove_stale_temporaries(path.parent)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=temporary_prefix(path), suffix=suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~current_umask())
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


class RunFolder:
    """
    A folder that receives a run's files: each file is written to a temporary beside it and renamed into place
    (:func:`replaced_atomically`), so a reader sees the old file or the whole new one, never a part. Nothing else in
    the folder is touched: no file the run does not write is removed or replaced, the folder itself is never
    replaced (a symbolic link to a folder is followed, and stays a link), and its permissions stay as they are.

    :param out: the folder; created (with the umask's permissions) if missing
    :param names: the files the run will write into it
    :param what: how error messages name it (e.g. ``"--out directory"``)
    :param overwrite: replace files of these names that are already there; if False (the default), their presence
        is an error before any work
    :raises ValueError: at construction, if ``out`` is an existing file, cannot be written (probed by creating a
        temporary), or already holds one of ``names`` without ``overwrite``
    """

    def __init__(self, out: str | os.PathLike[str], names: tuple[str, ...], what: str, overwrite: bool = False):
        self.out, self.names, self.what = Path(out), names, what
        check_writable_dir(self.out, what)
        remove_stale_temporaries(self.out)
        taken = [name for name in names if os.path.lexists(self.out / name)]
        if taken and not overwrite:
            raise ValueError(
                f"{what} {str(self.out)!r} already holds {', '.join(taken)}: pass --overwrite to replace "
                f"{'it' if len(taken) == 1 else 'them'}, or give another folder"
            )

    @contextlib.contextmanager
    def file(self, name: str) -> Iterator[Path]:
        """A temporary name that replaces ``out/name`` (one of ``names``) in one step once the block succeeds."""
        if name not in self.names:
            raise ValueError(f"{name!r} is not one of the files this run writes ({', '.join(self.names)})")
        with replaced_atomically(self.out / name, suffix=Path(name).suffix) as tmp:
            yield tmp
