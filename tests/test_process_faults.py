"""Killed processes: the benchmark runner's workers end with their driver, and a killed trainer or runner never
leaves a half-written file (Linux: processes are found through /proc)."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from benchmarks import cells as cell_files
from benchmarks.presets import Cell

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="finds processes through /proc")

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "envs"), os.environ.get("PYTHONPATH", "")])}
ENV_ID = "RoboCupDribblePaper-v0"
TINY = {"eval_every": 50, "eval_episodes": 5, "final_episodes": 5}
GRID = [
    Cell(ENV_ID, "Reference", "references", eval_episodes=5, final_episodes=5),
    Cell(ENV_ID, "SarsaAAC", "rbf10", 0, 600, **TINY),
    Cell(ENV_ID, "SarsaAAC", "rbf10", 1, 600, **TINY),
]
DRIVER = """
import sys
from benchmarks.presets import Cell
from benchmarks.run import main, run_grid
import benchmarks.run as run
import signal
signal.signal(signal.SIGTERM, run._exit_on_sigterm)
cells = [Cell.from_dict(c) for c in {cells!r}]
run_grid(cells, sys.argv[1], workers=2, progress=False)
"""


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, parent pid) of a process, None if it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return None
    fields = text[text.rindex(")") + 2 :].split()
    return fields[0], int(fields[1])


def descendants(root: int) -> set[int]:
    """The live processes below ``root``."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (stat := _stat(int(entry.name))) is not None and stat[0] != "Z":
            parents[int(entry.name)] = stat[1]
    found, frontier = set(), {root}
    while frontier:
        frontier = {pid for pid, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def alive(pids: set[int]) -> set[int]:
    return {pid for pid in pids if (stat := _stat(pid)) is not None and stat[0] != "Z"}


def wait_gone(pids: set[int], seconds: float) -> set[int]:
    deadline = time.monotonic() + seconds
    while alive(pids) and time.monotonic() < deadline:
        time.sleep(0.1)
    return alive(pids)


def check_no_half_written_file(out: Path) -> None:
    for path in (out / "cells").glob("*.json"):
        cell_files.read_cell_file(path)  # raises, naming it, if half-written
    leftovers = [p for sub in ("cells", "models", "errors") for p in (out / sub).glob(".*")]
    owners = {int(match.group(1)) for p in leftovers if (match := re.search(r"\.sb3aac-(\d+)\.tmp", p.name))}
    assert not alive(owners), f"temporaries of live processes: {leftovers}"


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "sig"), [(0, signal.SIGKILL), (1, signal.SIGTERM)])
def test_killed_runner_leaves_no_process_and_no_half_written_file(tmp_path: Path, seed: int, sig: int) -> None:
    script = DRIVER.format(cells=[c.to_dict() for c in GRID])
    driver = subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], env=ENV, cwd=ROOT, stderr=subprocess.DEVNULL)
    kill_at = time.monotonic() + random.Random(seed).uniform(1.0, 12.0)  # from the workers' start-up to their cells
    seen: set[int] = set()
    while time.monotonic() < kill_at and driver.poll() is None:
        seen |= descendants(driver.pid)  # the workers and the resource tracker, as they start
        time.sleep(0.05)
    driver.send_signal(sig)
    driver.wait(30)
    assert not wait_gone(seen, 30.0), "processes outlived the killed runner"  # a worker may still be importing
    check_no_half_written_file(tmp_path)


# ------------------------------------------------------------------------------------------ the Ray engine's watchdog

# A process that ignores SIGTERM and holds the file named by its argument open.
SLEEPER = "import signal, sys, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); f = open(sys.argv[1], 'w'); time.sleep(99)"
REAPER_DRIVER = """
import subprocess, sys
from benchmarks.process_reaper import ProcessReaper
folder, then = sys.argv[1], sys.argv[2]
sleeper = lambda name: subprocess.Popen([sys.executable, "-c", {sleeper!r}, folder + "/" + name], stdout=subprocess.DEVNULL)
before = sleeper("before")  # started before the watchdog: not the block's
with ProcessReaper() as reaper:
    reaper.claim(folder)
    inside = sleeper("inside")  # ignores SIGTERM
    print(before.pid, inside.pid, reaper.pid, flush=True)
    sys.stdin.readline()
    if then == "die":
        import os, signal
        os.kill(os.getpid(), signal.SIGKILL)
print("left the block", flush=True)
sys.stdin.readline()
"""


def start_reaper_driver(tmp_path: Path, then: str) -> tuple[subprocess.Popen[str], list[int]]:
    script = REAPER_DRIVER.format(sleeper=SLEEPER)
    driver = subprocess.Popen([sys.executable, "-c", script, str(tmp_path), then], env=ENV, cwd=ROOT, text=True,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE)  # fmt: skip
    assert driver.stdout is not None
    pids = [int(word) for word in driver.stdout.readline().split()]
    deadline = time.monotonic() + 60
    while not all((tmp_path / name).exists() for name in ("before", "inside")) and time.monotonic() < deadline:
        time.sleep(0.05)  # both sleepers run (and ignore SIGTERM)
    return driver, pids


def test_the_watchdog_ends_what_a_killed_driver_started_and_nothing_else(tmp_path: Path) -> None:
    pytest.importorskip("psutil", reason="the watchdog needs psutil (pip install sb3-aac[distributed])")
    from benchmarks.process_reaper import GRACE_SECONDS

    driver, (before, inside, watchdog) = start_reaper_driver(tmp_path, "die")
    try:
        driver.communicate("\n", timeout=30)  # it kills itself inside the block
        assert driver.returncode == -signal.SIGKILL
        assert not wait_gone({inside, watchdog}, GRACE_SECONDS + 10)  # SIGTERM ignored: SIGKILL after the grace
        assert alive({before})  # started before the block
    finally:
        os.kill(before, signal.SIGKILL)
        for pid in (inside, watchdog):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


def test_the_watchdog_leaves_alone_what_a_driver_that_cleaned_up_left_running(tmp_path: Path) -> None:
    pytest.importorskip("psutil", reason="the watchdog needs psutil (pip install sb3-aac[distributed])")
    driver, (before, inside, watchdog) = start_reaper_driver(tmp_path, "stay")
    try:
        assert driver.stdin is not None and driver.stdout is not None
        driver.stdin.write("\n")
        driver.stdin.flush()
        assert driver.stdout.readline() == "left the block\n"
        assert not wait_gone({watchdog}, 10)  # STOP: the watchdog exits with the block ...
        driver.kill()
        driver.wait(30)
        time.sleep(1)
        assert alive({before, inside}) == {before, inside}  # ... and kills nothing, not even after the driver's end
    finally:
        for pid in (before, inside):
            os.kill(pid, signal.SIGKILL)


def test_the_processes_using_a_claimed_directory(tmp_path: Path) -> None:
    pytest.importorskip("psutil", reason="the watchdog needs psutil (pip install sb3-aac[distributed])")
    from benchmarks.process_reaper import users_of

    claimed, other = tmp_path / "claimed", tmp_path / "other"
    claimed.mkdir()
    other.mkdir()
    started = time.time() - 1
    holding = subprocess.Popen([sys.executable, "-c", SLEEPER, str(claimed / "log")])
    naming = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)", f"--session={claimed}/sockets"])
    elsewhere = subprocess.Popen([sys.executable, "-c", SLEEPER, str(other / "log")])
    try:
        deadline = time.monotonic() + 60
        while not ((claimed / "log").exists() and (other / "log").exists()) and time.monotonic() < deadline:
            time.sleep(0.05)
        found = {p.pid for p in users_of([str(claimed)], started, skip=os.getpid())}
        assert {holding.pid, naming.pid} <= found and elsewhere.pid not in found
        assert not users_of([str(claimed)], time.time() + 60, skip=os.getpid())  # none started since then
    finally:
        for process in (holding, naming, elsewhere):
            process.kill()
            process.wait()


def command_line(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except (FileNotFoundError, ProcessLookupError):
        return ""


RAY_AGENTS = ("ray::DashboardAgent", "ray::RuntimeEnvAgent")  # the raylet's children that outlived a killed runner
RAY_GONE_SECONDS = 15.0  # the reaper's grace (2 s) after the runner's pipe closes, and room for a loaded machine


@pytest.mark.slow
def test_a_killed_ray_runner_leaves_no_process_of_its_ray_instance(tmp_path: Path) -> None:
    """``--engine ray`` without ``--address`` starts Ray here; SIGKILL the runner as soon as the raylet's agents run,
    while Ray still starts (its workers, the driver's ``ray.init``). Within RAY_GONE_SECONDS no process of that Ray
    instance is left: none of the runner's descendants (its watchdog, GCS, raylet, agents, workers), and no process
    naming the instance's session directory (``session_..._<runner pid>``)."""
    pytest.importorskip("ray", reason="Ray is not installed (pip install sb3-aac[distributed])")
    pytest.importorskip("psutil", reason="the Ray engine's watchdog needs psutil (pip install sb3-aac[distributed])")

    argv = ["--preset", "quick", "--only", "paper__SarsaAAC-tile__s0__20k", "--engine", "ray", "--workers", "1"]
    runner = subprocess.Popen(
        [sys.executable, "-m", "benchmarks.run", *argv, "--allow-dirty", "--out", str(tmp_path)],
        env=ENV, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    deadline = time.monotonic() + 180  # imports and Ray's start take seconds, more on a loaded machine
    seen: set[int] = set()
    agents: set[int] = set()
    try:
        while len(agents) < len(RAY_AGENTS) and time.monotonic() < deadline and runner.poll() is None:
            seen |= descendants(runner.pid)
            agents = {pid for pid in seen if command_line(pid).startswith(RAY_AGENTS)}
            time.sleep(0.1)
        assert len(agents) == len(RAY_AGENTS), f"the Ray agents did not start (runner exit {runner.poll()})"
        session = next(match[0] for pid in seen if (match := re.search(r"session_[0-9_-]+", command_line(pid))))
    finally:
        runner.kill()
        runner.wait(30)
    assert session.endswith(f"_{runner.pid}")
    left = wait_gone(seen, RAY_GONE_SECONDS)
    assert not left, f"outlived the killed runner: {[command_line(pid) for pid in left]}"
    named = {int(e.name) for e in Path("/proc").iterdir() if e.name.isdigit() and session in command_line(int(e.name))}
    assert not alive(named), f"processes of {session} left: {[command_line(pid) for pid in alive(named)]}"


def test_a_damaged_cell_file_is_recomputed_and_named(tmp_path: Path) -> None:
    from benchmarks import run as bench_run
    from benchmarks.report import build_report

    reference = GRID[0]
    assert not bench_run.run_grid([reference], tmp_path, workers=1, progress=False)["failed"]
    path = cell_files.cell_path(tmp_path, reference.cell_id)
    good = path.read_bytes()
    path.write_bytes(good[: len(good) // 2])  # as a disk-full or a foreign writer could leave it
    with pytest.warns(UserWarning, match=f"{path.name} is damaged.*computed again"):
        status = bench_run.run_grid([reference], tmp_path, workers=1, progress=False)
    assert status["done"] == [reference.cell_id]
    assert json.loads(path.read_text())["cell_id"] == reference.cell_id
    # the report names a damaged file instead of crashing on it
    other = tmp_path / "cells" / "RoboCupDribble-v0__Reference__references.json"
    other.write_text('{"cell_id": ')
    report = build_report(tmp_path, figures=False).read_text()
    assert "Damaged result files" in report and other.name in report


def test_a_live_runs_temporaries_and_running_cell_are_left_alone(tmp_path: Path) -> None:

    reference = GRID[0]
    (tmp_path / "cells").mkdir()
    live = tmp_path / "cells" / f".{reference.cell_id}.json.sb3aac-{os.getpid()}.tmpabc"  # a live process's temporary
    dead = tmp_path / "cells" / f".{reference.cell_id}.json.sb3aac-{2**22 + 12345}.tmpabc"  # beyond pid_max: dead
    live.write_text("{")
    dead.write_text("{")
    with cell_files.cell_lock(tmp_path, reference.cell_id) as locked:
        assert locked
        # another "run" of the grid while this process holds the cell
        script = (
            "import sys; from benchmarks.presets import Cell; from benchmarks.run import run_grid; "
            f"print(run_grid([Cell.from_dict({reference.to_dict()!r})], sys.argv[1], workers=1, progress=False)['busy'])"
        )
        result = subprocess.run(
            [sys.executable, "-c", script, str(tmp_path)], env=ENV, cwd=ROOT, capture_output=True, text=True
        )
        assert result.returncode == 0, result.stderr
        assert reference.cell_id in result.stdout
    assert live.exists() and not dead.exists()


def test_a_cell_another_run_finished_after_this_run_listed_it_is_not_run_again(tmp_path: Path) -> None:
    from benchmarks import run as bench_run
    from benchmarks.execution import run_cell_safely

    reference = GRID[0]
    assert bench_run.run_grid([reference], tmp_path, workers=1, progress=False)["done"] == [reference.cell_id]
    path = tmp_path / "cells" / f"{reference.cell_id}.json"
    before = path.read_bytes()
    # this run listed the cell before the other one finished it: it takes the lock, finds the file and stops
    assert run_cell_safely(reference.to_dict(), str(tmp_path))[:2] == (reference.cell_id, "skipped")
    assert path.read_bytes() == before


# ------------------------------------------------------------------------------------------------------ the trainer

TRAIN = ["-m", "sb3_aac.cli", "train", "--policy", "RbfPolicy", "--n-envs", "2", "--eval-episodes", "0", "--set", "n_rbf=3"]


def run_files(out: Path) -> dict[str, bytes]:
    return {name: (out / name).read_bytes() for name in ("model.zip", "policy.aacp", "run.json") if (out / name).exists()}


def digest(files: dict[str, bytes]) -> str:
    return hashlib.sha256(b"".join(files[k] for k in sorted(files))).hexdigest()


@pytest.mark.slow
def test_killed_trainer_leaves_whole_files_and_keeps_the_users(tmp_path: Path) -> None:
    """Each file of --out is the old one or a whole new one whenever the trainer is killed; run.json, written last,
    names the run whose model.zip is there; SIGTERM (like Ctrl-C) saves the model trained so far; nothing of the
    user's is touched, and a killed trainer's temporaries go with the next run."""
    from sb3_aac import RuntimePolicy, SarsaAAC

    out = tmp_path / "run"
    start = time.monotonic()
    subprocess.run(
        [sys.executable, *TRAIN, "--timesteps", "300", "--seed", "1", "--out", str(out)],
        env=ENV,
        check=True,
        capture_output=True,
    )
    duration = time.monotonic() - start
    (out / "notes.txt").write_text("the user's own file")
    rng = random.Random(0)
    outcomes = []
    for attempt in range(4):
        argv = [sys.executable, *TRAIN, "--timesteps", "400", "--seed", str(2 + attempt), "--out", str(out), "--overwrite"]
        trainer = subprocess.Popen(argv, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(rng.uniform(0.3, 1.1) * duration)
        trainer.send_signal(signal.SIGKILL if attempt % 2 == 0 else signal.SIGTERM)
        trainer.wait(30)
        files = run_files(out)
        assert set(files) == {"model.zip", "policy.aacp", "run.json"}, f"attempt {attempt}: {sorted(files)}"
        assert (out / "notes.txt").read_text() == "the user's own file"
        run = json.loads(files["run.json"])
        model = SarsaAAC.load(out / "model.zip")  # whole, whichever run wrote it
        RuntimePolicy.load(out / "policy.aacp")
        if run["seed"] != 2 + attempt:
            outcomes.append("old")
            continue
        assert model.num_timesteps == run["timesteps"], "run.json describes another model.zip"
        outcomes.append("interrupted" if run.get("interrupted") else "new")
        assert run.get("interrupted") or run["timesteps"] == 400
    subprocess.run([sys.executable, *TRAIN, "--timesteps", "100", "--out", str(out), "--overwrite"], env=ENV, check=True,
                   capture_output=True)  # fmt: skip
    assert not [p for p in out.iterdir() if p.name.startswith(".")], "a temporary inside the run directory"
    print("outcomes", outcomes)
