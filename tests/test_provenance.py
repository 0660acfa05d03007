"""Provenance of benchmark sweeps (benchmarks/provenance.py): dirty-tree refusal, the invocation log."""

from __future__ import annotations

import json
import subprocess

import pytest

from benchmarks import cells as cell_files
from benchmarks import provenance
from benchmarks import run as bench_run


def git(repo, *args):
    subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True)


@pytest.fixture
def repo(tmp_path):
    """A git repository with one committed source file and a committed results directory."""
    root = tmp_path / "repo"
    (root / "results").mkdir(parents=True)
    (root / "code.py").write_text("x = 1\n")
    (root / "results" / "runs.jsonl").write_text("")
    git(root, "init", "-q")
    git(root, "-c", "user.name=t", "-c", "user.email=t@t", "add", ".")
    git(root, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "init")
    return root


def test_a_clean_tree_passes_and_names_its_commit(repo):
    state = provenance.require_clean_tree(repo)
    assert len(state.commit) == 40 and not state.dirty and state.label == state.commit


def test_a_dirty_tree_is_refused_unless_allowed(repo):
    (repo / "code.py").write_text("x = 2\n")
    with pytest.raises(provenance.DirtyTreeError, match=r"code\.py.*--allow-dirty"):
        provenance.require_clean_tree(repo)
    state = provenance.require_clean_tree(repo, allow_dirty=True)
    assert state.changed_files == ("code.py",) and state.label.endswith("+dirty")


def test_changes_inside_the_results_directory_and_untracked_files_do_not_count(repo):
    (repo / "results" / "runs.jsonl").write_text("{}\n")  # a previous invocation's log line
    (repo / "notes.txt").write_text("untracked\n")
    assert not provenance.require_clean_tree(repo, ignore=(repo / "results",)).dirty
    with pytest.raises(provenance.DirtyTreeError):
        provenance.require_clean_tree(repo)


def test_a_renamed_file_is_a_change(repo):
    git(repo, "mv", "code.py", "moved.py")
    assert provenance.git_state(repo).changed_files == ("moved.py",)


def test_outside_git_the_commit_is_unknown(tmp_path):
    assert provenance.git_state(tmp_path) == provenance.GitState("unknown", ())


def test_the_cli_refuses_a_dirty_tree_and_logs_the_refusal(repo, tmp_path, monkeypatch, capsys):
    (repo / "code.py").write_text("x = 3\n")
    monkeypatch.setattr(bench_run, "REPO", repo)
    out = tmp_path / "out"
    ran = []
    monkeypatch.setattr(bench_run, "run_grid", lambda *args, **kwargs: ran.append(args))
    assert bench_run.main(["--preset", "quick", "--out", str(out), "--workers", "1"]) == 2
    assert not ran and "--allow-dirty" in capsys.readouterr().err
    (entry,) = provenance.invocations(out)
    assert entry["status"] == "refused" and entry["allow_dirty"] is False


def test_allow_dirty_is_recorded_in_every_cell(repo, tmp_path, monkeypatch):
    (repo / "code.py").write_text("x = 4\n")
    monkeypatch.setattr(bench_run, "REPO", repo)
    out = tmp_path / "out"
    status = bench_run.main(["--preset", "quick", "--only", "reference", "--out", str(out), "--workers", "1", "--allow-dirty"])
    assert status == 0
    (cell,) = cell_files.load_cells(out)
    record = cell["provenance"]
    assert record["allow_dirty"] is True and record["git_commit"].endswith("+dirty") and record["changed_files"] == ["code.py"]
    (entry,) = provenance.invocations(out)
    assert entry["status"] == "finished" and entry["invocation"] == record["invocation"] and entry["done"] == 1
    assert provenance.ENV_VAR not in bench_run.os.environ  # not left to later run_grid calls of this process


def test_interrupted_and_killed_invocations_are_logged(tmp_path):
    with pytest.raises(KeyboardInterrupt), provenance.logged_invocation(tmp_path, command="a", workers=2) as log:
        log["done"] = 3
        raise KeyboardInterrupt
    with pytest.raises(ZeroDivisionError), provenance.logged_invocation(tmp_path, command="b", workers=2):
        _ = 1 / 0
    with provenance.logged_invocation(tmp_path, command="c", workers=1) as log:
        log.update(done=1, skipped=0, failed=0)
    # a driver killed outright leaves only its start record
    with open(tmp_path / provenance.RUN_LOG, "a") as f:
        f.write(json.dumps({"event": "start", "invocation": "k1", "command": "d", "workers": 2, "start": "x"}) + "\n")
        f.write(
            json.dumps({"command": "old", "start": "y", "wall_s": 5.0, "workers": 2, "done": 1, "skipped": 0, "failed": 0})
            + "\n"
        )
    entries = provenance.invocations(tmp_path)
    assert [e["command"] for e in entries] == ["a", "b", "c", "d", "old"]
    assert [e["status"] for e in entries] == ["interrupted", "failed: ZeroDivisionError", "finished", "killed", "finished"]
    assert entries[0]["done"] == 3 and entries[2]["wall_s"] >= 0 and entries[3]["wall_s"] is None


def test_a_torn_log_line_is_skipped_with_a_warning_naming_it(tmp_path, capsys):
    with provenance.logged_invocation(tmp_path, command="a", workers=1) as log:
        log.update(done=1, skipped=0, failed=0)
    with open(tmp_path / provenance.RUN_LOG, "a") as f:
        f.write('{"event": "start", "invocation": "k2", "comm')  # the writer was killed mid-line
    entries = provenance.invocations(tmp_path)
    assert [e["command"] for e in entries] == ["a"]
    assert f"{provenance.RUN_LOG}:3 is not a JSON record" in capsys.readouterr().err
