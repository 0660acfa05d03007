"""``sb3-aac evaluate`` and ``sb3-aac reliability``: greedy metrics of a trained policy (or the hand-coded dribbler)
on fresh heterogeneous players, and the paper's reliability test with its figure."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from sb3_aac.cli.arguments import episode_count, output_file, require_extra, written
from sb3_aac.cli.envs import PROFILE_ENV_IDS, add_perception_argument
from sb3_aac.cli.models import load_policy
from sb3_aac.cli.reports import print_dribble_report, reliability_figure


def add_evaluate_commands(add: Any, played: argparse.ArgumentParser) -> None:
    """Add ``evaluate`` and ``reliability`` through ``add(name, help, example, parents)``; ``played`` holds the
    arguments of every command that plays a policy (MODEL, --profile, --seed)."""
    evaluate = add(
        "evaluate",
        "greedy metrics of MODEL on fresh heterogeneous players",
        "sb3-aac evaluate runs/rbf/model.zip --episodes 1000   |   sb3-aac evaluate dribbler --profile v11",
        (played,),
    )
    evaluate.add_argument("--episodes", type=episode_count, default=1000, help="episodes (default: %(default)s)")
    add_perception_argument(evaluate)
    evaluate.set_defaults(func=cmd_evaluate)

    reliability = add(
        "reliability",
        "the paper's reliability test: fresh players dribble once each; prints a summary, plots Figs. 9-10 to a PNG",
        "sb3-aac reliability runs/rbf/model.zip --out runs/rbf/reliability.png",
        (played,),
    )
    reliability.add_argument(
        "--players", type=episode_count, default=10_000, help="players (default: %(default)s, as the paper)"
    )
    reliability.add_argument("--out", default="reliability.png", help="PNG to write (default: %(default)s)")
    reliability.set_defaults(func=cmd_reliability)


def cmd_evaluate(args: argparse.Namespace) -> None:
    from robocup_dribble.evaluation import evaluate_dribbling

    policy, profile = load_policy(args.model, args.profile, args.trust)
    start = time.perf_counter()
    report = evaluate_dribbling(policy, args.episodes, profile=profile, seed=args.seed, perception=args.perception)
    print_dribble_report(
        report,
        f"{args.model} on {PROFILE_ENV_IDS[profile]} (perception {args.perception}): {len(report.distances)} greedy "
        "episodes of fresh heterogeneous players "
        f"({time.perf_counter() - start:.1f} s)",
    )


def cmd_reliability(args: argparse.Namespace) -> None:
    from robocup_dribble.evaluation import reliability_test

    out = output_file(args.out, (".png",), "--out")
    require_extra("plots", "reliability's figure", "matplotlib")
    policy, profile = load_policy(args.model, args.profile, args.trust)
    report = reliability_test(policy, args.players, profile=profile, seed=args.seed)
    print(f"reliability test of {args.model} on {PROFILE_ENV_IDS[profile]}: {args.players} fresh players, one episode each")
    print(f"  {report.summary()}")
    for metres in (5, 10, 15, 20, 25):
        print(f"  reached {metres:2d} m: {100 * report.share_reaching(metres):5.1f} %")
    fig = reliability_figure(report, f"{Path(args.model).name} on {PROFILE_ENV_IDS[profile]} (as Uc-Cetina 2013, Figs. 9-10)")
    import matplotlib.pyplot as plt  # after the figure chose the Agg backend

    with written(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    print(f"wrote {out}")
