"""What a preset costs: core-hours per stage (the grid's main budgets, the long budgets, the equal wall-clock budget
and the tuning stage), estimated from each learner's training rate on
each env (:func:`benchmarks.presets.training_rate`) and each env's evaluation costs, and the hours of wall time
on N cores (:func:`wall_hours`).

A cell's seconds (:func:`cell_seconds`) are its training, ``budget`` env steps at :func:`training_rate` (a
wall-clock cell: its ``seconds``), plus its greedy evaluations (a curve point of ``eval_episodes`` episodes every
``eval_every`` training episodes, one before training and one at the end, and ``final_episodes`` episodes),
each episode at :data:`EVAL_EPISODE_SECONDS`, plus :data:`CELL_SETUP_SECONDS`. A tuning trial trains
``env_steps`` per tuning seed and plays ``evaluations`` pruning evaluations and one final one of ``eval_episodes``
episodes; the stage's figure assumes no trial is pruned, so it is an upper bound (the median rule stops many trials
early). One core runs one cell or trial (the runner pins torch and BLAS to one thread), so seconds are core-seconds.

The rates are single-core figures of the development machine (two cores shared by several jobs, so they are
rough, within about 2x): ``python -m benchmarks.run --preset P --estimate`` prints the figure, and the local pool
orders its cells by the same :func:`cell_seconds`.

Wall time on N cores: the pool hands the longest cell still waiting to the first core that is free, so its cells
land as :func:`longest_first` puts them, and the busiest core's sum is the wall time. ``--shard I/N`` splits a grid
between machines the same way (:mod:`benchmarks.shards`).
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from benchmarks.presets import PRESETS, Cell, build_cells, select, training_rate
from benchmarks.tuning import plan_studies

# Training env steps per episode, typical of the learners at the grid's budgets (the number of curve points);
# dribbling and Platform from the finished cells of benchmarks/results, the others from the envs' random and
# scripted policies (docs/hybrid_domains.md).
EPISODE_STEPS = {
    "RoboCupDribblePaper-v0": 15,
    "RoboCupDribble-v0": 15,
    "Platform-v0": 4,
    "Goal-v0": 3,
    "Moving-v0": 100,
    "Sliding-v0": 120,
    "CatchPoint-v0": 17,
}
# Seconds of one greedy evaluation episode (the policy's single-observation decisions and the env's steps;
# dribbling evaluates on batched lanes): dribbling's and Platform's from the finished cells' eval_wall_s, the hybrid
# domains' the CPU time of benchmarks.domains.evaluate on 100 episodes with the torch learners (MP-DQN, TD3), whose
# decisions cost 10-30x SarsaAAC's.
EVAL_EPISODE_SECONDS = {
    "RoboCupDribblePaper-v0": 2e-4,
    "RoboCupDribble-v0": 2e-4,
    "Platform-v0": 8e-3,
    "Goal-v0": 3e-3,
    "Moving-v0": 3e-2,
    "Sliding-v0": 3e-2,
    "CatchPoint-v0": 6e-3,
}
CELL_SETUP_SECONDS = 2.0  # imports, building the env and model, timing decisions, saving the model
REFERENCE_SECONDS = 10.0  # a dribbling env's no-learning references


def evaluation_seconds(env_id: str, episodes: int) -> float:
    return episodes * EVAL_EPISODE_SECONDS.get(env_id, 0.01)


def cell_seconds(cell: Cell) -> float:
    """Estimated core-seconds of a cell: training, its evaluations and its setup."""
    if cell.algo == "Reference":
        return REFERENCE_SECONDS
    training = float(cell.seconds) if cell.seconds else cell.budget / training_rate(cell.env_id, cell.algo, cell.config)
    steps = cell.budget if not cell.seconds else training * training_rate(cell.env_id, cell.algo, cell.config)
    points = steps / EPISODE_STEPS.get(cell.env_id, 10) / cell.eval_every + 2
    evaluated = points * cell.eval_episodes + cell.final_episodes
    return training + evaluation_seconds(cell.env_id, round(evaluated)) + CELL_SETUP_SECONDS


def trial_seconds(study: Any) -> float:
    """Estimated core-seconds of one unpruned trial of a :class:`benchmarks.tuning.StudySpec`."""
    training = study.env_steps / training_rate(study.env_id, study.algo, study.config)
    evaluated = (study.evaluations + 1) * study.eval_episodes
    return study.seeds * (training + evaluation_seconds(study.env_id, evaluated)) + CELL_SETUP_SECONDS


def stage_of(cell: Cell, preset: dict[str, Any]) -> str:
    """``"grid"`` (an env's main budget and the references), ``"long"`` or ``"wall-clock"``."""
    if cell.seconds:
        return "wall-clock"
    if cell.algo != "Reference" and cell.budget != preset["envs"][cell.env_id]["budget"]:
        return "long"
    return "grid"


STAGES = ("grid", "long", "wall-clock", "tuning")

T = TypeVar("T")


def longest_first(items: Sequence[T], seconds: Callable[[T], float], key: Callable[[T], str], bins: int) -> list[list[T]]:
    """
    Split ``items`` into ``bins`` lists as a pool of ``bins`` cores runs them longest first: the longest item still
    waiting goes to the list with the least seconds so far (on a tie, the fewest items, then the lowest-numbered).
    Every item lands in exactly one list, and no list is empty while another holds two; equal seconds are ordered by
    ``key``, so the split does not depend on the order of ``items``. The busiest list holds at most
    ``sum / bins + max`` seconds (and at most 4/3 of the best split's).

    :raises ValueError: if ``bins`` < 1
    """
    if bins < 1:
        raise ValueError(f"bins must be >= 1, got {bins}")
    loads = [(0.0, 0, b) for b in range(bins)]
    split: list[list[T]] = [[] for _ in range(bins)]
    for item in sorted(items, key=lambda i: (-seconds(i), key(i))):
        load, count, b = heapq.heappop(loads)
        split[b].append(item)
        heapq.heappush(loads, (load + seconds(item), count + 1, b))
    return split


def busiest_hours(durations: Sequence[float], cores: int) -> float:
    """Hours until ``cores`` cores have run jobs of ``durations`` seconds longest first (:func:`longest_first`)."""
    jobs = list(enumerate(durations))
    split = longest_first(jobs, lambda job: job[1], lambda job: f"{job[0]:09d}", cores)
    return max(sum(seconds for _, seconds in part) for part in split) / 3600


def wall_hours(preset: str | dict[str, Any], cores: int, only: str | None = None) -> dict[str, float]:
    """
    Estimated hours of wall time of a preset on ``cores`` cores (``only`` as in :func:`estimate`): ``"tuning"``, its
    tuning stage's unpruned trials; ``"cells"``, then its cells (every stage's in one run, as the runner runs them);
    ``"total"``, one after the other (tuned cells need their tuning stage's settings).
    """
    p = PRESETS[preset] if isinstance(preset, str) else preset
    try:
        studies = plan_studies(p, only=only) if "tuning" in p else []
    except ValueError:  # `only` matches no study
        studies = []
    tuning = busiest_hours([trial_seconds(study) for study in studies for _ in range(study.trials)], cores)
    cells = busiest_hours([cell_seconds(cell) for cell in select(build_cells(p), only)], cores)
    return {"tuning": tuning, "cells": cells, "total": tuning + cells}


def wall_text(preset: str | dict[str, Any], cores: Sequence[int], only: str | None = None) -> str:
    """:func:`wall_hours` for each count of ``cores``, as a table in minutes."""
    lines = [f"{'cores':>6s} {'tuning':>8s} {'cells':>8s} {'total':>8s}  (minutes)"]
    for n in cores:
        minutes = {stage: 60 * hours for stage, hours in wall_hours(preset, n, only).items()}
        lines.append(f"{n:6d} {minutes['tuning']:8.1f} {minutes['cells']:8.1f} {minutes['total']:8.1f}")
    return "\n".join(lines)


def estimate(preset: str | dict[str, Any], only: str | None = None) -> dict[str, dict[str, float]]:
    """Per stage (:data:`STAGES`) and env id: ``{"runs": cells or trials, "hours": core-hours}`` of a preset's cells
    and its tuning stage at the preset's size (``only``: the cells and studies matching those patterns, as the
    runner's ``--only``)."""
    p = PRESETS[preset] if isinstance(preset, str) else preset
    table: dict[str, dict[str, float]] = {}

    def add(stage: str, env_id: str, runs: int, seconds: float) -> None:
        row = table.setdefault(f"{stage}\t{env_id}", {"runs": 0.0, "hours": 0.0})
        row["runs"] += runs
        row["hours"] += seconds / 3600

    for cell in select(build_cells(p), only):
        add(stage_of(cell, p), cell.env_id, 1, cell_seconds(cell))
    if "tuning" in p:
        try:
            studies = plan_studies(p, only=only)
        except ValueError:  # `only` matches no study
            studies = []
        for study in studies:
            add("tuning", study.env_id, study.trials, study.trials * trial_seconds(study))
    return table


def estimate_text(preset: str | dict[str, Any], only: str | None = None) -> str:
    """The estimate as a table: per stage its env ids, runs and core-hours, the stage's total, and the total."""
    table = estimate(preset, only)
    lines = [f"{'stage':12s} {'env':24s} {'runs':>6s} {'core-hours':>11s}"]
    total = 0.0
    for stage in STAGES:
        rows = {key.split("\t")[1]: row for key, row in table.items() if key.split("\t")[0] == stage}
        if not rows:
            continue
        for env_id, row in rows.items():
            lines.append(f"{stage:12s} {env_id:24s} {row['runs']:6.0f} {row['hours']:11.2f}")
        hours = sum(row["hours"] for row in rows.values())
        total += hours
        lines.append(f"{stage:12s} {'(all)':24s} {sum(r['runs'] for r in rows.values()):6.0f} {hours:11.2f}")
    lines.append(f"{'total':12s} {'':24s} {'':6s} {total:11.2f}")
    return "\n".join(lines)
