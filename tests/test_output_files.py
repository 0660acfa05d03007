"""sb3_aac.common.output_files: places checked before work, files replaced in one step with the umask's permissions,
a run's folder receiving its files without anything else in it being touched."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sb3_aac.common.output_files import (
    RunFolder,
    check_writable_dir,
    check_writable_file,
    remove_stale_temporaries,
    replaced_atomically,
)

DEAD_PID = 2**22 + 12345  # beyond Linux's largest pid_max: no such process


NAMES = ("model.zip", "policy.aacp", "run.json")


def write_run(folder: RunFolder, tag: str) -> None:
    for name in NAMES:
        with folder.file(name) as tmp:
            tmp.write_text(f"{tag} {name}")


def read_files(folder: Path) -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.mark.parametrize("place", ["/proc", "/proc/x/y", "/sys/kernel", "/dev/null"])
def test_unwritable_places_are_refused_before_any_work(place: str) -> None:
    with pytest.raises(ValueError, match=r"cannot write|existing file"):
        RunFolder(place, NAMES, "--out directory")
    with pytest.raises(ValueError, match=r"cannot write|existing file|directory"):
        check_writable_file(place + "/x.png" if place != "/dev/null" else place + "/x", "--out")
    with pytest.raises(ValueError, match=r"cannot write|existing file"):
        check_writable_dir(place + "/tb", "--tensorboard directory")


def test_a_run_folder_touches_nothing_it_does_not_write(tmp_path: Path) -> None:
    out = tmp_path / "run"
    write_run(RunFolder(out, NAMES, "--out"), "old")
    assert read_files(out)["model.zip"] == "old model.zip"
    (out / "notes.txt").write_text("mine")
    (out / "tb").mkdir()
    (out / "tb" / "events").write_text("logged")
    os.chmod(out, 0o751)
    with pytest.raises(ValueError, match=r"already holds model.zip, policy.aacp, run.json: pass --overwrite"):
        RunFolder(out, NAMES, "--out")
    assert read_files(out)["run.json"] == "old run.json"  # refused before writing anything
    write_run(RunFolder(out, NAMES, "--out", overwrite=True), "new")
    assert read_files(out) == {"model.zip": "new model.zip", "notes.txt": "mine", "policy.aacp": "new policy.aacp",
                               "run.json": "new run.json"}  # fmt: skip
    assert (out / "tb" / "events").read_text() == "logged"
    assert os.stat(out).st_mode & 0o777 == 0o751  # the folder keeps its permissions
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no temporaries left
    with pytest.raises(ValueError, match="not one of the files"):
        RunFolder(out, NAMES, "--out", overwrite=True).file("notes.txt").__enter__()


def test_a_linked_run_folder_is_followed_and_stays_a_link(tmp_path: Path) -> None:
    (tmp_path / "exp").mkdir()
    (tmp_path / "latest").symlink_to("exp")
    write_run(RunFolder(tmp_path / "latest", NAMES, "--out"), "new")
    assert (tmp_path / "latest").is_symlink() and read_files(tmp_path / "exp")["model.zip"] == "new model.zip"


def test_files_get_the_umask_permissions(tmp_path: Path) -> None:
    previous = os.umask(0o022)
    try:
        write_run(RunFolder(tmp_path / "run", NAMES, "--out"), "new")
        with replaced_atomically(tmp_path / "figure.png") as tmp:
            tmp.write_text("png")
    finally:
        os.umask(previous)
    assert os.stat(tmp_path / "run").st_mode & 0o777 == 0o755
    for path in (tmp_path / "figure.png", *(tmp_path / "run" / name for name in NAMES)):
        assert os.stat(path).st_mode & 0o777 == 0o644, path


def test_a_full_disk_keeps_the_earlier_file(tmp_path: Path, monkeypatch) -> None:
    folder = RunFolder(tmp_path / "run", NAMES, "--out")
    write_run(folder, "old")

    def disk_full(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", disk_full)
    with pytest.raises(OSError, match="No space"), folder.file("model.zip") as tmp:
        tmp.write_text("half")
    monkeypatch.undo()
    assert read_files(tmp_path / "run")["model.zip"] == "old model.zip"
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == sorted(NAMES)


def test_stale_temporaries_of_dead_writers_only_are_removed(tmp_path: Path) -> None:
    live = tmp_path / f".model.zip.sb3aac-{os.getpid()}.tmpabc"
    dead = tmp_path / f".model.zip.sb3aac-{DEAD_PID}.tmpabc"
    dead_dir = tmp_path / f".run.sb3aac-{DEAD_PID}.tmpxyz"
    user = tmp_path / ".hidden-but-mine"
    foreign = tmp_path / f".cache.{DEAD_PID}.tmp"  # another program's temporary: never ours to remove
    for path in (live, dead, user, foreign):
        path.write_text("x")
    dead_dir.mkdir()
    (dead_dir / "model.zip").write_text("x")
    assert sorted(remove_stale_temporaries(tmp_path)) == sorted([dead, dead_dir])
    assert live.exists() and user.exists() and foreign.exists() and not dead.exists() and not dead_dir.exists()


def test_replaced_atomically_keeps_the_old_file_on_error(tmp_path: Path) -> None:
    path = tmp_path / "figure.png"
    path.write_text("old")
    with pytest.raises(RuntimeError), replaced_atomically(path, suffix=".png") as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path
        tmp.write_text("half")
        raise RuntimeError("the writer failed")
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["figure.png"]
    with replaced_atomically(path) as tmp:
        tmp.write_text("new")
    assert path.read_text() == "new" and [p.name for p in tmp_path.iterdir()] == ["figure.png"]
