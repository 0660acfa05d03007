"""The benchmark grid: cells = env id x algorithm x config x seed x budget.

Every number here is our choice; the reasons are next to them. A cell is plain data (:class:`Cell`), so it can be
sent to a worker process and written into its result file as is.

Eight domains (:mod:`benchmarks.domains`; the full preset runs seven, Half Field Offense has its own): the dribbling
envs of both server eras, Platform-v0 (PyPI ``hybrid-platform``, Masson et al.'s Platform) and the ``hybrid_domains``
Goal-v0, Moving-v0, Sliding-v0 and CatchPoint-v0, each with its own budget. What a preset costs: ``python -m
benchmarks.run --preset P --estimate`` (:mod:`benchmarks.cost`, from :data:`STEPS_PER_SECOND` and
:data:`ENV_STEP_SECONDS`).

SarsaAAC configs (:data:`SARSA_CONFIGS`): ``TilePolicy`` and the recommended ``DeepPolicy`` with their defaults, and
the paper's three families (Uc-Cetina 2013, Figs. 5-7), all other hyperparameters at the SarsaAAC defaults (16 lanes):

* ``tile``: ``TilePolicy`` (hashed tilings over the inputs and their pairs; the fastest per env step);
* ``deep``: ``DeepPolicy`` (layer-normalised 2x64 nets with ObGD steps; the recommended policy, chosen by the report's
  rule, :func:`benchmarks.report_budgets.recommended_policy`) with SarsaAAC's one-step updates
  (``trace_lambda=0``): as good as the streaming paper's 0.8 or better, and cheaper (docs/sarsa_aac_results.md, DeepPolicy);
* ``mlp2/10/20``: ``MlpPolicy`` with 2, 10, 20 hidden tanh units per approximator;
* ``rbfmlp2/10/20``: ``RbfMlpPolicy``, a filter layer of 10 Gaussian RBFs per input, then 2, 10, 20 hidden units;
* ``rbf10/30/50``: ``RbfPolicy``, arrays of 10, 30, 50 Gaussian RBFs per input, linear output.

Parameterized-action peers (:data:`PEERS`): P-DQN, MP-DQN and HybridPPO with the settings of ``hyperparams/<algo>.yml``
for the env (an env without an entry: see :data:`PEERS`).
SB3 baselines (:data:`BASELINES`) through :class:`~sb3_aac.FlattenParameterizedAction` (PPO, A2C, SAC, TD3, DDPG:
one score per action type then every parameter) or :class:`~sb3_aac.DiscretizeParameterizedAction` (DQN: 5 values
per parameter). **Fairness rule**: every off-policy learner (SAC, TD3, DDPG, DQN, P-DQN, MP-DQN) takes one gradient
step per transition (SB3's default for SAC/TD3/DDPG with one env; ``n_envs`` lanes and ``gradient_steps=n_envs``), and
otherwise keeps its documented defaults (SB3's, or the reference MP-DQN code's); none is tuned for these tasks, and
neither is SarsaAAC (its defaults were chosen on several tasks, see its docstring). The tuned twins
(``<config>-tuned``) of an env's ``tuned`` learners run the best settings of an equal-size study each
(:mod:`benchmarks.tuning`); which learners are tuned where, and why: :data:`FULL`.
"""

from __future__ import annotations

import fnmatch
from dataclasses import asdict, dataclass, field
from typing import Any

from robocup_dribble import ENV_PROFILES

DRIBBLE_IDS = ("RoboCupDribblePaper-v0", "RoboCupDribble-v0")  # the paper's era first
PLATFORM_ID = "Platform-v0"
HYBRID_IDS = ("Goal-v0", "Moving-v0", "Sliding-v0", "CatchPoint-v0")  # envs/hybrid_domains (benchmarks.domains)
HFO_ID = "HalfFieldOffense-v0"  # envs/half_field_offense
ENV_IDS = (*DRIBBLE_IDS, PLATFORM_ID, *HYBRID_IDS, HFO_ID)
ENV_SHORT = {
    "RoboCupDribblePaper-v0": "paper",
    "RoboCupDribble-v0": "v19",
    PLATFORM_ID: "platform",
    **{env_id: env_id.split("-")[0].lower() for env_id in HYBRID_IDS},
    HFO_ID: "hfo",
}

# Evaluation seeds: with common random numbers every policy meets the same episodes of a set (episode slot j of a
# set plays its own seeded player, start and noise, or Platform's own seeded episode), and none of them is shared with
# training (training seeds are small integers) or with another set.
EVAL_SEED = 10_000  # the learning curves: `eval_episodes` greedy episodes every `eval_every` training episodes
FINAL_SEED = 20_000  # the final evaluation of a trained model (`final_episodes` greedy episodes)
RELIABILITY_SEED = 30_000  # the reliability test (10,000 fresh players, one episode each)

SARSA_N_ENVS = 16  # lanes for SarsaAAC (the quick start's setting)

# The paper's update for its configurations, so that they reproduce the paper's figures: without the replay the MLP
# families take by default (SarsaAAC's replay_ratio), and every rate at PAPER_RATE, the per-sample rate their figures
# were measured with (MlpPolicy's default is 0.05).
PAPER_RATE = 0.1
PAPER_UPDATE: dict[str, Any] = {
    "replay_ratio": 0,
    **dict.fromkeys(("learning_rate", "q_learning_rate", "param_learning_rate"), PAPER_RATE),
}
# name: (family, policy, policy_kwargs, SarsaAAC keyword arguments beyond its defaults)
SARSA_CONFIGS: dict[str, tuple[str, str, dict[str, Any], dict[str, Any]]] = {
    "tile": ("Tiles", "TilePolicy", {}, {}),
    "deep": ("Deep", "DeepPolicy", {}, {}),
    "mlp2": ("MLP", "MlpPolicy", {"hidden_units": 2}, PAPER_UPDATE),
    "mlp10": ("MLP", "MlpPolicy", {"hidden_units": 10}, PAPER_UPDATE),
    "mlp20": ("MLP", "MlpPolicy", {"hidden_units": 20}, PAPER_UPDATE),
    "rbfmlp2": ("MLP+RBF", "RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 2}, PAPER_UPDATE),
    "rbfmlp10": ("MLP+RBF", "RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 10}, PAPER_UPDATE),
    "rbfmlp20": ("MLP+RBF", "RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 20}, PAPER_UPDATE),
    "rbf10": ("RBF", "RbfPolicy", {"n_rbf": 10}, {}),
    "rbf30": ("RBF", "RbfPolicy", {"n_rbf": 30}, {}),
    "rbf50": ("RBF", "RbfPolicy", {"n_rbf": 50}, {}),
}
FAMILIES = ("Tiles", "Deep", "MLP", "MLP+RBF", "RBF")  # SarsaAAC's
PAPER_FAMILIES = ("MLP", "MLP+RBF", "RBF")
CONFIG_LABELS = {
    "tile": "TilePolicy",
    "deep": "DeepPolicy (recommended)",
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

# The off-policy learners' lanes: one gradient step per transition means gradient_steps = n_envs with train_freq=1.
OFF_POLICY_ENVS = 4
REPLAY_RATIO_ONE = {"train_freq": 1, "gradient_steps": OFF_POLICY_ENVS}

# The parameterized peers: hyperparams/<yml>.yml's entry for the env, then n_envs and "kwargs". P-DQN / MP-DQN take
# one gradient step per transition by the fairness rule (the reference MP-DQN code also takes one update per env
# step). An env without an entry in the yml gets the entry of env "fallback" (None: the algorithm's constructor
# defaults; the P-DQN / MP-DQN entries carry their env's initial parameters, so they do not carry over).
# HybridPPO's entries are one rule (hppo.yml: the PPO baseline's rollout shape, 8 lanes x 256 steps, minibatches of
# 256, and a type-entropy bonus of 0.01), so its Platform entry is the rule for the envs it does not list. On an
# episodic domain with its own entry a peer trains on that entry's env_wrapper chain, as rl-zoo3 does (the same
# observations as the domain's evaluation env; on Goal the reference's reward scale of 1/50), and on the ids of
# "reference_start" it starts its parameter actor at the reference MP-DQN code's function (benchmarks.models):
# with the yml's constant start MP-DQN never scored on Goal (P(goal) 0.0 after 60k steps, 0.684 with the reference's;
# docs/pdqn.md), and P-DQN scored in one of 7 seeds (0.0-0.15; the reference's run_goal_pdqn.py starts both so).
PEERS: dict[str, dict[str, Any]] = {
    "PDQN": {
        "yml": "pdqn",
        "n_envs": OFF_POLICY_ENVS,
        "kwargs": dict(REPLAY_RATIO_ONE),
        "fallback": None,
        "reference_start": ("Goal-v0",),
    },
    "MPDQN": {
        "yml": "mpdqn",
        "n_envs": OFF_POLICY_ENVS,
        "kwargs": dict(REPLAY_RATIO_ONE),
        "fallback": None,
        "reference_start": ("Goal-v0",),
    },
    "HybridPPO": {"yml": "hppo", "n_envs": 8, "kwargs": {}, "fallback": PLATFORM_ID},
}
ON_POLICY_PEERS = ("HybridPPO",)

# The small net every baseline uses: SB3's default for PPO, A2C and DQN. SAC/TD3/DDPG default to 256x256 and
# 400x300; we give them 64x64 too, so the baselines compare algorithms rather than net sizes, and because a
# gradient step of the big nets costs 2-3x more on one core. SarsaAAC's approximators are far smaller, and P-DQN's
# nets are 64x64 (dribbling) or 128 (Platform, the reference code's), so 64x64 is no capacity handicap.
BASELINE_NET = [64, 64]

# algo: wrapper ("flatten" or "discretize"), n_envs, SB3 keyword arguments (JSON-able; see adapters.build_baseline).
BASELINES: dict[str, dict[str, Any]] = {
    # On-policy: 8 lanes. PPO keeps SB3's 2048 transitions per rollout (8 x 256) and takes minibatches of 256 instead
    # of 64 (4x fewer gradient steps per rollout; 64 made PPO the slowest on-policy cell).
    "PPO": {"wrapper": "flatten", "n_envs": 8, "kwargs": {"n_steps": 256, "batch_size": 256}},
    # A2C: SB3 defaults (n_steps=5, i.e. 40 transitions per update with 8 envs).
    "A2C": {"wrapper": "flatten", "n_envs": 8, "kwargs": {}},
    # Off-policy: one gradient step per transition (SB3's default ratio for SAC/TD3/DDPG), SB3's learning_starts.
    "SAC": {
        "wrapper": "flatten",
        "n_envs": OFF_POLICY_ENVS,
        "kwargs": {**REPLAY_RATIO_ONE, "policy_kwargs": {"net_arch": BASELINE_NET}},
    },
    # TD3 and DDPG have no exploration noise by default in SB3: Gaussian noise of 0.1 on the [-1, 1] actions
    # (the RL Zoo's usual choice).
    "TD3": {
        "wrapper": "flatten",
        "n_envs": OFF_POLICY_ENVS,
        "kwargs": {**REPLAY_RATIO_ONE, "policy_kwargs": {"net_arch": BASELINE_NET}},
        "action_noise_sigma": 0.1,
    },
    "DDPG": {
        "wrapper": "flatten",
        "n_envs": OFF_POLICY_ENVS,
        "kwargs": {**REPLAY_RATIO_ONE, "policy_kwargs": {"net_arch": BASELINE_NET}},
        "action_noise_sigma": 0.1,
    },
    # DQN over the grid of 5 values per parameter; one gradient step per transition (SB3's default is one per 4).
    "DQN": {"wrapper": "discretize", "bins": 5, "n_envs": OFF_POLICY_ENVS, "kwargs": dict(REPLAY_RATIO_ONE)},
}
ON_POLICY = ("PPO", "A2C")

# Env steps per second of training on one core, per algorithm (a "<algo>-<config>" key for a config that differs),
# at the settings above on the dribbling env, whose lanes step in compiled code: the median of env_steps /
# train_wall_s over the finished cells of benchmarks/results (50k steps, load 2-3 on two cores; SAC's, DDPG's and
# P-DQN's paper-env cells ran three processes on two cores, so their medians 74, 145 and 209 times 1.5, P-DQN's
# agreeing with the 350 it had); DeepPolicy and HybridPPO (no such cells) as their same-run ratio to TilePolicy and
# PPO times those figures (docs/benchmarks.md, "Cost"). P-DQN's and MP-DQN's, measured as 350 and 250 before their
# explicit-gradient training step, times that step's same-run speed-up (``python -m benchmarks.speed.versus 20f1865``:
# 1.23x and 1.27x before it, 1.69x and 1.76x after). HybridPPO's since its numpy rollouts: 1.54x PPO's rate on the
# paper env's lanes (``python -m benchmarks.speed.training hppo``, 2026-12-08; 0.82x before). With ENV_STEP_SECONDS
# they give a learner's rate on each env (training_rate): the local pool starts the longest cells first, a wall-clock
# cell's schedule horizon is WALL_CLOCK_HEADROOM times what its learner steps in its seconds, and benchmarks.cost
# estimates a preset's core-hours.
STEPS_PER_SECOND = {
    "SarsaAAC": 30_000,
    "SarsaAAC-deep": 7_000,
    "PPO": 9_300,
    "A2C": 11_700,
    "SAC": 110,
    "TD3": 570,
    "DDPG": 215,
    "DQN": 1_300,
    "PDQN": 480,
    "MPDQN": 350,
    "HybridPPO": 14_300,
}
# Seconds of one env step in a training VecEnv, the learner's work excluded: Platform's from its finished cells
# (1 / rate there - 1 / rate on dribbling, for SarsaAAC, PPO and TD3: 2.5-3.8 ms), the hybrid domains' from the CPU
# time of random actions through benchmarks.domains.train_env (8 lanes), which agrees with SarsaAAC's TilePolicy on
# Goal and Moving against on dribbling in the same run; the dribbling lanes step in compiled code.
ENV_STEP_SECONDS = {
    "RoboCupDribblePaper-v0": 1e-6,
    "RoboCupDribble-v0": 1e-6,
    PLATFORM_ID: 3e-3,
    "Goal-v0": 6e-4,
    "Moving-v0": 4e-5,
    "Sliding-v0": 4e-5,
    "CatchPoint-v0": 6e-5,
    HFO_ID: 1.5e-5,  # the single env through SB3's DummyVecEnv (the wrapped baselines); its vector env ~1e-6
}

# A wall-clock cell's env-step horizon is this many times what its learner usually steps in its seconds
# (training_rate), so that the clock, not the horizon, ends its training on a quiet machine too: at 1.0 the measured
# rates of TilePolicy, DeepPolicy and MP-DQN (38k, 11.7k and 400 env steps/s on the paper env's 120 s cells, above
# STEPS_PER_SECOND's 30k, 7k and then 250) ended them by the horizon after 75-97 s, and on Half Field Offense MP-DQN and
# P-DQN after 166-207 s of 300. The schedules run over the horizon, so they are at least half done at the stop.
WALL_CLOCK_HEADROOM = 2.0

TUNED_SUFFIX = "-tuned"  # a config "<config>-tuned" runs <config> with the settings of its tuning study


def steps_per_second(algo: str, config: str) -> float:
    """A learner's :data:`STEPS_PER_SECOND`: its ``"<algo>-<config>"`` entry if it has one, else its algorithm's."""
    key = f"{algo}-{base_config(config)}"
    if key in STEPS_PER_SECOND:
        return float(STEPS_PER_SECOND[key])
    if algo not in STEPS_PER_SECOND:
        raise ValueError(f"no training rate for {algo} ({config}); known: {sorted(STEPS_PER_SECOND)}")
    return float(STEPS_PER_SECOND[algo])


def training_rate(env_id: str, algo: str, config: str) -> float:
    """Env steps per second of training on one core: the learner's :func:`steps_per_second` slowed by the env's own
    step cost (:data:`ENV_STEP_SECONDS`)."""
    return 1.0 / (1.0 / steps_per_second(algo, config) + ENV_STEP_SECONDS.get(env_id, 0.0))


def base_config(config: str) -> str:
    """The config a tuned config was tuned from (``"td3-tuned"`` -> ``"td3"``); other configs are their own."""
    return config.removesuffix(TUNED_SUFFIX)


def is_tuned(config: str) -> bool:
    return config.endswith(TUNED_SUFFIX)


@dataclass(frozen=True)
class Cell:
    """One training run (or, for ``algo="Reference"``, the no-learning references of an env)."""

    env_id: str
    algo: str  # "SarsaAAC", a key of BASELINES, or "Reference"
    config: str  # a key of SARSA_CONFIGS for SarsaAAC, the algo name in lower case for baselines; +TUNED_SUFFIX
    seed: int = 0
    budget: int = 0  # env steps of training (a wall-clock cell: at most, its schedules' horizon; the clock ends it)
    eval_every: int = 500  # training episodes between two evaluations of the learning curve
    eval_episodes: int = 100  # greedy episodes per curve point (EVAL_SEED)
    final_episodes: int = 1000  # greedy episodes of the final evaluation (FINAL_SEED)
    # extra algorithm kwargs (tests, experiments); a tuned config's are {"tuned_params": the best trial's parameters}
    overrides: dict[str, Any] = field(default_factory=dict)
    seconds: int = 0  # > 0: a wall-clock cell, training stops after this many seconds of training (evaluations excluded)

    @property
    def cell_id(self) -> str:
        env = ENV_SHORT.get(self.env_id, self.env_id)
        if self.algo == "Reference":  # its evaluation sizes differ between presets
            return f"{env}__reference__e{self.eval_episodes}-f{self.final_episodes}"
        budget = f"{self.seconds}s" if self.seconds else budget_label(self.budget)
        return f"{env}__{self.algo}-{self.config}__s{self.seed}__{budget}"

    @property
    def family(self) -> str:
        if self.algo == "SarsaAAC":
            return SARSA_CONFIGS[base_config(self.config)][0]
        if self.algo in PEERS:
            return "peer"
        return "reference" if self.algo == "Reference" else "baseline"

    @property
    def profile(self) -> str | None:
        """The dribbling env's server profile (None for other domains)."""
        return ENV_PROFILES.get(self.env_id)

    def to_dict(self) -> dict[str, Any]:
        """The fields as a dict; ``seconds`` only for a wall-clock cell (so env-step cells read as they always did)."""
        data = asdict(self)
        if not self.seconds:
            del data["seconds"]
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Cell:
        return cls(**{k: data[k] for k in cls.__dataclass_fields__ if k in data})


def budget_label(steps: int) -> str:
    """``150000`` -> ``"150k"``; ``2500`` -> ``"2.5k"``."""
    if steps >= 1000 and steps % 100 == 0:
        return f"{steps / 1000:g}k"
    return str(steps)


def config_label(algo: str, config: str) -> str:
    label = CONFIG_LABELS.get(base_config(config), algo) if algo == "SarsaAAC" else algo
    return f"{label}, tuned" if is_tuned(config) else label


# ---------------------------------------------------------------------------------------------------------------------
# Presets
# ---------------------------------------------------------------------------------------------------------------------

# A preset: per env id, its budget (env steps, the same for every algorithm of the env), and runs: (algo, config, seeds).
# The evaluation sizes are the preset's, unless an env's entry has its own.

# quick: CI-sized. The paper env, 2 seeds, SarsaAAC's fastest policy (TilePolicy), the paper's MLP, one baseline.
QUICK: dict[str, Any] = {
    "envs": {
        "RoboCupDribblePaper-v0": {
            "budget": 20_000,
            "runs": [("SarsaAAC", "tile", (0, 1)), ("SarsaAAC", "mlp2", (0, 1)), ("PPO", "ppo", (0, 1))],
        }
    },
    "eval_every": 500,
    "eval_episodes": 100,
    "final_episodes": 300,
    # CI-sized studies (benchmarks.tuning): 3 trials of 5,000 env steps, one tuning seed, 2 pruning evaluations.
    "tuning": {
        "learners": [("SarsaAAC", "tile"), ("SarsaAAC", "mlp2"), ("PPO", "ppo")],
        "trials": 3,
        "seeds": 1,
        "env_steps": 5_000,
        "evaluations": 2,
        "eval_episodes": 20,
    },
}

HEADLINE_SEEDS = tuple(range(10))  # a headline pair's learners: >= 10 seeds (benchmarks.significance)
PAPER_SEEDS = tuple(range(5))  # the paper's configs, the long and the wall-clock budgets, and costly default rows
FEW_SEEDS = tuple(range(3))  # every other learner

# full: the regeneration, sized to about 28 core-hours on the development machine (33.7 measured by 2026-12-08;
# ``python -m benchmarks.run --preset full --estimate`` prints each stage's estimate). Where the compute goes
# decides its shape: the torch learners that take one gradient step per transition train at 110-600 env steps/s on
# one core (``python -m benchmarks.speed.training pdqn``: MP-DQN 2.5-3 ms a step, as TD3), many times slower than
# SarsaAAC (the report's "Training cost" line), so 10 seeds of them at a 50k budget cost what all of SarsaAAC's cells
# together cost. Hence, per env:
#
# * ``runs``: the headline learners with HEADLINE_SEEDS (SarsaAAC's TilePolicy and DeepPolicy on every env, so the
#   recommended policy is chosen by tests on 10 seeds), the others with FEW_SEEDS (the defaults of a learner whose
#   tuned twin is the headline row with PAPER_SEEDS where they are costly, with HEADLINE_SEEDS where they are cheap).
# * ``tuned``: the learners with a tuning study (benchmarks.tuning: FULL_TUNING's size, ``tune_steps`` env steps a
#   trial) and a tuned twin with HEADLINE_SEEDS: SarsaAAC's TilePolicy and DeepPolicy everywhere but on HFO (their
#   defaults were chosen on a few of our tasks), HybridPPO wherever it runs and PPO wherever it runs but on HFO (their
#   defaults are their libraries'), MP-DQN on the paper env, Platform, Goal and CatchPoint and P-DQN on Platform, Goal
#   and CatchPoint (CatchPoint's best parameterized peers with their defaults; their rows without a study run the
#   reference MP-DQN code's published settings, or on CatchPoint the constructor's), TD3 on both dribbling envs. Not
#   tuned: MP-DQN and P-DQN on Moving and Sliding, which run their constructor defaults (no published settings there;
#   their rows came last, with no time left for studies); TD3 on CatchPoint, Platform and Goal, which
#   run their documented defaults (studies that could not rank their trials: on CatchPoint the one tuning seed,
#   TUNE_SEED, scores 0 with TD3's defaults after 5k-15k env steps where seed 0 scores 0.3, and the first five trials
#   scored 0 at every evaluation; on Platform the first four trials scored 0.283 at every evaluation; on Goal the first
#   seven trials, and the eighth at its first four, scored 0 at every evaluation), TD3 on Moving and Sliding (its rows
#   came last, with no time left for studies), and on HFO all but HybridPPO (the parameterized peer of its verdict),
#   where a study of 20 trials of HFO_BUDGET // 2 env steps and a tuned twin of 10 seeds cost about 2 core-hours a
#   learner (DeepPolicy's defaults already score P(goal) 0.994 there, mean of 10 seeds).
# * ``long``: the paper's episode counts (LONG_BUDGET), for the configs the paper's claims are about; ``wall_clock``:
#   equal seconds for the paper env's headline learners and HFO's torch learners.
#
# Sliding-v0 (Moving's variant with inertia, no published figure) runs as Moving-v0 does. Budgets: 50k env steps on
# dribbling (~3,500 SarsaAAC episodes), 20k on Platform; Goal-v0 60k (the reference MP-DQN code's ~20,000 episodes,
# after which Bester et al. report P(goal) 0.789; HyAR-TD3's figure is TD3-based); CatchPoint-v0 50k (~3,000
# episodes of at most 25 steps); Moving-v0 and Sliding-v0 100k (~1,000 episodes of at most 200 steps; H-PPO's ~1.7 on
# Moving is after 3M).
WALL_CLOCK_SECONDS = 120  # about the time TD3 needs for the 50k-step budget, and 70x SarsaAAC's (TilePolicy)
WALL_CLOCK_SEEDS = PAPER_SEEDS
# The long budget of the dribbling envs, sized for the paper's episode counts: on the paper env (seed 0, 16 lanes)
# SarsaAAC's TilePolicy passed 10,000 episodes at 99k env steps and 20,000 at 354k; MlpPolicy (2 hidden) 10,000 at
# 32k and 40,000 at 471k. 500k env steps therefore test the 10,000-episode claims and the 40,000-episode one.
LONG_BUDGET = 500_000
LONG_SEEDS = PAPER_SEEDS
# Tuning (benchmarks.tuning): one study per tuned learner and env, all the same size: 20 trials x the env's
# ``tune_steps`` x 1 tuning seed, the trial pruned by the median rule on 5 greedy evaluations of 50 episodes.
FULL_TUNING: dict[str, Any] = {
    "learners": None,
    "trials": 20,
    "seeds": 1,
    "env_steps": None,
    "evaluations": 5,
    "eval_episodes": 50,
}
_PAPER_CONFIGS = ("rbf50", "rbfmlp2", "mlp2")


def _runs(seeds: tuple[int, ...], *learners: str) -> list[tuple[str, str, tuple[int, ...]]]:
    """``("SarsaAAC-tile", "TD3")`` -> runs of those learners ("<algo>-<config>" or an algo, config its lower case)."""
    pairs = [name.split("-", 1) if "-" in name else (name, name.lower()) for name in learners]
    return [(algo, config, seeds) for algo, config in pairs]


def _learners(*names: str) -> list[tuple[str, str]]:
    return [(algo, config) for algo, config, _ in _runs((), *names)]


def _tuned(learners: list[tuple[str, str]], seeds: tuple[int, ...]) -> list[tuple[str, str, tuple[int, ...]]]:
    return [(algo, config + TUNED_SUFFIX, seeds) for algo, config in learners]


def _env(
    budget: int,
    runs: list[tuple[str, str, tuple[int, ...]]],
    tuned: list[tuple[str, str]],
    tune_steps: int,
    **views: Any,
) -> dict[str, Any]:
    """An env's entry of :data:`FULL`: its runs, then the tuned twins of ``tuned`` (HEADLINE_SEEDS), and ``views``
    (``long``, ``wall_clock``)."""
    entry = {"budget": budget, "runs": [*runs, *_tuned(tuned, HEADLINE_SEEDS)], "tuned": tuned, "tune_steps": tune_steps}
    return entry | views


# The episodic domains' evaluations cost 10-100x a dribbling episode's (Moving's run 200 steps of single-observation
# decisions), and seeds, not episodes, dominate a verdict's variance: half the curve and final episodes there.
_EPISODIC_SIZES = {"eval_episodes": 50, "final_episodes": 500}
_SARSA_HEADLINE = ("SarsaAAC-tile", "SarsaAAC-deep")  # tuned on every env
_PAPER_HEADLINE = (*_SARSA_HEADLINE, "MPDQN", "TD3")
_ON_POLICY = ("HybridPPO", "PPO")  # tuned wherever they run (on HFO HybridPPO only)
# Half Field Offense 1v0 (docs/half_field_offense.md): SarsaAAC's DeepPolicy (TilePolicy's tiles over 59 inputs learn
# too slowly there) against the hybrid peer and the best SB3 baseline at HFO_BUDGET env steps (~15,000 trials; ~90 s
# of DeepPolicy's training on one core, about 5.5 minutes of HybridPPO's or PPO's), and every torch learner given
# HFO_SECONDS of training, the wall-clock view of "within 10 minutes of one core" at the size one machine affords
# (in those seconds MP-DQN stepped ~135k env steps, ~1,300 trials: 7 % of the 20,000 episodes of its published figure).
# The peers run their constructor defaults (no hyperparams entry for HFO); HybridPPO alone is tuned there (``tuned``).
HFO_BUDGET = 1_500_000
HFO_SECONDS = 300
_HFO_VIEWS: dict[str, Any] = {
    "wall_clock": {"seconds": HFO_SECONDS, "runs": _runs(PAPER_SEEDS, "MPDQN", "PDQN", "HybridPPO", "PPO", "TD3")},
    "eval_every": 2500,
    "eval_episodes": 50,
}
FULL: dict[str, Any] = {
    "envs": {
        "RoboCupDribblePaper-v0": _env(
            50_000,
            [
                # HybridPPO's and PPO's defaults (cheap) with 10 seeds, MP-DQN's and TD3's (costly) with the 5 seeds a
                # tuned-against-default verdict needs
                *_runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "HybridPPO", "PPO"),
                *_runs(PAPER_SEEDS, "MPDQN", "TD3", *(f"SarsaAAC-{c}" for c in _PAPER_CONFIGS)),
                *_runs(FEW_SEEDS, "A2C", "DQN", "PDQN", "SAC", "DDPG"),
            ],
            _learners(*_PAPER_HEADLINE, *_ON_POLICY),
            20_000,
            long={
                "budget": LONG_BUDGET,
                "runs": _runs(LONG_SEEDS, "SarsaAAC-tile", *(f"SarsaAAC-{c}" for c in _PAPER_CONFIGS)),
            },
            wall_clock={"seconds": WALL_CLOCK_SECONDS, "runs": _runs(WALL_CLOCK_SEEDS, *_PAPER_HEADLINE)},
        ),
        "RoboCupDribble-v0": _env(
            50_000,
            [
                *_runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "PPO", "TD3", "HybridPPO"),
            ],
            _learners(*_SARSA_HEADLINE, *_ON_POLICY, "TD3"),
            20_000,
            long={"budget": LONG_BUDGET, "runs": _runs(LONG_SEEDS, "SarsaAAC-tile")},
        ),
        PLATFORM_ID: _env(
            20_000,
            [
                # MP-DQN and P-DQN: the reference settings (published 0.987 and 0.93), and tuned. TD3: its defaults
                *_runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "HybridPPO", "PPO", "MPDQN", "PDQN", "TD3"),
            ],
            _learners(*_SARSA_HEADLINE, "MPDQN", "PDQN", *_ON_POLICY),
            10_000,
            **_EPISODIC_SIZES,
        ),
        "Goal-v0": _env(
            60_000,
            [
                # MP-DQN and P-DQN: the reference settings (MP-DQN published P(goal) 0.789). TD3: its defaults
                *_runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "HybridPPO", "MPDQN", "PDQN", "TD3"),
            ],
            _learners(*_SARSA_HEADLINE, "HybridPPO", "MPDQN", "PDQN"),
            30_000,
            **_EPISODIC_SIZES,
        ),
        "CatchPoint-v0": _env(
            50_000,
            # MP-DQN and P-DQN: their constructor defaults (no published settings for this domain). TD3: its defaults
            _runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "TD3", "MPDQN", "PDQN"),
            _learners(*_SARSA_HEADLINE, "MPDQN", "PDQN"),
            25_000,
            **_EPISODIC_SIZES,
        ),
        "Moving-v0": _env(
            100_000,
            # MP-DQN and P-DQN: their constructor defaults (no published settings for this domain)
            _runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "HybridPPO", "PPO", "TD3", "MPDQN", "PDQN"),
            _learners(*_SARSA_HEADLINE, *_ON_POLICY),
            50_000,
            **_EPISODIC_SIZES,
        ),
        "Sliding-v0": _env(
            100_000,
            # MP-DQN and P-DQN: their constructor defaults, as on Moving-v0
            _runs(HEADLINE_SEEDS, "SarsaAAC-tile", "SarsaAAC-deep", "HybridPPO", "PPO", "TD3", "MPDQN", "PDQN"),
            _learners(*_SARSA_HEADLINE, *_ON_POLICY),
            50_000,
            **_EPISODIC_SIZES,
        ),
        HFO_ID: _env(
            HFO_BUDGET,
            _runs(HEADLINE_SEEDS, "SarsaAAC-deep", "HybridPPO", "PPO"),
            _learners("HybridPPO"),
            HFO_BUDGET // 2,
            **_HFO_VIEWS,
        ),
    },
    "tuning": FULL_TUNING,
    "eval_every": 500,
    "eval_episodes": 100,
    "final_episodes": 1000,
}

# The studies of one algorithm family, each a preset of the same runner (its report is the grid's, from its cells):
# P-DQN and MP-DQN with the reference settings (hyperparams/pdqn.yml, mpdqn.yml; docs/pdqn.md), and HybridPPO against
# PPO through FlattenParameterizedAction at equal env steps and lanes (hyperparams/hppo.yml; docs/hppo.md).
PDQN_STUDY: dict[str, Any] = {
    "envs": {
        "RoboCupDribblePaper-v0": {
            "budget": 150_000,
            "runs": _runs(FEW_SEEDS, "PDQN", "MPDQN"),
            "long": {"budget": 1_000_000, "runs": _runs(FEW_SEEDS, "MPDQN")},
        },
        PLATFORM_ID: {"budget": 100_000, "runs": _runs(FEW_SEEDS, "PDQN", "MPDQN"), **_EPISODIC_SIZES},
        "Goal-v0": {"budget": 100_000, "runs": _runs(FEW_SEEDS, "PDQN", "MPDQN"), **_EPISODIC_SIZES},
    },
    "eval_every": 500,
    "eval_episodes": 100,
    "final_episodes": 1000,
}
HPPO_STUDY: dict[str, Any] = {
    "envs": {
        "RoboCupDribblePaper-v0": {
            "budget": 50_000,
            "runs": _runs(PAPER_SEEDS, "HybridPPO", "PPO"),
            "long": {"budget": 1_000_000, "runs": _runs(PAPER_SEEDS, "HybridPPO", "PPO")},
        },
        "RoboCupDribble-v0": {"budget": 50_000, "runs": _runs(PAPER_SEEDS, "HybridPPO", "PPO")},
        PLATFORM_ID: {"budget": 100_000, "runs": _runs(PAPER_SEEDS, "HybridPPO", "PPO"), **_EPISODIC_SIZES},
    },
    "eval_every": 500,
    "eval_episodes": 100,
    "final_episodes": 1000,
}

# Half Field Offense 1v0 alone: the full preset's HFO entry at 5 seeds, without the 1.5M-step peers (its cost:
# ``python -m benchmarks.run --preset hfo --estimate``).
HFO_STUDY: dict[str, Any] = {
    "envs": {HFO_ID: {"budget": HFO_BUDGET, "runs": _runs(PAPER_SEEDS, "SarsaAAC-deep"), **_HFO_VIEWS}},
    "eval_every": 500,
    "eval_episodes": 100,
    "final_episodes": 1000,
}

PRESETS = {"quick": QUICK, "full": FULL, "pdqn": PDQN_STUDY, "hppo": HPPO_STUDY, "hfo": HFO_STUDY}


def build_cells(preset: str | dict[str, Any]) -> list[Cell]:
    """All cells of a preset (a name of :data:`PRESETS` or a dict of the same shape), references first; an env's
    ``eval_every``, ``eval_episodes`` and ``final_episodes`` are its entry's where it has them, else the preset's."""
    p = PRESETS[preset] if isinstance(preset, str) else preset

    def sizes(spec: dict[str, Any]) -> dict[str, int]:  # an env's evaluation sizes: its own, else the preset's
        return {key: spec.get(key, p[key]) for key in ("eval_every", "eval_episodes", "final_episodes")}

    cells = [
        Cell(
            env_id,
            "Reference",
            "references",
            final_episodes=sizes(spec)["final_episodes"],
            eval_episodes=sizes(spec)["eval_episodes"],
        )
        for env_id, spec in p["envs"].items()
        if env_id in ENV_PROFILES  # Platform's references are published figures (benchmarks.domains)
    ]
    for env_id, spec in p["envs"].items():
        common = sizes(spec)
        for algo, config, seeds in spec["runs"]:
            cells += [Cell(env_id, algo, config, seed, spec["budget"], **common) for seed in seeds]
        if "long" in spec:  # a longer env-step budget for some learners
            for algo, config, seeds in spec["long"]["runs"]:
                cells += [Cell(env_id, algo, config, seed, spec["long"]["budget"], **common) for seed in seeds]
        if "wall_clock" in spec:  # equal seconds of training; the horizon is more than the learner steps in them
            seconds = spec["wall_clock"]["seconds"]
            for algo, config, seeds in spec["wall_clock"]["runs"]:
                horizon = round(WALL_CLOCK_HEADROOM * training_rate(env_id, algo, config) * seconds)
                cells += [Cell(env_id, algo, config, seed, horizon, **common, seconds=seconds) for seed in seeds]
    return cells


def tuning_spec(preset: str | dict[str, Any]) -> dict[str, Any]:
    """A preset's tuning budget (benchmarks.tuning): ``learners`` per env id (None in the preset: each env's
    ``tuned`` learners, or where it lists none, the runs with :data:`HEADLINE_SEEDS`), ``trials``, ``seeds``,
    ``env_steps`` per env id (None in the preset: the env's ``tune_steps``, else its budget), ``evaluations`` and
    ``eval_episodes``."""
    p = PRESETS[preset] if isinstance(preset, str) else preset
    if "tuning" not in p:
        raise ValueError("this preset has no tuning budget (a 'tuning' entry)")
    spec = dict(p["tuning"])
    learners, steps = spec["learners"], spec["env_steps"]

    def env_learners(env: dict[str, Any]) -> list[tuple[str, str]]:
        if learners is not None:
            return list(learners)
        if "tuned" in env:
            return list(env["tuned"])
        headline = [r for r in env["runs"] if not is_tuned(r[1]) and len(r[2]) >= len(HEADLINE_SEEDS)]
        return [(algo, config) for algo, config, _ in headline]

    spec["learners"] = {env_id: env_learners(env) for env_id, env in p["envs"].items()}
    spec["env_steps"] = {
        env_id: env.get("tune_steps", env["budget"]) if steps is None else steps for env_id, env in p["envs"].items()
    }
    return spec


def select(cells: list[Cell], patterns: str | None) -> list[Cell]:
    """Cells whose id matches one of the comma-separated glob ``patterns`` (a pattern without ``*?[`` is a substring)."""
    if not patterns:
        return cells
    globs = [p if any(c in p for c in "*?[") else f"*{p}*" for p in (s.strip() for s in patterns.split(",")) if p]
    return [c for c in cells if any(fnmatch.fnmatchcase(c.cell_id, g) for g in globs)]
