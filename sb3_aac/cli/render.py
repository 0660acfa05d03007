"""``sb3-aac render``: one greedy episode of a policy to a GIF/MP4, or in a pygame window."""

from __future__ import annotations

import argparse
from typing import Any

from sb3_aac.cli.arguments import CliError, frame_rate, output_file, require_extra, written
from sb3_aac.cli.envs import PROFILE_ENV_IDS
from sb3_aac.cli.models import load_policy

VIDEO_SUFFIXES = (".gif", ".mp4")


def add_render_command(add: Any, played: argparse.ArgumentParser) -> None:
    """Add ``render`` through ``add(name, help, example, parents)``."""
    render = add(
        "render",
        "play one greedy episode to a GIF/MP4 or a window",
        "sb3-aac render runs/rbf/model.zip --out episode.gif",
        (played,),
    )
    render.add_argument("--out", default="episode.gif", help="video file, .gif or .mp4 (default: %(default)s)")
    render.add_argument("--window", action="store_true", help="show the episode in a pygame window instead of writing a file")
    render.add_argument("--fps", type=frame_rate, default=10.0, help="frames per second (default: %(default)s, server cycles)")
    render.set_defaults(func=cmd_render)


def cmd_render(args: argparse.Namespace) -> None:
    from robocup_dribble import DribbleEnv

    out = None if args.window else output_file(args.out, VIDEO_SUFFIXES, "--out")
    require_extra("render", "render", "pygame", *(() if out is None else ("imageio",)))
    if out is not None and out.suffix.lower() == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise CliError("writing .mp4 needs imageio-ffmpeg (pip install imageio-ffmpeg); or write a .gif") from None
    policy, profile = load_policy(args.model, args.profile, args.trust)
    try:
        env = DribbleEnv(profile=profile, render_mode="human" if args.window else "rgb_array")
        obs, info = env.reset(seed=args.seed)
        frames: list[Any] = [] if args.window else [env.render()]
    except Exception as error:  # pygame missing or no display
        raise CliError(f"cannot render: {error}") from None
    done, steps = False, 0
    while not done:
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        done, steps = terminated or truncated, steps + 1
        if not args.window:
            frames.append(env.render())
    env.close()
    outcome = "lost the ball" if info["ball_lost"] else "kept the ball to the action limit"
    print(f"one episode of {args.model} on {PROFILE_ENV_IDS[profile]}: {steps} actions, {info['distance']:.2f} m, {outcome}")
    if out is None:
        return
    import imageio.v2 as imageio

    with written(out) as tmp:
        if out.suffix.lower() == ".gif":
            imageio.mimsave(tmp, frames, duration=1000 / args.fps, loop=0)
        else:
            imageio.mimsave(tmp, frames, fps=args.fps)
    print(f"wrote {out} ({len(frames)} frames)")
