from __future__ import annotations

import math
from typing import Any, ClassVar, TypeVar

import numpy as np
import torch as th
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, Schedule
from stable_baselines3.common.utils import FloatSchedule, LinearSchedule

from sb3_aac.common.action_stats import ActionStats
from sb3_aac.common.array_env import array_path, step_as_vec_env
from sb3_aac.common.guards import GuardedAlgorithmMixin, check_finite_step
from sb3_aac.common.hyperparameters import check_counts, check_finite, check_fraction, check_unit_interval
from sb3_aac.common.model_files import check_policy_class
from sb3_aac.common.seeding import algorithm_generator
from sb3_aac.common.observations import observation_batch
from sb3_aac.sarsa_aac.deep import DeepKernel, DeepTraces
from sb3_aac.sarsa_aac.exploration import TYPE_EXPLORATIONS, select_types
from sb3_aac.sarsa_aac.kernels import Kernel
from sb3_aac.sarsa_aac.lane_steps import LANE_CHUNK
from sb3_aac.sarsa_aac.monitoring import TRAIN_STAT_FIELDS, TrainingMonitor
from sb3_aac.sarsa_aac.parameter_critic import ParameterCritic, check_parameter_update
from sb3_aac.sarsa_aac.replay import RecentTransitions, Transitions
from sb3_aac.sarsa_aac.tile_coding import TileKernel, TileTraces
from sb3_aac.sarsa_aac.policies import DeepPolicy, MlpPolicy, RbfMlpPolicy, RbfPolicy, SarsaAACPolicy, TilePolicy

SelfSarsaAAC = TypeVar("SelfSarsaAAC", bound="SarsaAAC")

# Schedules are re-evaluated whenever training progress has moved by this much (0.1%), not at every step.
SCHEDULE_RESOLUTION = 1e-3
# The weights are checked (and kept as the last finite ones) every this many steps.
CHECK_INTERVAL = 256


class SarsaAAC(GuardedAlgorithmMixin, TrainingMonitor):
    """
    SARSA Actor-Actor-Critic (SARSA-AAC) for parameterized actions: pick one of K action types, then a real-valued
    parameter vector for it.

    Paper: V. Uc-Cetina, "A Novel Reinforcement Learning Architecture for Continuous State and Action Spaces",
    Advances in Artificial Intelligence 2013, https://doi.org/10.1155/2013/492852

    Per environment step ``(s, k, p, r, s', k', p')``, with ``V`` the critic, ``Q_k`` the action-type actor and
    ``mu`` the parameter actor (all independent function approximators, see :class:`SarsaAACPolicy`):

    - ``delta = r + gamma * V(s') - V(s)``; the critic steps toward ``r + gamma * V(s')``;
    - SARSA: ``Q_k`` steps toward ``r + gamma * Q_{k'}(s')``, where ``k'`` is the type actually chosen next;
    - CACLA (van Hasselt & Wiering 2007) on the parameter actor: only if ``delta > 0``, the approximators of
      type ``k``'s parameters step toward the *executed* parameters ``p`` (in the scaled ``[-1, 1]`` space).

    With ``trace_lambda > 0`` (TilePolicy and DeepPolicy) the critic learns by TD(lambda) and the action-type actor by
    SARSA(lambda) (Sutton & Barto, 2nd ed., Sec. 12.2 and 12.7): each step's error also moves the earlier states
    (and types) of the episode in proportion to their eligibility traces, which decay by ``gamma * trace_lambda``
    per step; one trace per lane, zeroed where an episode ends (termination or truncation, after that step's
    update). The parameter actor stays one-step: its CACLA target is the executed parameters, not a return.

    On a termination the targets are ``r``. On a time-limit truncation (``infos[i]["TimeLimit.truncated"]``) they
    bootstrap from ``infos[i]["terminal_observation"]``, with ``k'`` drawn there by the exploration policy.

    Replay (not in the paper; ``replay_ratio > 0``): every live transition is also kept in a buffer of the last
    ``replay_size`` (:mod:`sb3_aac.sarsa_aac.replay`), and after each env step's update ``replay_ratio`` transitions
    per lane, drawn uniformly from it, take the same one-step update on the current weights (no traces; the SARSA
    target with the ``k'`` that was chosen then). The buffer is not saved: a loaded model starts it empty. On by
    default only for the MLP families, where it wins per second as well as per sample on the paper env.

    Exploration (chosen by us; the paper does not describe it, and without it the CACLA update would be a
    no-op): epsilon-greedy (or Boltzmann) over action types and Gaussian noise of standard deviation
    ``param_noise`` on the scaled parameters; both decay linearly over the first ``exploration_fraction`` of
    training, or, if ``exploration_episodes`` is given, over that many finished episodes (counted over all lanes,
    since the model was created), whatever the budget. Executed parameters are clipped to the action space's
    bounds. Schedules of progress (exploration and learning rates) are re-evaluated every 0.1% of training
    progress rather than at every step; the episode schedule at every episode end.

    Every approximator takes normalised steps (see :mod:`sb3_aac.sarsa_aac.approximators`): for one sample a learning
    rate of 1 moves a linear approximator's output onto its target, and the lanes' samples of one env step are
    applied one after another, each error recomputed on the weights the earlier lanes left
    (:mod:`sb3_aac.sarsa_aac.lane_steps`). So ``n`` lanes take the steps one lane would take on their ``n`` samples
    (the targets bootstrapped from the weights at the start of the env step, or with hidden layers at the start of
    the sample's chunk of at most :data:`~sb3_aac.sarsa_aac.lane_steps.LANE_CHUNK` lanes): a rate means the same per
    sample whatever the number of lanes, so the learning curve per env step changes with the lane count only through
    the order and the correlation of the samples (measured in ``docs/sarsa_aac_results.md``). Rates are validated to lie in
    ``[0, 1]``; 0 freezes an approximator (as rl-zoo3's ``enjoy`` loads a model only to act, with
    ``custom_objects={"learning_rate": 0.0}``).

    Reward units do not matter: ``return_scale`` is the root mean square of the lanes' discounted returns
    (``G <- gamma * G + r``, reset at episode ends) over all steps so far. When it first becomes non-zero, the
    initial (random) Q and V weights are multiplied by it, and the hidden layers of the Q and V approximators
    (MLP heads) take steps divided by ``return_scale**2``, i.e. they learn as if the targets were in units of
    ``return_scale``; linear heads and output layers are unit-free by construction, and CACLA only reads the sign
    of ``delta``. So multiplying every reward by ``c > 0`` multiplies Q, V and ``return_scale`` by ``c`` and
    leaves every decision unchanged (up to rounding). The Boltzmann temperature is in units of ``return_scale``.

    Divergence: every forward pass of training is checked for non-finite outputs before an action is chosen
    from it, and the weights are checked every ``CHECK_INTERVAL`` steps, when a copy of them is kept. On a
    non-finite value the weights are restored to that copy and a ``FloatingPointError`` names the approximators;
    ``save`` after it saves a usable model.

    Envs offering the array path (:func:`sb3_aac.common.array_env.array_path`) are stepped with arrays, other envs
    with SB3's ``env.step``; the callbacks' locals are the same on both (see :mod:`sb3_aac.common.array_env`).
    All updates are closed-form numpy on the CPU, vectorised over environments; ``device`` only says where the
    parameters are stored between ``learn()`` calls. Callbacks run after ``env.step`` and before that step's
    update.

    The paper gives no numbers for any hyperparameter; every default below was chosen by us, on the measurements in
    ``docs/sarsa_aac_results.md`` ("How the defaults were chosen").

    :param policy: The policy model to use (DeepPolicy, recommended; TilePolicy, the fastest per env step; MlpPolicy,
        RbfMlpPolicy, RbfPolicy; or a SarsaAACPolicy subclass)
    :param env: The environment to learn from (if registered in Gym, can be str)
    :param learning_rate: Critic learning rate (normalised, in ``[0, 1]``), or a schedule of the progress
        remaining (from 1 to 0) whose values at 1 and 0 are in ``[0, 1]``; None (the default) takes the policy's
        ``default_learning_rate`` (0.1 per sample for the tiles, RBFs and RbfMlpPolicy, 0.05 for MlpPolicy, 0.5 for
        DeepPolicy's ObGD step), as do the other two rates
    :param q_learning_rate: Action-type actor learning rate, or a schedule
    :param param_learning_rate: Parameter actor learning rate, or a schedule
    :param gamma: The discount factor
    :param type_exploration: ``"epsilon_greedy"``, or ``"boltzmann"`` (softmax over Q with temperature given by
        the exploration schedule, in units of ``return_scale``)
    :param exploration_fraction: Fraction of the training period over which the exploration rate and the
        parameter noise decay (unused if ``exploration_episodes`` is given)
    :param exploration_episodes: If given, the exploration rate and the parameter noise decay over this many
        finished episodes instead, so the schedule does not depend on ``total_timesteps``
    :param exploration_initial_eps: Initial epsilon (or temperature for Boltzmann exploration)
    :param exploration_final_eps: Final epsilon (or temperature)
    :param param_noise_initial: Initial standard deviation of the Gaussian noise on the scaled parameters
    :param param_noise_final: Final standard deviation of the parameter noise
    :param parameter_update: The parameter actor's update: ``"cacla"`` (the paper's: toward the executed parameters
        where ``delta > 0``) or ``"critic"`` (toward them where a critic of the parameters, learned online at the
        critic's rate, says they gain; :mod:`sb3_aac.sarsa_aac.parameter_critic`)
    :param trace_lambda: The eligibility-trace decay ``lambda`` in ``[0, 1]`` of the critic and the action-type
        actor; 0 (the default) is the one-step update; ``> 0`` needs TilePolicy or DeepPolicy
    :param replacing_traces: Replacing traces (a visited feature's trace is set to 1, and its traces of the
        other action types to 0) if True, accumulating traces (1 is added) if False
    :param replay_ratio: Replayed transitions per live one, a whole number ``>= 0`` (0: no replay); None (the
        default) takes the policy's ``default_replay_ratio`` (2 for MlpPolicy and RbfMlpPolicy, 0 for the others)
    :param replay_size: How many recent transitions (of all lanes) the replay buffer holds
    :param info_keywords: Keys of ``info`` read at the step where an episode ends and logged as
        ``rollout/ep_<key>_mean`` (mean over the last ``stats_window_size`` episodes that reported it)
    :param stats_window_size: Window size for the rollout logging, specifying the number of episodes to average
        the reported success rate, mean episode length, and mean reward over
    :param log_min_timesteps: ``learn(log_interval=n)`` dumps the logs once ``n`` episodes (SB3's off-policy
        convention) *and* at least this many env steps (counted over all lanes) have passed since the previous
        dump. The spacing in steps keeps logging a fixed share of the work whatever the number of lanes (with 256
        lanes, episodes end at every step, so ``n`` episodes alone would dump at every step); 0 dumps every ``n``
        episodes, as SB3's DQN does. The first dump of a ``learn`` call comes after its first ``n`` episodes, without
        the spacing, and ``learn`` ends with a dump of what it logged since the last one.
    :param tensorboard_log: the log location for tensorboard (if None, no logging)
    :param policy_kwargs: additional arguments to be passed to the policy on creation (see :class:`DenseBankPolicy`
        for MlpPolicy, RbfMlpPolicy and RbfPolicy, :class:`TilePolicy`)
    :param verbose: Verbosity level: 0 for no output, 1 for info messages (such as device or wrappers used), 2 for
        debug messages
    :param seed: Seed for the pseudo random generators
    :param device: Device on which the parameters are stored; the computation is numpy on the CPU
    :param _init_setup_model: Whether or not to build the network at the creation of the instance
    """

    load_device: ClassVar[str] = "cpu"  # its updates are numpy on the CPU

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {
        "DeepPolicy": DeepPolicy,
        "MlpPolicy": MlpPolicy,
        "RbfMlpPolicy": RbfMlpPolicy,
        "RbfPolicy": RbfPolicy,
        "TilePolicy": TilePolicy,
    }
    policy: SarsaAACPolicy
    # Per-lane discounted returns so far (None until the first step), and the last finite weights (restored on
    # divergence; None until first kept). Set in _reset_train_stats.
    _lane_returns: np.ndarray | None
    _finite_weights: dict[str, th.Tensor] | None
    # The policy's training kernel, bound when learn() starts.
    _kernel: Kernel[Any]

    def __init__(
        self,
        policy: str | type[SarsaAACPolicy],
        env: GymEnv | str | None,
        learning_rate: float | Schedule | None = None,
        q_learning_rate: float | Schedule | None = None,
        param_learning_rate: float | Schedule | None = None,
        gamma: float = 0.9,
        type_exploration: str = "epsilon_greedy",
        exploration_fraction: float = 0.5,
        exploration_episodes: int | None = None,
        exploration_initial_eps: float = 0.3,
        exploration_final_eps: float = 0.05,
        param_noise_initial: float = 0.3,
        param_noise_final: float = 0.05,
        parameter_update: str = "cacla",
        trace_lambda: float = 0.0,
        replacing_traces: bool = True,
        replay_ratio: int | None = None,
        replay_size: int = 10_000,
        info_keywords: tuple[str, ...] = ("distance", "ball_lost"),
        stats_window_size: int = 100,
        log_min_timesteps: int = 2000,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: th.device | str = "cpu",
        _init_setup_model: bool = True,
    ) -> None:
        super().__init__(
            policy,
            env,
            learning_rate,  # type: ignore[arg-type]  # None until the policy's default is known, below
            policy_kwargs=policy_kwargs,
            stats_window_size=stats_window_size,
            tensorboard_log=tensorboard_log,
            verbose=verbose,
            device=device,
            support_multi_env=True,
            seed=seed,
            # The action space is validated (with a ValueError) when the policy parses it.
            supported_action_spaces=None,
        )
        check_policy_class(self, SarsaAACPolicy)
        default = self.policy_class.default_learning_rate  # type: ignore[attr-defined]  # a SarsaAACPolicy, checked
        self.learning_rate = default if learning_rate is None else learning_rate
        self.q_learning_rate = default if q_learning_rate is None else q_learning_rate
        self.param_learning_rate = default if param_learning_rate is None else param_learning_rate
        self.gamma = gamma
        self.type_exploration = type_exploration
        self.exploration_fraction = exploration_fraction
        self.exploration_episodes = exploration_episodes
        self.exploration_initial_eps = exploration_initial_eps
        self.exploration_final_eps = exploration_final_eps
        self.param_noise_initial = param_noise_initial
        self.param_noise_final = param_noise_final
        self.parameter_update = parameter_update
        self.trace_lambda = trace_lambda
        self.replacing_traces = replacing_traces
        self.replay_ratio = self.policy_class.default_replay_ratio if replay_ratio is None else replay_ratio  # type: ignore[attr-defined]
        self.replay_size = replay_size
        self._set_info_keywords(info_keywords)
        # A run-time check of user input that the annotation cannot guarantee.
        if not (isinstance(log_min_timesteps, (int, np.integer)) and log_min_timesteps >= 0):  # type: ignore[redundant-expr]
            raise ValueError(f"log_min_timesteps must be a whole number of env steps >= 0, got {log_min_timesteps!r}")
        self.log_min_timesteps = int(log_min_timesteps)
        if _init_setup_model:
            self._setup_model()

    def _check_hyperparameters(self) -> None:
        for name in ("learning_rate", "q_learning_rate", "param_learning_rate"):
            rate = getattr(self, name)
            values = (rate(1.0), rate(0.0)) if callable(rate) else (rate,)
            if not all(isinstance(v, (int, float, np.floating)) and 0 <= v <= 1 for v in values):
                raise ValueError(
                    f"{name} must be in [0, 1] (a normalised step; 1 lands one sample on its target, 0 learns nothing), got "
                    f"{values[0] if len(values) == 1 else f'a schedule from {values[0]} to {values[1]}'}"
                )
        if self.type_exploration not in TYPE_EXPLORATIONS:
            raise ValueError(f"Unknown type_exploration {self.type_exploration!r}, valid values: {list(TYPE_EXPLORATIONS)}")
        check_unit_interval(self, "gamma")
        check_fraction(self, "exploration_fraction")
        episodes = self.exploration_episodes
        # A run-time check of user input that the annotation cannot guarantee.
        if episodes is not None and not (
            isinstance(episodes, (int, np.integer)) and not isinstance(episodes, bool) and episodes >= 1  # type: ignore[redundant-expr]
        ):
            raise ValueError(f"exploration_episodes must be None or a whole number of episodes >= 1, got {episodes!r}")
        exploration = ("exploration_initial_eps", "exploration_final_eps", "param_noise_initial", "param_noise_final")
        check_finite(self, *exploration, minimum=0)
        check_parameter_update(self.parameter_update)
        check_unit_interval(self, "trace_lambda", note=" (0: one-step updates)")
        if not isinstance(self.replacing_traces, (bool, np.bool_)):
            raise ValueError(
                f"replacing_traces must be True (replacing) or False (accumulating), got {self.replacing_traces!r}"
            )
        ratio = self.replay_ratio
        if not (isinstance(ratio, (int, np.integer)) and not isinstance(ratio, bool) and ratio >= 0):
            raise ValueError(
                f"replay_ratio must be a whole number of replayed transitions per live one, >= 0 (0: no replay), got {ratio!r}"
            )
        check_counts(self, "replay_size")
        if self.type_exploration == "epsilon_greedy" and max(self.exploration_initial_eps, self.exploration_final_eps) > 1:
            raise ValueError("epsilon-greedy exploration rates must be <= 1")

    def _setup_model(self) -> None:
        self._check_hyperparameters()
        self._setup_lr_schedule()
        self.q_lr_schedule = FloatSchedule(self.q_learning_rate)
        self.param_lr_schedule = FloatSchedule(self.param_learning_rate)
        # By episodes the schedules read 1 - episodes / exploration_episodes (see _exploration_progress).
        fraction = self.exploration_fraction if self.exploration_episodes is None else 1.0
        self.exploration_schedule = LinearSchedule(self.exploration_initial_eps, self.exploration_final_eps, fraction)
        self.param_noise_schedule = LinearSchedule(self.param_noise_initial, self.param_noise_final, fraction)
        self._update_exploration()
        self.set_random_seed(self.seed)
        # SB3 types policy_class as type[BasePolicy]; __init__ checked that it is a SarsaAACPolicy.
        self.policy = self.policy_class(self.observation_space, self.action_space, **self.policy_kwargs)  # type: ignore[assignment]
        self.policy = self.policy.to(self.device)
        if self.trace_lambda > 0 and not isinstance(self.policy, (TilePolicy, DeepPolicy)):
            raise ValueError(
                f"trace_lambda > 0 (got {self.trace_lambda}) needs linear tile heads (TilePolicy) or DeepPolicy; "
                f"{type(self.policy).__name__} learns with one-step updates only (trace_lambda=0)"
            )
        # The critic of the parameters (parameter_update="critic"; None for the paper's CACLA).
        self.parameter_critic = ParameterCritic(self.policy) if self.parameter_update == "critic" else None
        # The recent transitions replayed after each env step's own update (None without replay; not saved).
        obs_dim = int(np.prod(self.observation_space.shape))  # type: ignore[arg-type]  # a Box, checked by the policy
        self._replay = RecentTransitions(self.replay_size, obs_dim, self.policy.n_params) if self.replay_ratio > 0 else None
        # The action a' chosen at _last_obs and not yet executed: (obs (n, D), k (n,), scaled params (n, P)).
        self._pending: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        # The lanes' eligibility traces of the episodes under way (None with trace_lambda == 0 or before learn).
        self._traces: TileTraces | DeepTraces | None = None
        # Count and sum of squares of the lanes' discounted returns so far; return_scale = sqrt(sum / count).
        # Kept when load() calls this after restoring them (0 until the first non-zero reward).
        self._return_moments = getattr(self, "_return_moments", np.zeros(2))
        self.return_scale = getattr(self, "return_scale", 0.0)
        self._reset_keyword_buffers()
        self._reset_train_stats()

    def set_random_seed(self, seed: int | None = None) -> None:
        """Seed python, numpy, torch, the action space, the env, and the algorithm's own generator."""
        super().set_random_seed(seed)
        # All exploration draws come from this generator, seeded from the global state
        # when seed is None (set_random_seed repeats runs)
        self._rng = algorithm_generator(seed)

    def _get_torch_save_params(self) -> tuple[list[str], list[str]]:
        return (["policy"] if self.parameter_critic is None else ["policy", "parameter_critic"]), []

    def _excluded_save_params(self) -> list[str]:
        return [
            *super()._excluded_save_params(),
            # Per-run state rebuilt by _setup_model / learn (the generator is re-seeded from `seed`).
            *("_pending", "_rng", "_kernel", "_lr", "_rows", "_td_chunks", "_train_stats", "_action_stats", "_replay"),
            "parameter_critic",  # its weights are saved as a state dict where it exists (_get_torch_save_params)
            *("_hidden_gain", "_lane_returns", "_finite_weights", "_last_dump", "_dumped_in_learn", "_traces", "_trace_hits"),
        ]

    # ------------------------------------------------------------------ acting

    def _explore(self, out: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exploratory types ``(n,)`` and scaled, clipped parameters ``(n, P)`` from bank outputs ``(n, A)``."""
        policy = self.policy
        rate = self.exploration_rate
        if self.type_exploration == "boltzmann" and self.return_scale > 0:
            rate *= self.return_scale  # the temperature is in units of the return scale
        k = select_types(out[:, policy.q_slice], rate, self.type_exploration, self._rng)
        params = out[:, policy.param_slice]
        if self.param_noise > 0:
            # Not Generator.normal(params, ...): with an array mean it costs several times more.
            params = params + self.param_noise * self._rng.standard_normal(params.shape)
        else:
            params = params.copy()
        # In place: np.clip costs several times more on small arrays.
        np.minimum(params, 1.0, out=params)
        return k, np.maximum(params, -1.0, out=params)

    def predict(  # type: ignore[override]
        self,
        observation: np.ndarray,
        state: tuple[np.ndarray, ...] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = False,
    ) -> tuple[Any, tuple[np.ndarray, ...] | None]:
        """
        Get the action(s) for one observation or a batch.

        :param observation: one observation, or a batch ``(n, *obs_shape)``
        :param state: unused (no recurrent state), returned as is
        :param episode_start: unused
        :param deterministic: greedy action if True, otherwise the current exploration (``exploration_rate``,
            ``param_noise``) is applied, as during training
        :return: one env action (a tuple ``env.step`` accepts) for a single observation, or an object ndarray of
            shape ``(n,)`` of such tuples for a batch; and ``state``
        """
        if deterministic:
            return self.policy.predict(observation, state, episode_start, deterministic=True)
        obs, vectorized = observation_batch(observation, self.observation_space)
        out, _ = self.policy.evaluate(obs)
        k, params = self._explore(out)
        return self.policy.actions_from_outputs(out, k, params, vectorized), state

    # ------------------------------------------------------------------ learning

    def learn(
        self: SelfSarsaAAC,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int | None = 4,
        tb_log_name: str = "SarsaAAC",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> SelfSarsaAAC:
        """
        Return a trained model.

        :param total_timesteps: The total number of samples (env steps) to train on
        :param callback: callback(s) called at every step with state of the algorithm.
        :param log_interval: Dump the logs every ``log_interval`` finished episodes, but at most once per
            ``log_min_timesteps`` env steps, and at the end (see the class docstring; None: never)
        :param tb_log_name: the name of the run for TensorBoard logging
        :param reset_num_timesteps: whether or not to reset the current timestep number (used in logging)
        :param progress_bar: Display a progress bar using tqdm and rich.
        :return: the trained model
        """
        obs_before = self._last_obs
        total_timesteps, callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar
        )
        self._last_dump = (self._episode_num, self.num_timesteps)
        self._dumped_in_learn = False
        callback.on_training_start(locals(), globals())
        assert self.env is not None
        env = self.env
        if self.device.type != "cpu":
            self.policy.to("cpu")  # the updates are numpy on CPU storage
        self._kernel = self.policy.rebind()
        if self.parameter_critic is not None:
            self.parameter_critic.reset_kernel()
        if self._pending is None or self._last_obs is not obs_before:
            obs = self._last_obs.astype(np.float64).reshape(self.n_envs, -1)  # type: ignore[union-attr]
            self._observe(obs)
            self._pending = (obs, *self._explore(self._kernel.forward(obs)[0]))
            self._traces = self._new_traces()  # new episodes

        self._update_schedules()
        self._keep_finite_weights()
        array_env = array_path(env)
        callback.on_rollout_start()
        try:
            while self.num_timesteps < total_timesteps:
                _, k, params = self._pending
                # Callbacks see ``actions`` in locals(): the env's actions, or (types, params) on the array path.
                actions: np.ndarray | tuple[np.ndarray, np.ndarray]
                new_obs: np.ndarray
                infos: list[dict[str, Any]]
                if array_env is None:
                    actions = self.policy.spec.to_env(k, params)
                    # SB3 types VecEnv observations as a union; a Box observation space gives an array.
                    new_obs, rewards, dones, infos = env.step(actions)  # type: ignore[assignment]
                else:
                    actions = (k, params)
                    new_obs, rewards, dones, infos = step_as_vec_env(array_env, k, self.policy.spec.unscale(params))
                self.num_timesteps += env.num_envs
                check_finite_step(new_obs, rewards, self.num_timesteps)

                callback.update_locals(locals())
                if not callback.on_step():
                    # The env has moved on without an update: choose afresh at new_obs next time.
                    self._last_obs, self._last_episode_starts, self._pending = new_obs, dones, None
                    break

                self._update_current_progress_remaining(self.num_timesteps, total_timesteps)
                any_done = bool(dones.any())
                if any_done:  # episode statistics and success flags exist only where an episode ended
                    ended = np.flatnonzero(dones)
                    self._update_info_buffer([infos[i] for i in ended], dones[ended])
                self._train_step(new_obs, rewards, dones, infos, any_done)
                self._last_obs, self._last_episode_starts = new_obs, dones
                if any_done:
                    self._on_episodes_end(dones, infos, log_interval)
            self._flush_td_chunks()
            if log_interval is not None and self.num_timesteps > self._last_dump[1]:
                self.dump_logs()
        finally:
            if self.device.type != "cpu":
                self.policy.to(self.device)
        callback.on_rollout_end()
        callback.on_training_end()
        return self

    def _update_schedules(self) -> None:
        """Evaluate the exploration and learning-rate schedules at the current progress."""
        progress = self._schedule_progress = self._current_progress_remaining
        self._update_exploration()
        policy, lr = self.policy, self._lr
        lr[policy.q_slice] = self.q_lr_schedule(progress)
        lr[policy.param_slice] = self.param_lr_schedule(progress)
        lr[policy.value_index] = self.lr_schedule(progress)

    def _update_exploration(self) -> None:
        """The exploration rate and parameter noise at the current progress (of training, or of the episodes)."""
        if self.exploration_episodes is None:
            progress = self._current_progress_remaining
        else:
            progress = max(0.0, 1.0 - self._episode_num / self.exploration_episodes)
        self.exploration_rate = self.exploration_schedule(progress)
        self.param_noise = self.param_noise_schedule(progress)

    def _train_step(
        self, new_obs: np.ndarray, rewards: np.ndarray, dones: np.ndarray, infos: list[dict[str, Any]], any_done: bool
    ) -> None:
        """
        One SARSA-AAC update of every approximator for all envs, then choose the next action. The lanes of a policy
        with hidden layers (DeepPolicy, the MLP heads) are updated in chunks of at most
        :data:`~sb3_aac.sarsa_aac.lane_steps.LANE_CHUNK`, one after another.
        """
        obs, k, params = self._pending  # type: ignore[misc]
        n = len(k)
        if self._current_progress_remaining < self._schedule_progress - SCHEDULE_RESOLUTION:
            self._update_schedules()

        # An owned float64 copy: kept until the next step (a VecEnv may reuse its buffer) and no mixed dtypes.
        next_obs = new_obs.astype(np.float64).reshape(n, -1)
        discount = np.where(dones, 0.0, self.gamma)
        # Time-limit truncations bootstrap from the terminal observation (new_obs already holds the reset one).
        truncated = [int(i) for i in np.flatnonzero(dones) if infos[i].get("TimeLimit.truncated", False)] if any_done else []
        terminal_obs = {i: np.ravel(infos[i]["terminal_observation"]) for i in truncated}
        rewards = rewards.astype(np.float64)  # mixed float32/float64 arithmetic costs more than this cast
        # Before the forward pass: it may put the weights into return units, and s' normalised with itself.
        self._track_return_scale(rewards, dones)
        self._observe(next_obs)
        chunk = LANE_CHUNK if self.policy.chunks_lanes else n
        parts = [
            self._update_lanes(slice(start, start + chunk), obs, k, params, rewards, next_obs, discount, terminal_obs)
            for start in range(0, n, chunk)
        ]
        if len(parts) == 1:
            next_k, next_params, stats = parts[0]
        else:
            next_k, next_params = np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
            stats = tuple(np.concatenate(columns) for columns in zip(*(p[2] for p in parts), strict=True))
        if any_done and self._traces is not None:
            self._traces.clear(np.flatnonzero(dones))
        if self._replay is not None:
            self._replay_transitions(self._replay.sample(n * self.replay_ratio, self._rng), chunk)
        self._n_updates += 1

        self._pending = (next_obs, next_k, next_params)
        self._td_chunks.append(stats)
        if len(self._td_chunks) >= CHECK_INTERVAL:
            self._flush_td_chunks()
            self._keep_finite_weights()

    def _update_lanes(
        self,
        lanes: slice,
        obs: np.ndarray,
        k: np.ndarray,
        params: np.ndarray,
        rewards: np.ndarray,
        next_obs: np.ndarray,
        discount: np.ndarray,
        terminal_obs: dict[int, np.ndarray],
    ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
        """
        The update of the env step's ``lanes`` on the current weights (errors measured before any of their steps).

        :param terminal_obs: the terminal observations of the truncated lanes, by lane
        :return: the lanes' next types and parameters chosen at ``next_obs``, and their TD statistics
            ``(delta, q_error, k, params, V(s))``
        """
        policy, kernel = self.policy, self._kernel
        start = lanes.start
        obs, k, params, rewards, next_obs = obs[lanes], k[lanes], params[lanes], rewards[lanes], next_obs[lanes]
        discount = discount[lanes]  # a view: the truncated lanes' entries are set below (the step's array is not reused)
        n, vi = len(k), policy.value_index
        rows = self._rows if len(self._rows) == n else np.arange(n)
        truncated = [i - start for i in terminal_obs if start <= i < start + n]
        traces = self._traces
        if traces is not None and n < self.n_envs:
            assert isinstance(traces, DeepTraces)  # the only other traces are TilePolicy's, whose lanes are not split
            traces = traces.lanes(lanes)
        batch = np.concatenate((obs, next_obs, *[terminal_obs[start + i][None] for i in truncated]))
        # One forward pass for s (weights as they are now), s' and the terminal observations.
        out, cache = kernel.forward(batch)
        if not math.isfinite(out.sum()):  # one reduction catches NaN and inf before an action is chosen from them
            self._on_non_finite_outputs(batch)
        current, following = out[:n], out[n : 2 * n]
        next_k, next_params = self._explore(following)
        # The observation and type each lane's targets bootstrap from: s' and k', or where truncated the terminal ones.
        bootstrap_obs, bootstrap_k = next_obs, next_k
        if truncated:
            terminal = out[2 * n :]
            bootstrap_obs, bootstrap_k = next_obs.copy(), next_k.copy()
            bootstrap_obs[truncated] = batch[2 * n :]
            bootstrap_k[truncated] = self._explore(terminal)[0]
            following = following.copy()
            following[truncated] = terminal
            discount[truncated] = self.gamma
        if self._replay is not None:
            self._replay.add(obs, k, params, rewards, discount, bootstrap_obs, bootstrap_k)
        err, delta, q_error = self._errors(obs, k, params, rewards, discount, current, following, bootstrap_k, rows)
        self._apply(cache, err, k, traces)
        return next_k, next_params, (delta, q_error, k, params, current[:, vi])

    def _errors(
        self,
        obs: np.ndarray,
        k: np.ndarray,
        params: np.ndarray,
        rewards: np.ndarray,
        discount: np.ndarray,
        current: np.ndarray,
        following: np.ndarray,
        next_k: np.ndarray,
        rows: np.ndarray,
        observe: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Target minus output ``(n, A)`` of a batch of transitions, with its TD and SARSA errors ``(n,)`` each.

        :param current: the outputs at ``s``; ``following``: at the observations the targets bootstrap from
        :param next_k: the types chosen there; ``rows``: ``arange(n)``
        :param observe: whether a deep parameter critic folds ``obs`` into its input normalisation (not on replay)
        """
        policy, vi, ps = self.policy, self.policy.value_index, self.policy.param_slice
        delta = rewards + discount * following[:, vi] - current[:, vi]
        q_error = rewards + discount * following[rows, next_k] - current[rows, k]
        err = np.zeros_like(current)
        err[rows, k] = q_error
        # CACLA: move the chosen type's parameter approximators toward the executed parameters if delta > 0.
        if self.parameter_critic is None:
            err[:, ps] = (params - current[:, ps]) * policy.param_table[(delta > 0).view(np.uint8), k]
        else:
            err[:, ps] = self.parameter_critic.parameter_errors(
                obs, k, params, current[:, ps], delta, self._lr[vi], self._hidden_gain[vi], self.param_noise, observe
            )
        err[:, vi] = delta
        return err, delta, q_error

    def _apply(self, cache: Any, err: np.ndarray, k: np.ndarray, traces: TileTraces | DeepTraces | None) -> None:
        """One step of the kernel on ``err`` (from :meth:`_errors`), through the lanes' traces where they exist."""
        kernel = self._kernel
        if isinstance(kernel, DeepKernel):
            assert traces is None or isinstance(traces, DeepTraces)
            kernel.update(cache, err, self._lr, self._hidden_gain, k, traces)
        elif traces is None:
            kernel.update(cache, err, self._lr, self._hidden_gain)
        else:
            assert isinstance(kernel, TileKernel) and isinstance(traces, TileTraces)  # checked in _setup_model
            kernel.update_traced(cache, err, self._lr, self._trace_hits[k], traces)

    def _replay_transitions(self, transitions: Transitions, chunk: int) -> None:
        """
        One-step updates (no traces) on replayed transitions, ``chunk`` at a time, each chunk's errors measured on
        the weights the earlier chunks left; the targets bootstrap from the stored ``k'`` (see the class docstring).
        """
        obs, k, params, rewards, discount, next_obs, next_k = transitions
        for start in range(0, len(k), chunk):
            part = slice(start, start + chunk)
            n = len(k[part])
            batch = np.concatenate((obs[part], next_obs[part]))
            out, cache = self._kernel.forward(batch)
            if not math.isfinite(out.sum()):
                self._on_non_finite_outputs(batch)
            err, _, _ = self._errors(
                obs[part], k[part], params[part], rewards[part], discount[part], out[:n], out[n:], next_k[part],
                np.arange(n), observe=False,
            )  # fmt: skip
            self._apply(cache, err, k[part], None)

    # ------------------------------------------------------------------ return scale

    def _track_return_scale(self, rewards: np.ndarray, dones: np.ndarray) -> None:
        """
        Fold this step's per-lane discounted returns into ``return_scale``; on its first non-zero value, express
        the initial Q and V weights in those units (see the class docstring).
        """
        lane_returns = self._lane_returns
        if lane_returns is None or len(lane_returns) != len(rewards):
            lane_returns = self._lane_returns = np.zeros(len(rewards))
        lane_returns *= self.gamma
        lane_returns += rewards
        self._return_moments[0] += len(rewards)
        self._return_moments[1] += lane_returns @ lane_returns
        lane_returns[dones] = 0.0
        count, square_sum = self._return_moments
        scale = math.sqrt(square_sum / count)
        if scale > 0:
            if self.return_scale == 0:  # the Q and V weights are not in return units yet
                self.policy.scale_value_outputs(scale)
            self.return_scale = scale
            self._set_return_units()

    def _set_return_units(self) -> None:
        """The hidden-layer gains of the Q and V approximators for the current ``return_scale``."""
        unit = self.return_scale if self.return_scale > 0 else 1.0
        policy = self.policy
        self._hidden_gain[policy.q_slice] = self._hidden_gain[policy.value_index] = unit**-2

    # ------------------------------------------------------------------ per-run state

    def _observe(self, obs: np.ndarray) -> None:
        """Fold new observations ``(n, D)`` into a deep policy's running statistics (other policies keep none)."""
        if isinstance(self.policy, DeepPolicy):
            self.policy.approximators.observe(obs)

    def _new_traces(self) -> TileTraces | DeepTraces | None:
        """Zero eligibility traces of the action-type actor and the critic, one per lane (None if ``trace_lambda == 0``)."""
        if self.trace_lambda == 0:
            return None
        policy = self.policy
        if isinstance(policy, DeepPolicy):
            return policy.approximators.new_traces(self.n_envs, self.gamma * self.trace_lambda)
        assert isinstance(policy, TilePolicy)  # checked in _setup_model
        columns = np.array([*range(policy.n_types), policy.value_index])
        # hit[k]: the columns whose trace the features of (s, k) set: Q_k and V.
        self._trace_hits = np.concatenate((np.eye(policy.n_types), np.ones((policy.n_types, 1))), axis=1)
        decay = self.gamma * self.trace_lambda
        return TileTraces(self.n_envs, policy.approximators.n_features, columns, decay, self.replacing_traces)

    def _reset_train_stats(self) -> None:
        self._lr = np.zeros(self.policy.value_index + 1)
        self._rows = np.arange(self.n_envs)
        self._td_chunks = []
        self._hidden_gain = np.ones_like(self._lr)
        self._set_return_units()
        self._lane_returns = None
        self._finite_weights = None
        self._finite_weights_timestep = 0
        # Sums since the last dump (TRAIN_STAT_FIELDS); the executed actions and the critic's values.
        self._train_stats = np.zeros(len(TRAIN_STAT_FIELDS))
        self._action_stats = ActionStats(self.policy.spec, value_name="value")
