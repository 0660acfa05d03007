"""``sb3-aac push``: evaluate a trained dribbling model and share it on the Hugging Face Hub with a model card."""

from __future__ import annotations

import argparse
import re
import tempfile
from typing import Any

from sb3_aac.cli.arguments import CliError, add_trust_argument, episode_count, input_file, require_extra, seed_int
from sb3_aac.cli.envs import PROFILE_ENV_IDS
from sb3_aac.cli.models import load_policy

# The Hub's repository ids: a user or organisation, a slash, a name (letters, digits, '-', '_', '.'; 96 at most).
HUB_TIMEOUT_S = 60.0  # seconds the Hub may stay silent (connecting, or between two reads) before push gives up
REPO_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,95}/[A-Za-z0-9][A-Za-z0-9_.-]{0,95}$")


def add_push_command(add: Any) -> None:
    """Add ``push`` through ``add(name, help, example)``."""
    push = add(
        "push",
        "evaluate MODEL greedily and upload it to the Hugging Face Hub with its exported policy and a model card",
        "sb3-aac push runs/tile/model.zip --repo-id you/sarsa-aac-dribble   (log in first: huggingface-cli login)",
    )
    push.add_argument("model", metavar="MODEL", help="a model.zip saved by train")
    push.add_argument("--repo-id", required=True, help="the Hub model repository, USER/NAME (created if missing)")
    push.add_argument("--profile", choices=list(PROFILE_ENV_IDS), help="server profile (default: inferred from MODEL)")
    push.add_argument("--episodes", type=episode_count, default=1000, help="evaluation episodes (default: %(default)s)")
    push.add_argument("--seed", type=seed_int, default=0, help="seed of the evaluation episodes (default: %(default)s)")
    push.add_argument("--folder", help="write the files here (default: a temporary folder, removed after the upload)")
    push.add_argument("--overwrite", action="store_true", help="replace the files --folder already holds")
    push.add_argument("--dry-run", action="store_true", help="write --folder and upload nothing")
    push.add_argument("--private", action="store_true", help="create the repository as private")
    add_trust_argument(push)
    push.set_defaults(func=cmd_push)


def cmd_push(args: argparse.Namespace) -> None:
    from robocup_dribble.evaluation import evaluate_dribbling

    from sb3_aac.hub import Evaluation

    if not REPO_ID.match(args.repo_id):
        raise CliError(f"--repo-id must be USER/NAME (letters, digits, '-', '_', '.'), got {args.repo_id!r}")
    if args.dry_run and args.folder is None:
        raise CliError("--dry-run writes the files into --folder: give one")
    if not args.dry_run:
        require_extra("hub", "push", "huggingface_hub")
    input_file(args.model, (".zip",), "MODEL")
    model, profile = load_policy(args.model, args.profile, args.trust)
    env_id = PROFILE_ENV_IDS[profile]
    report = evaluate_dribbling(model, args.episodes, profile=profile, seed=args.seed)
    evaluation = Evaluation(
        env_id,
        len(report.distances),
        {
            "mean_distance": report.mean_distance,
            "share_reaching_20m": report.share_reaching(20),
            "ball_loss_rate": report.loss_rate,
        },
        protocol=f"greedy actions, fresh heterogeneous players (sb3-aac evaluate, seed {args.seed})",
        units={"mean_distance": "m"},
    )
    print(f"{args.model} on {env_id}: mean distance {report.mean_distance:.2f} m over {len(report.distances)} episodes")
    if args.folder is not None:
        push_from(model, args.folder, evaluation, args)
        return
    with tempfile.TemporaryDirectory(prefix="sb3-aac-push-") as folder:
        push_from(model, folder, evaluation, args)


def push_from(model: Any, folder: str, evaluation: Any, args: argparse.Namespace) -> None:
    """Write the Hub folder, then upload it (unless --dry-run)."""
    from sb3_aac.hub import hub_folder, push_folder

    try:
        files = hub_folder(model, folder, evaluation, args.repo_id, overwrite=args.overwrite)
    except ValueError as error:
        raise CliError(str(error)) from None
    print(f"wrote {', '.join(files)} into {folder}")
    if args.dry_run:
        return
    try:
        url = push_folder(folder, files, args.repo_id, api=hub_api(), private=args.private)
    except Exception as error:  # huggingface_hub raises HTTP, auth and connection errors of many types
        raise CliError(f"cannot upload to {args.repo_id}: {type(error).__name__}: {error}") from None
    print(f"uploaded to {url}")


def hub_api() -> Any:
    """The ``huggingface_hub.HfApi`` the upload goes through (the logged-in token), on a session that gives up after
    :data:`HUB_TIMEOUT_S` of silence (huggingface_hub's own waits forever on an endpoint that never answers)."""
    from huggingface_hub import HfApi, get_session

    get_session().timeout = HUB_TIMEOUT_S
    return HfApi()
