"""The benchmark grid: cells = env id x algorithm x approximator config x seed x budget.

Every number here is our choice; the reasons are next to them. A cell is plain data (:class:`Cell`), so it can be
sent to a worker process and written into its result file as is.

SarsaAAC configs are the paper's three families (Uc-Cetina 2013, Figs. 5-7), all other hyperparameters at the
SarsaAAC defaults (16 lanes of ``DribbleVecEnv``):

* ``mlp2/10/20``: ``MlpPolicy`` with 2, 10, 20 hidden tanh units per approximator;
* ``rbfmlp2/10/20``: ``RbfMlpPolicy``, a filter layer of 10 Gaussian RBFs per input, then 2, 10, 20 hidden units;
* ``rbf10/30/50``: ``RbfPolicy``, arrays of 10, 30, 50 Gaussian RBFs per input, linear output.

SB3 baselines (:data:`BASELINES`) train on the same env ids for the same number of env steps, through
:class:`~sb3_aac.FlattenParameterizedAction` (PPO, A2C, SAC, TD3, DDPG: ``Box(11)``) or
:class:`~sb3_aac.DiscretizeParameterizedAction` (DQN: ``Discrete(80)``, 5 values per parameter). Their
hyperparameters are SB3's defaults except where :data:`BASELINES` says otherwise, and why.
"""

from __future__ import annotations

import fnmatch
from dataclasses import asdict, dataclass, field
from typing import Any

from robocup_dribble import ENV_PROFILES

ENV_IDS = ("RoboCupDribblePaper-v0", "RoboCupDribble-v0")
ENV_SHORT = {"RoboCupDribblePaper-v0": "paper", "RoboCupDribble-v0": "v19"}

# Evaluation seeds of evaluate_dribbling: the same players, starts and noise for every cell of an env, and none of
# them shared with training (training seeds are small integers) or with each other.
EVAL_SEED = 10_000  # the learning curves: `eval_episodes` greedy episodes every `eval_every` training episodes
FINAL_SEED = 20_000  # the final evaluation of a trained model (`final_episodes` greedy episodes)
RELIABILITY_SEED = 30_000  # the reliability test (10,000 fresh players, one episode each)

SARSA_N_ENVS = 16  # DribbleVecEnv lanes for SarsaAAC (the README's setting)

# name: (family, policy, policy_kwargs)
SARSA_CONFIGS: dict[str, tuple[str, str, dict[str, Any]]] = {
    "mlp2": ("MLP", "MlpPolicy", {"hidden_units": 2}),
    "mlp10": ("MLP", "MlpPolicy", {"hidden_units": 10}),
    "mlp20": ("MLP", "MlpPolicy", {"hidden_units": 20}),
    "rbfmlp2": ("MLP+RBF", "RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 2}),
    "rbfmlp10": ("MLP+RBF", "RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 10}),
    "rbfmlp20": ("MLP+RBF", "RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 20}),
    "rbf10": ("RBF", "RbfPolicy", {"n_rbf": 10}),
    "rbf30": ("RBF", "RbfPolicy", {"n_rbf": 30}),
    "rbf50": ("RBF", "RbfPolicy", {"n_rbf": 50}),
}
FAMILIES = ("MLP", "MLP+RBF", "RBF")
CONFIG_LABELS = {
    "mlp2": "MLP (2 hidden)",
    "mlp10": "MLP (10 hidden)",
    "mlp20": "MLP (20 hidden)",
    "rbfmlp2": "MLP+RBF (2 hidden)",
    "rbfmlp10": "MLP+RBF (10 hidden)",
    "rbfmlp20": "MLP+RBF (20 hidden)",
    "rbf10": "RBF arrays (10/input)",
    "rbf30": "RBF arrays (30/input)",
    "rbf50": "RBF arrays (50/input)",
}

# The small net every baseline uses: SB3's default for PPO, A2C and DQN. SAC/TD3/DDPG default to 256x256 and
# 400x300; we give them 64x64 too, so the baselines compare algorithms rather than net sizes, and because a
# gradient step of the big nets costs 2-3x more on one core (SAC 256x256 ran at ~250 env steps/s here, 64x64 at
# ~500). SarsaAAC's approximators are far smaller (at most 20 hidden units), so 64x64 is no capacity handicap.
BASELINE_NET = [64, 64]

# algo: wrapper ("flatten" or "discretize"), n_envs, SB3 keyword arguments (JSON-able; see adapters.build_baseline).
# Every baseline steps its n_envs lanes as one batched DribbleVecEnv behind the wrapper's action space
# (adapters.WrappedDribbleVecEnv: the same actions and physics as DummyVecEnv over the wrapped DribbleEnv, without
# its ~100-400 us of Python per transition, which was half of A2C's and PPO's training time).
BASELINES: dict[str, dict[str, Any]] = {
    # On-policy: 8 DummyVecEnv envs. PPO keeps SB3's 2048 transitions per rollout (8 x 256) and takes minibatches
    # of 256 instead of 64 (4x fewer gradient steps per rollout; 64 made PPO the slowest on-policy cell).
    "PPO": {"wrapper": "flatten", "n_envs": 8, "kwargs": {"n_steps": 256, "batch_size": 256}},
    # A2C: SB3 defaults (n_steps=5, i.e. 40 transitions per update with 8 envs).
    "A2C": {"wrapper": "flatten", "n_envs": 8, "kwargs": {}},
    # Off-policy: SB3's defaults take one gradient step per env step with one env, ~250-500 env steps/s on this
    # machine (5-10 min per 150k-step cell, 30 such cells), too slow for the time box at SarsaAAC's step budget.
    # With 16 envs and train_freq=1 they take one gradient step per 16 transitions (a replay ratio of 1/16 instead
    # of 1). That is a handicap in sample efficiency we state in the report; it keeps the number of env steps equal
    # to SarsaAAC's.
    "SAC": {
        "wrapper": "flatten",
        "n_envs": 16,
        "kwargs": {"train_freq": 1, "gradient_steps": 1, "learning_starts": 1000, "policy_kwargs": {"net_arch": BASELINE_NET}},
    },
    # TD3 and DDPG have no exploration noise by default in SB3: Gaussian noise of 0.1 on the [-1, 1] actions
    # (the RL Zoo's usual choice).
    "TD3": {
        "wrapper": "flatten",
        "n_envs": 16,
        "kwargs": {"train_freq": 1, "gradient_steps": 1, "learning_starts": 1000, "policy_kwargs": {"net_arch": BASELINE_NET}},
        "action_noise_sigma": 0.1,
    },
    "DDPG": {
        "wrapper": "flatten",
        "n_envs": 16,
        "kwargs": {"train_freq": 1, "gradient_steps": 1, "learning_starts": 1000, "policy_kwargs": {"net_arch": BASELINE_NET}},
        "action_noise_sigma": 0.1,
    },
    # DQN over 80 discrete actions (5 values per parameter: dash directions -180/-90/0/90/180 deg, kick speeds
    # 0..max in quarters, ...). 8 envs, one gradient step per 8 transitions (SB3's default is one per 4 with one
    # env); learning_starts 1000 instead of 100 so the first updates see more than a few episodes.
    "DQN": {
        "wrapper": "discretize",
        "bins": 5,
        "n_envs": 8,
        "kwargs": {"train_freq": 1, "gradient_steps": 1, "learning_starts": 1000},
    },
}
ON_POLICY = ("PPO", "A2C")


@dataclass(frozen=True)
class Cell:
    """One training run (or, for ``algo="Reference"``, the no-learning references of an env)."""

    env_id: str
    algo: str  # "SarsaAAC", a key of BASELINES, or "Reference"
    config: str  # a key of SARSA_CONFIGS for SarsaAAC, the algo name in lower case for baselines
    seed: int = 0
    budget: int = 0  # env steps of training
    eval_every: int = 500  # training episodes between two evaluations of the learning curve
    eval_episodes: int = 100  # greedy episodes per curve point (EVAL_SEED)
    final_episodes: int = 1000  # greedy episodes of the final evaluation (FINAL_SEED)
    overrides: dict[str, Any] = field(default_factory=dict)  # extra algorithm kwargs (tests, experiments)

    @property
    def cell_id(self) -> str:
        env = ENV_SHORT.get(self.env_id, self.env_id)
        if self.algo == "Reference":  # its evaluation sizes differ between presets
            return f"{env}__reference__e{self.eval_episodes}-f{self.final_episodes}"
        return f"{env}__{self.algo}-{self.config}__s{self.seed}__{budget_label(self.budget)}"

    @property
    def family(self) -> str:
        if self.algo == "SarsaAAC":
            return SARSA_CONFIGS[self.config][0]
        return "reference" if self.algo == "Reference" else "baseline"

    @property
    def profile(self) -> str:
        return ENV_PROFILES[self.env_id]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Cell:
        return cls(**{k: data[k] for k in cls.__dataclass_fields__ if k in data})


def budget_label(steps: int) -> str:
    """``150000`` -> ``"150k"``; ``2500`` -> ``"2.5k"``."""
    if steps >= 1000 and steps % 100 == 0:
        return f"{steps / 1000:g}k"
    return str(steps)


def config_label(algo: str, config: str) -> str:
    return CONFIG_LABELS.get(config, algo) if algo == "SarsaAAC" else algo


# ---------------------------------------------------------------------------------------------------------------------
# Presets
# ---------------------------------------------------------------------------------------------------------------------

# quick: CI-sized. The paper env, 2 seeds, the paper's best SarsaAAC family and its MLP, one baseline; tiny budgets.
QUICK = {
    "env_ids": ("RoboCupDribblePaper-v0",),
    "seeds": (0, 1),
    "sarsa_configs": ("rbf10", "mlp2"),
    "baselines": ("PPO",),
    "sarsa_budget": 20_000,
    "baseline_budget": 20_000,
    "baseline_seeds": (0, 1),
    "eval_every": 500,
    "eval_episodes": 100,
    "final_episodes": 300,
}

# full: both envs, every SarsaAAC config with 5 seeds, the 6 baselines with 3 seeds, all at 150k env steps (SarsaAAC
# RbfPolicy reaches ~21-22 m there, ~9,000-11,000 episodes). Measured on the 2-core development machine with 2
# workers while other jobs kept its load average at 2-3: a SarsaAAC cell 15-45 s (90 cells); baseline cells at 150k
# steps PPO 130 s, SAC 197 s, the others ~100-150 s (36 cells); ~7,000 worker-seconds in all, i.e. ~60 min with 2
# workers under that load, ~40-45 min on two free cores. Evaluations every 1,000 episodes (~10 points for RBF
# arrays, more for configs and baselines with short episodes) cost under ~10% of a cell.
FULL = {
    "env_ids": ENV_IDS,
    "seeds": (0, 1, 2, 3, 4),
    "sarsa_configs": tuple(SARSA_CONFIGS),
    "baselines": tuple(BASELINES),
    "sarsa_budget": 150_000,
    "baseline_budget": 150_000,
    "baseline_seeds": (0, 1, 2),
    "eval_every": 1000,
    "eval_episodes": 100,
    "final_episodes": 1000,
}

PRESETS = {"quick": QUICK, "full": FULL}


def build_cells(preset: str | dict[str, Any]) -> list[Cell]:
    """All cells of a preset (a name of :data:`PRESETS` or a dict of the same shape), references first."""
    p = PRESETS[preset] if isinstance(preset, str) else preset
    common = {"eval_every": p["eval_every"], "eval_episodes": p["eval_episodes"], "final_episodes": p["final_episodes"]}
    cells = [
        Cell(env_id, "Reference", "references", final_episodes=p["final_episodes"], eval_episodes=p["eval_episodes"])
        for env_id in p["env_ids"]
    ]
    for env_id in p["env_ids"]:
        for config in p["sarsa_configs"]:
            cells += [Cell(env_id, "SarsaAAC", config, seed, p["sarsa_budget"], **common) for seed in p["seeds"]]
        for algo in p["baselines"]:
            cells += [Cell(env_id, algo, algo.lower(), seed, p["baseline_budget"], **common) for seed in p["baseline_seeds"]]
    return cells


def select(cells: list[Cell], patterns: str | None) -> list[Cell]:
    """Cells whose id matches one of the comma-separated glob ``patterns`` (a pattern without ``*?[`` is a substring)."""
    if not patterns:
        return cells
    globs = [p if any(c in p for c in "*?[") else f"*{p}*" for p in (s.strip() for s in patterns.split(",")) if p]
    return [c for c in cells if any(fnmatch.fnmatchcase(c.cell_id, g) for g in globs)]
