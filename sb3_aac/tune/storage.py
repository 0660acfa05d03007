"""Where a study lives: an SQL database URL, or an Optuna journal file that several processes or machines share."""

from __future__ import annotations

import json
from pathlib import Path

from optuna.storages import BaseStorage, JournalStorage, RDBStorage
from optuna.storages.journal import JournalFileBackend

SQLITE_PREFIX = "sqlite:///"
# How long to wait for a database server to accept a connection (PostgreSQL's and MySQL's drivers take this
# argument), so that an unreachable host fails at once instead of after the system's TCP timeout.
CONNECT_TIMEOUT_S = 10


def open_storage(spec: str) -> BaseStorage:
    """
    The storage ``spec`` names: a database URL (``sqlite:///study.db``, ``postgresql://...``) or, for anything
    without ``://``, the path of an Optuna journal file (``study.log``), which processes on several machines can share
    over a network filesystem (SQLite there is unsafe). Missing folders of a file are created.

    :raises ValueError: one line saying why the storage cannot be opened (unwritable place, not a study database,
        an in-memory database that would keep nothing, a file that is not a regular file (a FIFO, a device), a
        journal file that is not Optuna's, a database driver that is not installed)
    """
    if "://" in spec:
        if spec.startswith("sqlite:"):
            database = spec[len(SQLITE_PREFIX) :] if spec.startswith(SQLITE_PREFIX) else ""
            if database in ("", ":memory:") or database.startswith(":memory:?"):
                raise ValueError(
                    f"{spec!r} is an in-memory database, which keeps nothing after the command: give a file, e.g. "
                    "sqlite:///study.db"
                )
            _check_regular_file(Path(database), spec)
            _make_parent(Path(database), spec)
        engine_kwargs = (
            {"connect_args": {"connect_timeout": CONNECT_TIMEOUT_S}} if spec.startswith(("postgresql", "mysql")) else {}
        )
        try:
            return RDBStorage(spec, engine_kwargs=engine_kwargs)
        except Exception as error:  # sqlalchemy's errors (and a driver's ImportError) have no common base
            raise ValueError(f"cannot open the study database {spec!r}: {_database_error(error, spec)}") from None
    path = Path(spec)
    if path.is_dir():
        raise ValueError(f"the journal file {spec!r} is a directory; give a file name (e.g. study.log) or a database URL")
    _check_regular_file(path, spec)
    _make_parent(path, spec)
    try:
        _check_journal(path)
        storage = JournalStorage(JournalFileBackend(str(path)))
        storage.get_all_studies()  # replays the journal: fails now, not mid-study
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(
            f"cannot read {spec!r} as an Optuna journal file ({type(error).__name__}: {_first_line(error)})"
        ) from None
    return storage


def _check_regular_file(path: Path, spec: str) -> None:
    """A storage file that exists must be a regular file: a FIFO would block the command, a device (a link to
    /dev/zero) would be read without end."""
    if path.exists() and not path.is_file():
        raise ValueError(f"the study storage {spec!r} is not a regular file (a FIFO, a device or a socket); give a file")


def _database_error(error: BaseException, spec: str) -> str:
    """The line that says why a database URL cannot be opened; for a missing driver, which one SQLAlchemy wanted."""
    cause = error.__cause__
    if isinstance(error, ImportError) and isinstance(cause, ModuleNotFoundError) and cause.name:
        scheme = spec.split("://", 1)[0]
        return (
            f"the module {cause.name!r}, SQLAlchemy's driver for {scheme}://, is not installed: install it, or name an "
            f"installed driver in the URL ({scheme.split('+')[0]}+DRIVER://..., e.g. postgresql+psycopg2:// for psycopg2)"
        )
    return _first_line(error)


def _check_journal(path: Path) -> None:
    """Every complete line of an existing journal is a JSON record (Optuna skips a bad last line, then appends to it)."""
    if not path.exists():
        return
    with path.open("rb") as file:
        for number, line in enumerate(file, start=1):
            if not line.endswith(b"\n"):
                continue  # a record another process is still writing
            try:
                record = json.loads(line)
            except ValueError:
                raise ValueError(f"line {number} is not a JSON record") from None
            if not (isinstance(record, dict) and "op_code" in record):
                raise ValueError(f"line {number} is not an Optuna journal record")


def _make_parent(path: Path, spec: str) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise ValueError(
            f"cannot create the folder {str(path.parent)!r} for the study storage {spec!r}: {error.strerror}"
        ) from None


def _first_line(error: BaseException) -> str:
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
