"""``sb3-aac pitch``: play a policy on a real rcssserver and in the env on the same episodes, and test the difference."""

from __future__ import annotations

import argparse
import csv
import sys
from typing import Any

from sb3_aac.cli.arguments import CliError, episode_count, output_file, positive_float, seed_int, written
from sb3_aac.cli.models import load_policy

CSV_COLUMNS = ("episode", "type_id", "real_distance", "real_ball_lost", "sim_distance", "sim_ball_lost")


def add_pitch_command(add: Any, played: argparse.ArgumentParser) -> None:
    """Add ``pitch`` through ``add(name, help, example, parents)``; ``played`` holds MODEL, --profile and --seed."""
    pitch = add(
        "pitch",
        "play MODEL on a real rcssserver 19 (started on loopback only) and in the env on the same episodes; "
        "print both, their difference and Welch's test",
        "sb3-aac pitch runs/tile/model.zip --server ~/rcssserver-19.0.0/build/rcssserver --episodes 1000 --out pitch.csv",
        (played,),
    )
    pitch.add_argument(
        "--server",
        metavar="PATH",
        help="the rcssserver 19 binary (default: $RCSSSERVER, else rcssserver on PATH); see docs/pitch.md to build it",
    )
    pitch.add_argument("--episodes", type=episode_count, default=1000, help="episodes on each side (default: %(default)s)")
    pitch.add_argument(
        "--world-seed",
        type=seed_int,
        default=1,
        help="the server's player::random_seed: which 18 heterogeneous types it has (default: %(default)s)",
    )
    pitch.add_argument(
        "--timeout", type=positive_float, default=10.0, help="seconds to wait for the server (default: %(default)s)"
    )
    pitch.add_argument(
        "--perceive",
        action="store_true",
        help="the policy sees what a player in a match sees instead of the exact state: on the server its own "
        "see/sense_body, in the env the env's model of that perception (perception='match')",
    )
    pitch.add_argument("--out", help="write the per-episode results to this .csv file")
    pitch.set_defaults(func=cmd_pitch)


def cmd_pitch(args: argparse.Namespace) -> None:
    from robocup_dribble.evaluation import evaluate_episodes
    from robocup_dribble.rcss import ServerError, checked_profile, find_server, play_on_server, server_episodes, server_options
    from robocup_dribble.rcss.server import checked_timeout

    from sb3_aac.common.statistics import mean_interval, welch_test

    try:
        checked_timeout(args.timeout)
    except ValueError as error:
        raise CliError(f"--timeout: {error}") from None
    out = output_file(args.out, (".csv",), "--out") if args.out else None
    if args.profile == "v11":
        raise CliError(
            "--profile v11 cannot be played on a real server: only rcssserver 19 can be built "
            "(no v11-era server is obtainable)"
        )
    server = args.server or find_server()
    if server is None:
        raise CliError("no rcssserver found: give --server PATH or set RCSSSERVER (docs/pitch.md: building rcssserver 19)")
    policy, profile = load_policy(args.model, args.profile, args.trust)
    if profile != "v19":
        raise CliError(f"{args.model} plays profile {profile}; only v19 can be played on a real server")
    try:
        import scipy  # noqa: F401
    except ImportError:
        raise CliError("pitch needs scipy for its test (pip install scipy)") from None
    try:
        server_options(checked_profile(profile), args.world_seed)  # the server's limits on the seed, before any work
    except ValueError as error:
        raise CliError(f"--world-seed: {error}") from None
    episodes = server_episodes(args.episodes, world_seed=args.world_seed, seed=args.seed, profile=profile)
    perception = "match" if args.perceive else "full"
    print(f"{args.model}: {args.episodes} episodes of world {args.world_seed} (player::random_seed), seed {args.seed}")
    if args.perceive:
        print("  the policy acts on its own perception: on the server see/sense_body, in the env perception='match'")
    else:
        print("  the policy acts on the exact state: on the server fullstate, in the env the state")
    with _progress(args.episodes) as advance:
        try:
            real = play_on_server(
                policy, episodes, server=server, timeout=args.timeout, on_episode=advance, perceive=args.perceive
            )
        except (ServerError, ValueError) as error:
            raise CliError(str(error)) from None
    sim = evaluate_episodes(
        policy, episodes.player_types, episodes.start_states, profile=profile, seed=args.seed, perception=perception
    )
    for name, report in (("real server", real), ("env        ", sim)):
        low, high = mean_interval(report.distances)
        print(f"  {name}  {report.mean_distance:6.2f} m [{low:.2f}, {high:.2f}]  ball lost {100 * report.loss_rate:5.1f} %")
    t, p = welch_test(real.distances, sim.distances)
    print(f"  difference   {real.mean_distance - sim.mean_distance:+6.2f} m (real - env), Welch t = {t:.2f}, p = {p:.3g}")
    if out is not None:
        with written(out) as tmp, open(tmp, "w", newline="") as file:
            writer = csv.writer(file)
            writer.writerow(CSV_COLUMNS)
            for j in range(args.episodes):
                writer.writerow(
                    (j, int(episodes.type_ids[j]), f"{real.distances[j]:.6f}", int(real.ball_lost[j]),
                     f"{sim.distances[j]:.6f}", int(sim.ball_lost[j]))
                )  # fmt: skip
        print(f"wrote {out}")


class _progress:
    """A tqdm bar on stderr counting episodes (none if tqdm is not installed); ``with`` gives the per-episode callback."""

    def __init__(self, total: int) -> None:
        self.total = total
        self.bar: Any = None

    def __enter__(self) -> Any:
        try:
            from tqdm import tqdm
        except ImportError:
            return None
        self.bar = tqdm(total=self.total, unit="episode", desc="real server", file=sys.stderr)
        return lambda index, distance, lost: self.bar.update(1)

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.close()
