"""The benchmark's domains: how each env id is built for training and how a policy is scored on it.

* Dribbling (``RoboCupDribblePaper-v0``, ``RoboCupDribble-v0``): batched :class:`~robocup_dribble.DribbleVecEnv`
  lanes; scored by :func:`robocup_dribble.evaluation.evaluate_dribbling` (metres along +x), whose episode slots each
  have their own seeded player, start state and noise (common random numbers).
* Episodic domains (:data:`EPISODIC`): Platform-v0 (PyPI ``hybrid-platform``), this repository's
  ``hybrid_domains`` (Goal-v0, Moving-v0, Sliding-v0, CatchPoint-v0) and ``HalfFieldOffense-v0``, one Gymnasium env
  each (:func:`episodic_env`) in SB3's ``DummyVecEnv`` (HFO's own learners: its batched vector env); scored by
  greedy episodes, episode slot ``j`` of a set with seed ``s`` starting from ``reset(seed=s * SLOT_STRIDE + j)``, so
  every policy meets the same episodes too. Each is ranked by its published metric (:func:`metric`): mean return
  (Platform, Moving, Sliding) or success share (Goal and HFO: P(goal); CatchPoint).

Each score comes as the summary every result file uses (:func:`summarize`) plus the per-episode scores in slot
order, so two policies' episodes can be paired.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from hybrid_domains.reference_inputs import GoalFeatures
from robocup_dribble import ENV_PROFILES, DribbleVecEnv
from robocup_dribble.evaluation import evaluate_dribbling
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecEnv

from benchmarks.presets import HFO_ID, HYBRID_IDS, PLATFORM_ID
from sb3_aac import SelectObservation

REACH_METRES = 20.0  # the paper's "at least around 20 meters with high reliability" (section 4.1)
SLOT_STRIDE = 1_000_003  # a prime: the reset seeds of two evaluation sets never meet
PLATFORM_SUCCESS_RETURN = 1.0  # Platform's return is the share of the level covered: 1 reaches the goal

# Published Platform-v0 figures (mean return of the trained greedy policy), drawn as reference lines:
# (label with the protocol behind the figure, mean return, citation). The protocol: a mean over seeds, the best of N
# agents, or "not re-read" where our sources give the figure without it (HyAR's Table 2).
PLATFORM_REFERENCES: tuple[tuple[str, float, str], ...] = (
    ("MP-DQN (mean over seeds)", 0.987, "Bester, James, Konidaris 2019, arXiv:1905.04388"),
    ("HyAR-TD3 (protocol not re-read)", 0.98, "Li et al., ICLR 2022 (HyAR), Table 2"),
    ("P-DQN (protocol not re-read)", 0.93, "as reported by Li et al., ICLR 2022, Table 2"),
    ("H-PPO (protocol not re-read)", 0.80, "as reported by Li et al., ICLR 2022, Table 2"),
)


@dataclass(frozen=True)
class EpisodicDomain:
    """How an episodic benchmark domain is built and scored.

    :param make: the env learners train and are scored on (Box observations, the env's parameterized actions)
    :param metric: the summary key that ranks policies, ``"return_mean"`` or ``"success_share"``
    :param success_key: the ``info`` key that flags a successful episode at its last step, or None: success is a
        return of at least :data:`PLATFORM_SUCCESS_RETURN`
    :param references: published figures of ``metric``: (label, value, citation)
    """

    make: Callable[[], gym.Env]
    metric: str
    success_key: str | None
    references: tuple[tuple[str, float, str], ...]


def _platform() -> gym.Env:
    import gym_platform  # noqa: F401  (registers Platform-v0)

    return SelectObservation(gym.make(PLATFORM_ID), 0)


def _hybrid(env_id: str) -> Callable[[], gym.Env]:
    def make() -> gym.Env:
        import hybrid_domains  # noqa: F401  (registers the ids)

        env = gym.make(env_id)
        if env_id == "Goal-v0":  # the reference MP-DQN code's 17 inputs (the state and 3 keeper features)
            return GoalFeatures(env)
        return env

    return make


def _half_field_offense() -> gym.Env:
    import half_field_offense  # noqa: F401  (registers HalfFieldOffense-v0)

    return gym.make(HFO_ID)


# Half Field Offense's published P(goal) (docs/half_field_offense.md has their protocols: the best agent or the mean
# over seeds).
HFO_REFERENCES: tuple[tuple[str, float, str], ...] = (
    ("MP-DQN (mean over seeds)", 0.913, "Bester, James, Konidaris 2019, arXiv:1905.04388"),
    ("P-DQN (best of 9)", 0.997, "Xiong et al. 2018, arXiv:1810.06394"),
    ("PA-DDPG (best of 7)", 1.0, "Hausknecht & Stone, ICLR 2016"),
    ("Helios (hand-coded)", 0.962, "as reported by Hausknecht & Stone, ICLR 2016"),
)

# Published figures of the new domains (Li et al., ICLR 2022 (HyAR), Table 2, as summarised in the issue; DI-engine's
# Moving-v0 curve read off its docs plot at 3M steps).
EPISODIC: dict[str, EpisodicDomain] = {
    PLATFORM_ID: EpisodicDomain(_platform, "return_mean", None, PLATFORM_REFERENCES),
    "Goal-v0": EpisodicDomain(
        _hybrid("Goal-v0"),
        "success_share",
        "goal",
        (
            ("MP-DQN (mean over seeds)", 0.789, "Bester, James, Konidaris 2019, arXiv:1905.04388"),
            ("HyAR-TD3 (protocol not re-read)", 0.78, "Li et al., ICLR 2022 (HyAR), Table 2"),
            ("PDQN-TD3 (protocol not re-read)", 0.71, "as reported by Li et al., ICLR 2022, Table 2"),
        ),
    ),
    "Moving-v0": EpisodicDomain(
        _hybrid("Moving-v0"),
        "return_mean",
        "success",
        (("H-PPO (mean of 5 seeds, read off a plot)", 1.7, "DI-engine docs, gym_hybrid Moving-v0, 3M steps"),),
    ),
    "Sliding-v0": EpisodicDomain(_hybrid("Sliding-v0"), "return_mean", "success", ()),
    "CatchPoint-v0": EpisodicDomain(
        _hybrid("CatchPoint-v0"),
        "success_share",
        "caught",
        (("HyAR-TD3 (protocol not re-read)", 0.90, "Li et al., ICLR 2022 (HyAR), Table 2"),),
    ),
    HFO_ID: EpisodicDomain(_half_field_offense, "success_share", "is_success", HFO_REFERENCES),
}
assert set(EPISODIC) == {PLATFORM_ID, *HYBRID_IDS, HFO_ID}


def is_dribbling(env_id: str) -> bool:
    return env_id in ENV_PROFILES


def info_keywords(env_id: str) -> tuple[str, ...]:
    """The ``info`` keys every learner logs as ``rollout/ep_<key>_mean`` on ``env_id``: the dribbling env's metres and
    lost balls; none on the episodic domains (their success flag is SB3's ``rollout/success_rate``)."""
    return ("distance", "ball_lost") if is_dribbling(env_id) else ()


def episodic_domain(env_id: str) -> EpisodicDomain:
    """The :class:`EpisodicDomain` of ``env_id``; a ValueError names the known ids otherwise."""
    if env_id not in EPISODIC:
        raise ValueError(f"unknown env id {env_id!r}; the benchmark knows {[*ENV_PROFILES, *EPISODIC]}")
    return EPISODIC[env_id]


def metric(env_id: str) -> str:
    """The key of the summary that ranks policies on ``env_id``."""
    return "distance_mean" if is_dribbling(env_id) else episodic_domain(env_id).metric


def metric_label(env_id: str) -> str:
    if is_dribbling(env_id):
        return "metres dribbled"
    if env_id in ("Goal-v0", HFO_ID):
        return "P(goal)"
    return "mean return" if metric(env_id) == "return_mean" else "success share"


def episodic_env(env_id: str, wrapper: Callable[[gym.Env], gym.Env] | None = None) -> gym.Env:
    """One env of an episodic domain with a Box observation (and ``wrapper`` around it, e.g. an action wrapper)."""
    env = episodic_domain(env_id).make()
    return wrapper(env) if wrapper is not None else env


def train_env(env_id: str, n_envs: int, seed: int, wrapper: Callable[[gym.Env], gym.Env] | None = None) -> VecEnv:
    """The training VecEnv of a cell that acts in the env's own parameterized action space (``wrapper`` None) or
    through an action wrapper. Dribbling: ``DribbleVecEnv`` lanes (wrapped ones: :mod:`benchmarks.adapters`)."""
    if is_dribbling(env_id):
        if wrapper is not None:
            raise ValueError("dribbling baselines train on benchmarks.adapters.baseline_env (batched wrappers)")
        env = DribbleVecEnv(n_envs, profile=ENV_PROFILES[env_id])
        env.seed(seed)
        return env
    episodic_domain(env_id)  # a clear error for an unknown id, before any env is built
    if env_id == HFO_ID and wrapper is None:  # its trials step side by side in compiled code
        from half_field_offense import HalfFieldOffenseVecEnv

        trials = HalfFieldOffenseVecEnv(n_envs)
        trials.seed(seed)
        return trials
    return make_vec_env(lambda: episodic_env(env_id, wrapper), n_envs=n_envs, seed=seed)


def distance_stats(d: np.ndarray) -> dict[str, float]:
    """Mean, median and max of per-episode metres (the keys every dribbling result uses)."""
    return {"distance_mean": float(np.mean(d)), "distance_median": float(np.median(d)), "distance_max": float(np.max(d))}


def summarize(
    env_id: str, scores: np.ndarray, ball_lost: np.ndarray | None = None, success: np.ndarray | None = None
) -> dict[str, Any]:
    """The summary every result file uses, from per-episode scores in slot order (kept under ``"episode_scores"``).

    ``ball_lost`` (dribbling, required) and ``success`` (episodic domains with a success flag; without it success is a
    return of at least :data:`PLATFORM_SUCCESS_RETURN`) are per-episode flags in the same order."""
    d = np.asarray(scores, dtype=float)
    episode_scores = [round(float(x), 4) for x in d]
    if is_dribbling(env_id):
        if ball_lost is None:
            raise ValueError(f"a dribbling summary needs the per-episode ball_lost flags ({env_id})")
        return {
            "episodes": len(d),
            **distance_stats(d),
            "reach20_share": float(np.mean(d >= REACH_METRES)),
            "ball_loss_rate": float(np.mean(ball_lost)),
            "episode_scores": episode_scores,
        }
    return {
        "episodes": len(d),
        "return_mean": float(np.mean(d)),
        "return_median": float(np.median(d)),
        "success_share": float(np.mean(d >= PLATFORM_SUCCESS_RETURN - 1e-6 if success is None else success)),
        "episode_scores": episode_scores,
    }


def evaluate(env_id: str, policy: Any, n_episodes: int, seed: int) -> dict[str, Any]:
    """Greedy score of ``policy`` (anything with SB3's ``predict``) on episode slots ``0..n_episodes-1`` of set
    ``seed`` of ``env_id``: :func:`summarize`'s summary."""
    if is_dribbling(env_id):
        report = evaluate_dribbling(policy, n_episodes, ENV_PROFILES[env_id], seed)
        return summarize(env_id, report.distances, report.ball_lost)
    return summarize(env_id, *episodic_returns(env_id, policy, n_episodes, seed))


def episodic_returns(env_id: str, policy: Any, n_episodes: int, seed: int) -> tuple[np.ndarray, np.ndarray | None]:
    """Undiscounted returns of greedy episodes of an episodic domain, slot ``j`` reset with seed
    ``seed * SLOT_STRIDE + j``, and the per-episode success flags if the domain reports them (else None)."""
    key = episodic_domain(env_id).success_key
    returns, success = play_episodes(episodic_env(env_id), policy, n_episodes, seed, key)
    return returns, (success if key is not None else None)


def play_episodes(
    env: gym.Env, policy: Any, n_episodes: int, seed: int, success_key: str | None
) -> tuple[np.ndarray, np.ndarray]:
    """Undiscounted returns of greedy episodes of ``env`` (closed after), slot ``j`` reset with seed
    ``seed * SLOT_STRIDE + j``, and whether ``info[success_key]`` was true at each one's last step (all False for
    ``success_key`` None)."""
    if n_episodes < 1:
        env.close()
        raise ValueError(f"n_episodes must be >= 1, got {n_episodes}")
    returns = np.zeros(n_episodes)
    success = np.zeros(n_episodes, dtype=bool)
    try:
        for slot in range(n_episodes):
            obs, _ = env.reset(seed=seed * SLOT_STRIDE + slot)
            done = False
            while not done:
                action, _ = policy.predict(obs, deterministic=True)
                obs, reward, terminated, truncated, info = env.step(action)
                returns[slot] += float(reward)
                done = terminated or truncated
            success[slot] = bool(info.get(success_key, False)) if success_key is not None else False
    finally:
        env.close()
    return returns, success
