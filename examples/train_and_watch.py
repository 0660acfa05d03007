"""
Train SarsaAAC to dribble, measure it on fresh players, and save a GIF of one episode.

    python examples/train_and_watch.py            # 100,000 env steps: seconds of training
    python examples/train_and_watch.py --quick    # a few seconds, to check the pipeline

Needs pygame and imageio (``pip install "sb3-aac[dev]"``). The same as
``sb3-aac train --out runs/watch && sb3-aac render runs/watch/model.zip``.
"""

from __future__ import annotations

import argparse

import imageio.v2 as imageio

from robocup_dribble import DribbleEnv, DribbleVecEnv
from robocup_dribble.evaluation import evaluate_dribbling
from sb3_aac import SarsaAAC


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a tiny budget")
    parser.add_argument("--gif", default="dribble.gif", help="where to write the episode")
    args = parser.parse_args()
    steps, episodes = (3_000, 100) if args.quick else (100_000, 1_000)

    env = DribbleVecEnv(16, profile="v11")  # the paper's server; 16 lanes stepped together
    env.seed(0)
    model = SarsaAAC("DeepPolicy", env, seed=0).learn(steps)  # what ``sb3-aac train`` trains by default

    report = evaluate_dribbling(model, episodes, profile="v11", seed=1)
    print("greedy, fresh players:", report.summary())

    watch = DribbleEnv(profile="v11", render_mode="rgb_array")
    obs, _ = watch.reset(seed=2)
    frames, done, info = [watch.render()], False, {}
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = watch.step(action)
        frames.append(watch.render())
        done = terminated or truncated
    watch.close()
    imageio.mimsave(args.gif, frames, duration=100, loop=0)  # 100 ms per frame: one server cycle
    print(f"wrote {args.gif}: {len(frames) - 1} actions, {info['distance']:.1f} m")


if __name__ == "__main__":
    main()
