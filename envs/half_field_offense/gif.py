"""One Half Field Offense trial as an animated GIF: ``python -m half_field_offense.gif --out trial.gif`` records the
hand-coded agent (:class:`half_field_offense.agent.HandCodedOffense`); :func:`save_trial_gif` records any policy.
Needs the ``render`` extra (pygame and imageio)."""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any

from half_field_offense.agent import HandCodedOffense
from half_field_offense.env import HalfFieldOffenseEnv


def save_trial_gif(policy: Any, path: str | Path, seed: int = 0, fps: int = 10, **env_kwargs: Any) -> str:
    """Play trial ``seed`` of :class:`HalfFieldOffenseEnv` greedily with ``policy`` (``predict(obs,
    deterministic=True)``) and write its frames to the GIF ``path``, replacing it only once the file is complete.

    :return: the trial's final status name.
    """
    import imageio.v2 as imageio

    env = HalfFieldOffenseEnv(render_mode="rgb_array", **env_kwargs)
    obs, info = env.reset(seed=seed)
    frames: list[Any] = [env.render()]
    while True:
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        frames.append(env.render())
        if terminated or truncated:
            break
    env.close()
    target = Path(path)
    with tempfile.NamedTemporaryFile(dir=target.parent, suffix=".gif", delete=False) as tmp:
        imageio.mimsave(tmp.name, frames, duration=1000 / fps, loop=0)
    os.replace(tmp.name, target)
    return str(info["status"])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split(":")[0])
    parser.add_argument("--out", default="trial.gif", help="the GIF to write (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="which trial (default: %(default)s)")
    args = parser.parse_args(argv)
    status = save_trial_gif(HandCodedOffense(), args.out, args.seed)
    print(f"{args.out}: the hand-coded agent's trial {args.seed}, {status}")


if __name__ == "__main__":
    main()
