"""
Sample efficiency on the domains with interacting inputs: SarsaAAC's greedy success against TD3's at the env steps
TD3 needs to reach 90 % of its final score (target: within 5 points).

TD3 is the grid's (:data:`benchmarks.presets.BASELINES`: SB3's TD3 through ``FlattenParameterizedAction``, 4 lanes,
one gradient step per transition, 64x64 nets, Gaussian action noise 0.1; :func:`benchmarks.adapters.build_baseline`);
SarsaAAC is a (task, policy) pair of :mod:`benchmarks.learning` (:func:`benchmarks.learning.build`), one lane unless
``--n-envs``. Every learner is scored every ``--every`` env steps by the task's greedy success rate (200 episodes of
``EVAL_SEED``, the same episodes for every learner) and once more at the end (500 episodes of ``FINAL_SEED``). Each
seed's curve is appended to ``--out`` as one JSON line, so learners and seeds can run in separate processes::

    PYTHONPATH=.:envs python -m benchmarks.sample_efficiency train --task moving --learner td3 --seeds 3
    PYTHONPATH=.:envs python -m benchmarks.sample_efficiency train --task moving --learner tile --seeds 3
    PYTHONPATH=.:envs python -m benchmarks.sample_efficiency train --task moving --learner deep --seeds 3 \\
        --set trace_lambda=0.8
    PYTHONPATH=.:envs python -m benchmarks.sample_efficiency train --task moving --learner tile --seeds 3 --n-envs 16
    PYTHONPATH=.:envs python -m benchmarks.sample_efficiency compare

(``--task catch`` likewise; ``--first-seed`` runs one seed per process.) ``compare`` reads the curves. TD3's reference
step ``S`` is the first checkpoint at which its seeds' mean curve reaches 90 % of their mean final score; a learner's
score at ``S`` is its curve at its first checkpoint at or past ``S``. It prints one line per (task, learner): the
per-seed scores at ``S``, their mean, IQM and the IQM's 95 % bootstrap CI over seeds, the difference of the means to
TD3's at ``S`` and the verdict (``met`` if the difference is at least -0.05), then the per-seed final scores; TD3's
line adds each seed's own steps to 90 % of its final score.
"""

from __future__ import annotations

import argparse
import ast
import json
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.learning import DOMAIN_TASKS, POLICIES, TASKS, build, iqm, iqm_ci
from sb3_aac.common.checkpoints import GreedyCheckpoints

TD3 = "td3"
REACH_SHARE = 0.9  # TD3's reference step: where it first reaches this share of its final score
TOLERANCE = 0.05  # the target: within 5 points of TD3's success at that step
DEFAULT_OUT = Path("benchmarks/results/learning/domain_curves.jsonl")


@dataclass(frozen=True)
class Curve:
    """One seed's greedy success ``(env steps, score)`` every ``every`` env steps, and its final score."""

    task: str
    learner: str  # "td3" or a policy name of benchmarks.learning.POLICIES
    lanes: int
    seed: int
    every: int
    steps: int
    points: list[tuple[int, float]]
    final: float
    seconds: float
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """The learner with its lanes and settings: the seeds of one label form one line of ``compare``."""
        return f"{self.learner} lanes={self.lanes}" + "".join(f" {key}={value}" for key, value in self.settings.items())

    def score_at(self, steps: int) -> float | None:
        """The score at the first checkpoint at or past ``steps`` (None if the curve ends before)."""
        return next((score for at, score in self.points if at >= steps), None)


def train(task: str, learner: str, seed: int, steps: int, every: int, n_envs: int | None, settings: dict[str, Any]) -> Curve:
    """Train one seed of ``learner`` on ``task`` for ``steps`` env steps, scoring it every ``every`` env steps."""
    score = TASKS[task][4]
    if learner == TD3:
        from benchmarks import adapters

        if n_envs is not None or settings:
            raise ValueError("TD3 keeps the grid's settings (4 lanes): --n-envs and --set are for SarsaAAC")
        env_id = DOMAIN_TASKS[task]
        model: Any = adapters.build_baseline(env_id, "TD3", seed)
        predictor = adapters.adapter_for(model, "TD3", env_id)
        lanes, kwargs = model.n_envs, {}
    else:
        model = build(task, learner, seed, n_envs, None, settings)
        predictor, lanes, kwargs = model, model.n_envs, {"log_interval": None}

    def checkpoint(_: Any) -> float:
        value = score(predictor, True)
        print(f"{task} {learner} seed={seed} steps={model.num_timesteps} score={value:.3f}", flush=True)
        return value

    watch = GreedyCheckpoints(every, checkpoint)
    start = time.process_time()
    model.learn(steps, callback=watch, **kwargs)
    seconds = time.process_time() - start
    return Curve(task, learner, lanes, seed, every, steps, watch.curve, score(predictor, False), seconds, settings)


def load(path: Path) -> list[Curve]:
    """The curves of a file written by ``train`` (a later line of the same seed and label replaces an earlier one)."""
    curves: dict[tuple[str, str, int], Curve] = {}
    for line in path.read_text().splitlines():
        record = json.loads(line)
        curve = Curve(**{**record, "points": [tuple(point) for point in record["points"]]})
        curves[(curve.task, curve.label, curve.seed)] = curve
    return list(curves.values())


def steps_to_share(points: Sequence[tuple[int, float]], final: float) -> int | None:
    """The first checkpoint's env steps whose score reaches :data:`REACH_SHARE` of ``final`` (None if none does)."""
    return next((at for at, score in points if score >= REACH_SHARE * final), None)


def reference_step(td3: list[Curve]) -> int | None:
    """TD3's reference step: where the seeds' mean curve first reaches :data:`REACH_SHARE` of their mean final score
    (None if it never does)."""
    length = min(len(curve.points) for curve in td3)
    checkpoints = [at for at, _ in td3[0].points[:length]]
    if any([at for at, _ in curve.points[:length]] != checkpoints for curve in td3):
        raise ValueError(f"TD3's curves of {td3[0].task} need common checkpoints (the same --every and lanes)")
    mean = np.mean([[score for _, score in curve.points[:length]] for curve in td3], axis=0)
    return steps_to_share(list(zip(checkpoints, mean.tolist(), strict=True)), float(np.mean([c.final for c in td3])))


def figures(values: Sequence[float]) -> str:
    low, high = iqm_ci(list(values))
    return (
        f"{[round(v, 3) for v in values]} mean={np.mean(values):.3f} iqm={iqm(list(values)):.3f} ci95=[{low:.3f}, {high:.3f}]"
    )


def compare(curves: list[Curve]) -> list[str]:
    """The lines of ``compare``: per task, TD3's first, then every other learner's at TD3's reference step."""
    lines = []
    for task in sorted({curve.task for curve in curves}):
        groups: dict[str, list[Curve]] = {}
        for curve in sorted(curves, key=lambda c: (c.label, c.seed)):
            if curve.task == task:
                groups.setdefault(curve.label, []).append(curve)
        td3 = next((group for label, group in groups.items() if group[0].learner == TD3), None)
        if td3 is None:
            lines.append(f"{task}: no TD3 curves, so no reference step")
            continue
        at = reference_step(td3)
        own = [steps_to_share(curve.points, curve.final) for curve in td3]
        head = f"{task:7s} {td3[0].label} seeds={[c.seed for c in td3]} steps={td3[0].steps}"
        head += f" final={figures([c.final for c in td3])} (seeds' own steps to {REACH_SHARE:.0%} of it: {own})"
        if at is None:
            lines.append(f"{head}: the seeds' mean curve never reaches {REACH_SHARE:.0%} of their mean final score")
            continue
        reference = [score for curve in td3 if (score := curve.score_at(at)) is not None]
        reference_mean = float(np.mean(reference))
        lines.append(f"{head} reference_step={at} at_reference={figures(reference)}")
        for label, group in groups.items():
            if group is td3:
                continue
            head = f"{task:7s} {label} seeds={[c.seed for c in group]} steps={group[0].steps}"
            scores = [score for curve in group if (score := curve.score_at(at)) is not None]
            if len(scores) < len(group):
                lines.append(f"{head} curves end before TD3's reference step {at}")
                continue
            difference = float(np.mean(scores)) - reference_mean
            verdict = "met" if difference >= -TOLERANCE else "missed"
            lines.append(
                f"{head} at_reference({at})={figures(scores)} vs TD3 {reference_mean:.3f}: {difference:+.3f} "
                f"{verdict} (target >= {-TOLERANCE:+.2f}) final={figures([c.final for c in group])}"
            )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("train", help="train seeds of one learner and append their curves to --out")
    run.add_argument("--task", required=True, choices=sorted(DOMAIN_TASKS))
    run.add_argument("--learner", required=True, choices=[TD3, *POLICIES])
    run.add_argument("--seeds", type=int, default=3)
    run.add_argument("--first-seed", type=int, default=0)
    run.add_argument("--steps", type=int, default=None, help="env steps (default: the task's budget)")
    run.add_argument("--every", type=int, default=5000, help="env steps between greedy checkpoints")
    run.add_argument("--n-envs", type=int, default=None, help="SarsaAAC's lanes (default: the task's)")
    run.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="SarsaAAC keyword arguments")
    run.add_argument("--out", type=Path, default=DEFAULT_OUT)
    show = commands.add_parser("compare", help="print the comparison of the curves in --out")
    show.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args()
    if args.command == "compare":
        for line in compare(load(args.out)):
            print(line, flush=True)
        return
    import torch as th

    th.set_num_threads(1)
    settings = {key: ast.literal_eval(value) for key, value in (item.split("=", 1) for item in args.set)}
    steps = args.steps or TASKS[args.task][2]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        curve = train(args.task, args.learner, seed, steps, args.every, args.n_envs, settings)
        with args.out.open("a") as out:
            out.write(json.dumps(asdict(curve)) + "\n")
        print(f"{curve.task} {curve.label} seed={seed} final={curve.final:.3f} cpu={curve.seconds:.0f}s", flush=True)


if __name__ == "__main__":
    main()
