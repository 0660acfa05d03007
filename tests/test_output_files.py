"""sb3_aac.common.output_files: places checked before work, files replaced in one step, a run directory published
as one set whatever step fails."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sb3_aac.common import output_files
from sb3_aac.common.output_files import (
    DirectoryPublisher,
    check_writable_dir,
    check_writable_file,
    remove_stale_temporaries,
    replaced_atomically,
)

DEAD_PID = 2**22 + 12345  # beyond Linux's largest pid_max: no such process


def write_set(folder: Path, tag: str) -> None:
    for name in ("model.zip", "policy.aacp", "run.json"):
        (folder / name).write_text(f"{tag} {name}")


def read_set(folder: Path) -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.mark.parametrize("place", ["/proc", "/proc/x/y", "/sys/kernel", "/dev/null"])
def test_unwritable_places_are_refused_before_any_work(place: str) -> None:
    with pytest.raises(ValueError, match=r"cannot write|existing file"):
        DirectoryPublisher(place, "--out directory")
    with pytest.raises(ValueError, match=r"cannot write|existing file|directory"):
        check_writable_file(place + "/x.png" if place != "/dev/null" else place + "/x", "--out")
    with pytest.raises(ValueError, match=r"cannot write|existing file"):
        check_writable_dir(place + "/tb", "--tensorboard directory")


def test_the_current_directory_is_refused(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    for place in ("", ".", str(tmp_path), str(tmp_path.parent)):
        with pytest.raises(ValueError, match="current directory"):
            DirectoryPublisher(place, "--out directory")


def test_publish_new_and_replace_keeping_other_entries(tmp_path: Path) -> None:
    out = tmp_path / "run"
    first = DirectoryPublisher(out, "--out")
    write_set(first.staging, "old")
    first.publish()
    assert read_set(out)["model.zip"] == "old model.zip"
    (out / "notes.txt").write_text("mine")
    (out / "tb").mkdir()
    (out / "tb" / "events").write_text("logged")
    second = DirectoryPublisher(out, "--out")
    write_set(second.staging, "new")
    second.publish()
    assert read_set(out) == {
        "model.zip": "new model.zip",
        "notes.txt": "mine",
        "policy.aacp": "new policy.aacp",
        "run.json": "new run.json",
    }
    assert (out / "tb" / "events").read_text() == "logged"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no staging or old directory left


@pytest.mark.parametrize(
    ("failing", "exchange"),
    [("fsync", True), ("link", True), ("exchange", True), ("fsync", False), ("link", False), ("rename", False)],
)
def test_a_failure_at_any_step_leaves_the_old_set(tmp_path: Path, monkeypatch, failing: str, exchange: bool) -> None:
    out = tmp_path / "run"
    first = DirectoryPublisher(out, "--out")
    write_set(first.staging, "old")
    first.publish()
    (out / "notes.txt").write_text("mine")
    before = read_set(out)
    second = DirectoryPublisher(out, "--out")
    write_set(second.staging, "new")

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt  # a kill at this step, as far as the files can tell

    if not exchange:
        monkeypatch.setattr(output_files, "_exchange", lambda a, b: False)
    target = {"fsync": (os, "fsync"), "link": (os, "link"), "exchange": (output_files, "_exchange"), "rename": (os, "rename")}[
        failing
    ]
    monkeypatch.setattr(*target, interrupt)
    with pytest.raises(KeyboardInterrupt):
        second.publish()
    monkeypatch.undo()
    assert read_set(out) == before
    second.discard()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


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
