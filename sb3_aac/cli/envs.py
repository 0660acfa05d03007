"""The envs the commands train and play: the dribbling ids and their server profiles, Half Field Offense, the toy env,
envs other packages register (``--gym-package``), and the training env of an id."""

from __future__ import annotations

from typing import Any

import half_field_offense
from half_field_offense import HFOTask
from robocup_dribble import ENV_PROFILES
from robocup_dribble.perception import PERCEPTIONS
from sb3_aac.cli.arguments import CliError
from sb3_aac.common.envs import TOY_ENV_ID, register_toy_env

DRIBBLE_IDS = ENV_PROFILES  # dribbling env id -> server profile (the one table, robocup_dribble's)
PROFILE_ENV_IDS = {profile: env_id for env_id, profile in DRIBBLE_IDS.items()}


def import_gym_packages(names: list[str]) -> None:
    import importlib

    for name in names:
        try:
            importlib.import_module(name)
        except (ImportError, TypeError, ValueError) as error:  # TypeError/ValueError: relative or empty names (".", "")
            raise CliError(f"--gym-package {name!r} cannot be imported ({error}); is it installed / on PYTHONPATH?") from None


def check_env_id(env_id: str) -> None:
    import gymnasium as gym

    register_toy_env()
    if env_id not in gym.registry:
        known = [*DRIBBLE_IDS, half_field_offense.ENV_ID, TOY_ENV_ID]
        raise CliError(
            f"unknown env id {env_id!r}; sb3-aac's ids are {known}. For another parameterized-action env, register it "
            "with gymnasium and pass the module that registers it with --gym-package MODULE"
        )


def max_episode_length(env_id: str) -> int:
    import gymnasium as gym

    if env_id in DRIBBLE_IDS:
        from robocup_dribble import DribbleTask

        return DribbleTask().max_actions
    if env_id == half_field_offense.ENV_ID:
        return HFOTask().frames_per_trial + 1
    spec = gym.spec(env_id)
    if spec.max_episode_steps is not None:
        return int(spec.max_episode_steps)
    if env_id == TOY_ENV_ID:
        return 10
    raise CliError(f"{env_id} declares no max_episode_steps, so an --episodes budget has no step bound: use --timesteps")


def add_perception_argument(parser: Any) -> None:
    """``--perception``: what the policy reads in the dribbling envs (their ``perception`` option)."""
    parser.add_argument(
        "--perception",
        choices=PERCEPTIONS,
        default="full",
        help="dribbling envs: the policy reads the exact state (full) or a match player's own perception, rcssserver's "
        "quantised see/sense_body and the estimate kept from them (match) (default: %(default)s)",
    )


def make_train_env(env_id: str, n_envs: int, seed: int | None, perception: str = "full") -> Any:
    """``n_envs`` lanes of ``env_id`` seeded with ``seed``; ``perception`` (``"full"`` or ``"match"``) is the dribbling
    envs' option (robocup_dribble.perception), refused for any other env."""
    if env_id in DRIBBLE_IDS:
        from robocup_dribble import DribbleVecEnv

        env = DribbleVecEnv(n_envs, profile=DRIBBLE_IDS[env_id], perception=perception)
        env.seed(seed)
        return env
    if perception != "full":
        raise CliError(f"--perception {perception} is an option of the dribbling envs {sorted(DRIBBLE_IDS)}, not of {env_id}")
    if env_id == half_field_offense.ENV_ID:
        trials = half_field_offense.HalfFieldOffenseVecEnv(n_envs)
        trials.seed(seed)
        return trials
    from stable_baselines3.common.env_util import make_vec_env

    try:
        return make_vec_env(env_id, n_envs=n_envs, seed=seed)
    except Exception as error:  # any failure of a third-party env's constructor
        raise CliError(f"cannot make {env_id}: {type(error).__name__}: {error}") from None
