from __future__ import annotations

import io
import pathlib
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, TypeVar

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.noise import ActionNoise
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.save_util import load_from_pkl
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, RolloutReturn, Schedule, TrainFreq, TrainFrequencyUnit
from stable_baselines3.common.utils import (
    FloatSchedule,
    LinearSchedule,
    should_collect_more_steps,
    update_learning_rate,
)
from stable_baselines3.common.vec_env import VecEnv
from torch.nn import functional as F

from sb3_aac.common.action_stats import ActionStats
from sb3_aac.common.array_env import array_path, step_as_vec_env
from sb3_aac.common.divergence import divergence_error
from sb3_aac.common.episode_stats import EpisodeStatsMixin
from sb3_aac.common.guards import GuardedAlgorithmMixin, check_finite_step, check_schedule
from sb3_aac.common.hyperparameters import check_counts, check_fraction, check_positive, check_unit_interval
from sb3_aac.common.model_files import check_policy_class
from sb3_aac.common.seeding import algorithm_generator
from sb3_aac.common.observations import observation_batch
from sb3_aac.common import mlp_gradients
from sb3_aac.common.updates import clip_grad_norm, polyak_update, set_grads
from sb3_aac.pdqn.buffers import ParameterizedReplayBuffer, ParameterizedReplayBufferSamples
from sb3_aac.pdqn.noise import ParamNoise
from sb3_aac.pdqn.policies import MlpPolicy, PDQNPolicy

SelfPDQN = TypeVar("SelfPDQN", bound="PDQN")


def mse_loss(q: th.Tensor, target: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
    """The mean squared error of ``q`` ``(n,)`` and its gradient with respect to ``q``."""
    return F.mse_loss(q, target), (q - target) * (2.0 / len(q))


def huber_loss(q: th.Tensor, target: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
    """The Huber loss (``smooth_l1_loss``, threshold 1) of ``q`` ``(n,)`` and its gradient with respect to ``q``."""
    return F.smooth_l1_loss(q, target), (q - target).clamp(-1.0, 1.0) / len(q)


# The Q network's loss functions: (q, target) -> (loss, d loss / d q).
LOSSES: dict[str, Callable[[th.Tensor, th.Tensor], tuple[th.Tensor, th.Tensor]]] = {"mse": mse_loss, "huber": huber_loss}


def invert_gradients(grad: th.Tensor, params: th.Tensor) -> th.Tensor:
    """
    Inverting gradients (Hausknecht & Stone 2016) in the scaled space ``[-1, 1]``.

    ``grad`` is the ascent direction ``dQ/dx``. Where it points up it is scaled by ``(1 - x) / 2``, where it points
    down by ``(x + 1) / 2``: it fades as ``x`` approaches the bound it points to and reverses once ``x`` is beyond it.
    """
    return th.where(grad > 0, grad * (1.0 - params), grad * (params + 1.0)) / 2.0


class PDQN(GuardedAlgorithmMixin, EpisodeStatsMixin, OffPolicyAlgorithm):
    """
    Parameterized Deep Q-Network (P-DQN) for parameterized actions: pick one of K action types and its parameters.

    Paper: J. Xiong et al., "Parametrized Deep Q-Networks Learning: Reinforcement Learning with Discrete-Continuous
    Hybrid Action Space", 2018, https://arxiv.org/abs/1810.06394

    Two networks (see :class:`~sb3_aac.pdqn.policies.PDQNPolicy`): the parameter actor ``x(s)`` gives every type's
    parameters, the Q network ``Q(s, k, x)`` the value of each type given all of them. The agent acts with
    ``k = argmax_k Q(s, k, x(s))`` and ``x_k(s)``. Per gradient step, on a replay minibatch:

    - Q network: minimise ``loss(Q(s, k, x), r + gamma * (1 - done) * max_k' Q'(s', k', x'(s')))`` over the stored
      ``(s, k, x)``, with ``Q'``, ``x'`` the target networks and ``loss`` the squared error (both papers) or Huber;
    - parameter actor: maximise ``sum_k Q(s, k, x(s))`` (the Q network held fixed);
    - every ``target_update_interval`` gradient steps: Polyak averaging of the targets, ``tau`` for the Q network and
      ``actor_tau`` for the actor (the reference code: 0.1 and 0.001).

    Parameters stay inside their bounds as in the papers, by inverting gradients (``policy_kwargs`` ``param_bounding=
    "invert_gradients"``, the default; the actor's output is clipped when acting), or by a tanh on the actor's output
    (``param_bounding="tanh"``). Gradient norms are clipped to ``max_grad_norm`` (10 in the reference code).

    Exploration: epsilon-greedy over types, epsilon decaying linearly over ``exploration_fraction`` of training
    (as DQN), and Gaussian or Ornstein-Uhlenbeck noise on the scaled parameters; before ``learning_starts`` the
    actions are uniformly random. Time-limit truncations bootstrap from the terminal observation
    (``replay_buffer_kwargs=dict(handle_timeout_termination=...)``). Envs offering the array path
    (:func:`sb3_aac.common.array_env.array_path`) are stepped with arrays; the callbacks' locals are the same on
    both paths (see :mod:`sb3_aac.common.array_env`), plus ``k`` and ``params``.

    :param policy: The policy model to use (MlpPolicy, or a PDQNPolicy subclass)
    :param env: The environment to learn from (if registered in Gym, can be str)
    :param learning_rate: Learning rate of the Q network (Adam), or a schedule of the progress remaining
    :param actor_learning_rate: Learning rate of the parameter actor, or a schedule
    :param buffer_size: Size of the replay buffer
    :param learning_starts: How many steps of uniformly random actions to collect before learning starts
    :param batch_size: Minibatch size of each gradient step
    :param tau: Polyak coefficient of the Q network's target (1 is a hard copy)
    :param actor_tau: Polyak coefficient of the parameter actor's target
    :param gamma: The discount factor
    :param train_freq: Update the model every ``train_freq`` steps, or a tuple like ``(2, "episode")``
    :param gradient_steps: Gradient steps after each rollout (-1: as many as env steps in the rollout)
    :param replay_buffer_kwargs: Keyword arguments of :class:`~sb3_aac.pdqn.buffers.ParameterizedReplayBuffer`
    :param optimize_memory_usage: The replay buffer's memory-efficient variant (then pass
        ``replay_buffer_kwargs=dict(handle_timeout_termination=False)``)
    :param target_update_interval: Update the target networks every this many gradient steps
    :param exploration_fraction: Fraction of the training period over which epsilon decays
    :param exploration_initial_eps: Initial probability of a uniformly random action type
    :param exploration_final_eps: Final probability of a uniformly random action type
    :param param_noise: ``"ornstein_uhlenbeck"``, ``"gaussian"`` or None: noise on the scaled parameters
    :param param_noise_std: Standard deviation of the noise's Gaussian increments (scaled units)
    :param param_noise_theta: Mean reversion of the Ornstein-Uhlenbeck noise
    :param loss: ``"mse"`` (both papers) or ``"huber"``: the Q network's loss
    :param max_grad_norm: Maximum gradient norm of both networks
    :param info_keywords: Keys of ``info`` read at the step where an episode ends and logged as
        ``rollout/ep_<key>_mean`` (mean over the last ``stats_window_size`` episodes that reported it)
    :param policy_kwargs: Additional arguments of the policy on creation (see :class:`PDQNPolicy`)
    :param stats_window_size: Window size for the rollout logging
    :param tensorboard_log: the log location for tensorboard (if None, no logging)
    :param verbose: Verbosity level: 0 for no output, 1 for info messages, 2 for debug messages
    :param seed: Seed for the pseudo random generators
    :param device: Device (cpu, cuda, ...) on which the code should be run ("auto": cuda if available)
    :param _init_setup_model: Whether or not to build the network at the creation of the instance
    """

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {"MlpPolicy": MlpPolicy}
    policy: PDQNPolicy
    replay_buffer: ParameterizedReplayBuffer  # type: ignore[assignment]
    multi_pass: ClassVar[bool] = False
    """Whether the Q network is MP-DQN's multi-pass one (set by the class, not by the user)."""

    def __init__(
        self,
        policy: str | type[PDQNPolicy],
        env: GymEnv | str | None,
        learning_rate: float | Schedule = 1e-3,
        actor_learning_rate: float | Schedule = 1e-4,
        buffer_size: int = 100_000,
        learning_starts: int = 500,
        batch_size: int = 128,
        tau: float = 0.1,
        actor_tau: float = 0.001,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 1,
        gradient_steps: int = 1,
        replay_buffer_kwargs: dict[str, Any] | None = None,
        optimize_memory_usage: bool = False,
        target_update_interval: int = 1,
        exploration_fraction: float = 0.1,
        exploration_initial_eps: float = 1.0,
        exploration_final_eps: float = 0.01,
        param_noise: str | None = "ornstein_uhlenbeck",
        param_noise_std: float = 0.1,
        param_noise_theta: float = 0.15,
        loss: str = "mse",
        max_grad_norm: float = 10.0,
        info_keywords: tuple[str, ...] = ("distance", "ball_lost"),
        policy_kwargs: dict[str, Any] | None = None,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: th.device | str = "auto",
        _init_setup_model: bool = True,
    ) -> None:
        super().__init__(
            policy,
            env,  # type: ignore[arg-type]
            learning_rate,
            buffer_size,
            learning_starts,
            batch_size,
            tau,
            gamma,
            train_freq,
            gradient_steps,
            replay_buffer_kwargs=replay_buffer_kwargs,
            optimize_memory_usage=optimize_memory_usage,
            policy_kwargs=policy_kwargs,
            stats_window_size=stats_window_size,
            tensorboard_log=tensorboard_log,
            verbose=verbose,
            device=device,
            support_multi_env=True,
            seed=seed,
            sde_support=False,
            # The action space is validated (with a ValueError) when the policy parses it.
            supported_action_spaces=None,
        )
        check_policy_class(self, PDQNPolicy)
        self.actor_learning_rate = actor_learning_rate
        self.actor_tau = actor_tau
        self.target_update_interval = target_update_interval
        self.exploration_fraction = exploration_fraction
        self.exploration_initial_eps = exploration_initial_eps
        self.exploration_final_eps = exploration_final_eps
        self.param_noise = param_noise
        self.param_noise_std = param_noise_std
        self.param_noise_theta = param_noise_theta
        self.loss = loss
        self.max_grad_norm = max_grad_norm
        self._set_info_keywords(info_keywords)
        self.exploration_rate = exploration_initial_eps
        # Saved with the model, so that loading it with the other class fails instead of changing the Q network.
        self.q_network_passes = "multi" if self.multi_pass else "single"
        if _init_setup_model:
            self._setup_model()

    def _check_hyperparameters(self) -> None:
        if self.q_network_passes != ("multi" if self.multi_pass else "single"):
            saved = "MPDQN" if self.q_network_passes == "multi" else "PDQN"
            raise ValueError(f"This model has a {self.q_network_passes}-pass Q network: load it with {saved}.load")
        if self.loss not in LOSSES:
            raise ValueError(f"Unknown loss {self.loss!r}, valid values: {list(LOSSES)}")
        check_unit_interval(self, "gamma", "tau", "actor_tau", "exploration_initial_eps", "exploration_final_eps")
        check_fraction(self, "exploration_fraction")
        check_counts(self, "batch_size", "buffer_size", "target_update_interval")
        check_positive(self, "max_grad_norm")
        check_schedule("actor_learning_rate", self.actor_learning_rate)
        if "multi_pass" in self.policy_kwargs:
            raise ValueError("policy_kwargs cannot set multi_pass: use PDQN (single pass) or MPDQN (multi-pass)")

    def _setup_model(self) -> None:
        self._check_hyperparameters()
        self._setup_lr_schedule()
        self.actor_lr_schedule = FloatSchedule(self.actor_learning_rate)
        self.set_random_seed(self.seed)
        self.policy = self.policy_class(
            self.observation_space,
            self.action_space,
            self.lr_schedule,
            self.actor_lr_schedule,
            multi_pass=self.multi_pass,
            **self.policy_kwargs,
        ).to(self.device)  # type: ignore[assignment]
        # SB3 sets replay_buffer to None before this; the class annotation (no None) is for the training code.
        if self.replay_buffer is None:
            self.replay_buffer = ParameterizedReplayBuffer(  # type: ignore[unreachable]
                self.buffer_size,
                self.observation_space,
                self.action_space,
                device=self.device,
                n_envs=self.n_envs,
                optimize_memory_usage=self.optimize_memory_usage,
                **self.replay_buffer_kwargs,
            )
        self._convert_train_freq()
        self._action_stats = ActionStats(self.policy.spec, value_name="q")
        self._last_dump_timestep = self.num_timesteps
        self.exploration_schedule = LinearSchedule(
            self.exploration_initial_eps, self.exploration_final_eps, self.exploration_fraction
        )
        shape = (self.n_envs, self.policy.spec.n_params)
        self._noise = (
            None
            if self.param_noise is None
            else ParamNoise(self.param_noise, shape, self.param_noise_std, self.param_noise_theta)
        )
        self._reset_keyword_buffers()

    def set_random_seed(self, seed: int | None = None) -> None:
        """Seed python, numpy, torch, the action space, the env, and the algorithm's own generator."""
        super().set_random_seed(seed)
        # Exploration and minibatch draws come from this generator, seeded from the global state
        # when seed is None (set_random_seed repeats runs)
        self._rng = algorithm_generator(seed)

    def _excluded_save_params(self) -> list[str]:
        # Per-run state rebuilt by _setup_model (the generator is re-seeded from `seed`).
        return [*super()._excluded_save_params(), "_rng", "_noise", "_action_stats", "_last_dump_timestep"]

    def _get_torch_save_params(self) -> tuple[list[str], list[str]]:
        return ["policy", "policy.q_optimizer", "policy.actor_optimizer"], []

    # ------------------------------------------------------------------ acting

    def _greedy_numpy(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Greedy types ``(n,)`` and unclipped actor parameters ``(n, n_params)``; raises on non-finite outputs."""
        policy, n_types = self.policy, self.policy.spec.n_types
        with th.inference_mode():
            q, params, k = policy.greedy(policy.features(th.as_tensor(obs, device=self.device)))
            # One transfer: [q, params, k] per row (the type is exact as a float).
            out = th.cat((q, params, k.unsqueeze(1).to(q.dtype)), dim=1).cpu().numpy()
        if not np.isfinite(out).all():
            params_finite = np.isfinite(out[:, n_types:-1]).all()
            self._raise_divergence("the Q network's output" if params_finite else "the parameter actor's output")
        return out[:, -1].astype(np.int64), out[:, n_types:-1].astype(np.float64)

    def _random_types(self, k: np.ndarray, rate: float) -> np.ndarray:
        """``k`` with each entry replaced by a uniformly random type with probability ``rate``."""
        explore = self._rng.random(len(k)) < rate
        if explore.any():
            k[explore] = self._rng.integers(self.policy.spec.n_types, size=int(explore.sum()))
        return k

    def _sample_action(
        self, learning_starts: int, action_noise: ActionNoise | None = None, n_envs: int = 1
    ) -> tuple[np.ndarray, np.ndarray]:
        """Exploratory types ``(n_envs,)`` and scaled parameters ``(n_envs, n_params)`` in ``[-1, 1]``."""
        spec = self.policy.spec
        if self.num_timesteps < learning_starts:
            return self._rng.integers(spec.n_types, size=n_envs), self._rng.uniform(-1.0, 1.0, (n_envs, spec.n_params))
        assert self._last_obs is not None
        k, params = self._greedy_numpy(self._last_obs)  # type: ignore[arg-type]
        k = self._random_types(k, self.exploration_rate)
        if self._noise is not None:
            params += self._noise(self._rng)
        return k, np.clip(params, -1.0, 1.0)

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
        :param deterministic: greedy action if True; otherwise each type is replaced by a uniformly random one with
            probability ``exploration_rate`` (as ``DQN.predict``), the parameters staying the actor's
        :return: one env action (a tuple ``env.step`` accepts) for a single observation, or an object ndarray of
            shape ``(n,)`` of such tuples for a batch; and ``state``
        """
        if deterministic:
            return self.policy.predict(observation, state, episode_start, deterministic=True)
        obs, vectorized = observation_batch(observation, self.observation_space)
        k, params = self._greedy_numpy(obs)
        return self.policy.spec.to_env_predicted(self._random_types(k, self.exploration_rate), params, vectorized), state

    # ------------------------------------------------------------------ collecting

    def _on_step(self) -> None:
        self.exploration_rate = self.exploration_schedule(self._current_progress_remaining)

    def collect_rollouts(  # type: ignore[override]
        self,
        env: VecEnv,
        callback: BaseCallback,
        train_freq: TrainFreq,
        replay_buffer: ParameterizedReplayBuffer,
        action_noise: ActionNoise | None = None,
        learning_starts: int = 0,
        log_interval: int | None = None,
    ) -> RolloutReturn:
        """
        Collect transitions into the replay buffer (see ``OffPolicyAlgorithm.collect_rollouts``), through the array
        path when the env offers it.
        """
        # No set_training_mode here or in train(): the networks have no dropout or batch norm, and the call walks
        # every submodule (8% of a training step).
        if env.num_envs > 1 and train_freq.unit != TrainFrequencyUnit.STEP:
            raise ValueError(f"train_freq in episodes needs one env, got {env.num_envs}: use train_freq in steps")
        arrays, spec = array_path(env), self.policy.spec
        n_steps, n_episodes = 0, 0
        callback.on_rollout_start()
        while should_collect_more_steps(train_freq, n_steps, n_episodes):
            k, params = self._sample_action(learning_starts, None, env.num_envs)
            # Callbacks see the same locals on both paths (sb3_aac.common.array_env).
            actions: Any
            infos: list[dict[str, Any]]
            if arrays is not None:
                actions = (k, params)
                new_obs, rewards, dones, infos = step_as_vec_env(arrays, k, spec.unscale(params))
            else:
                actions = spec.to_env(k, params)
                new_obs, rewards, dones, infos = env.step(actions)  # type: ignore[assignment]
            truncated = np.array([bool(d and i.get("TimeLimit.truncated", False)) for d, i in zip(dones, infos, strict=True)])
            self.num_timesteps += env.num_envs
            n_steps += 1
            check_finite_step(new_obs, rewards, self.num_timesteps)
            self._action_stats.add(k, params)

            callback.update_locals(locals())
            if not callback.on_step():
                return RolloutReturn(n_steps * env.num_envs, n_episodes, continue_training=False)

            next_obs = np.array(new_obs)  # an owned copy (a VecEnv may reuse its buffers)
            ended = np.flatnonzero(dones)
            for i in ended:
                next_obs[i] = infos[i]["terminal_observation"]
            replay_buffer.add(self._last_obs, next_obs, k, params, rewards, dones, truncated)  # type: ignore[arg-type]
            self._last_obs = np.array(new_obs)
            self._update_current_progress_remaining(self.num_timesteps, self._total_timesteps)
            self._on_step()
            if len(ended):
                n_episodes += len(ended)
                self._on_episodes_end(ended, infos, log_interval)
        callback.on_rollout_end()
        return RolloutReturn(n_steps * env.num_envs, n_episodes, continue_training=True)

    def _on_episodes_end(self, ended: np.ndarray, infos: list[dict[str, Any]], log_interval: int | None) -> None:
        """Episode statistics of the envs in ``ended``, from their info dicts."""
        for i in ended:
            maybe_ep_info = infos[i].get("episode")
            if maybe_ep_info is not None:
                self.ep_info_buffer.append(maybe_ep_info)  # type: ignore[union-attr]
            if infos[i].get("is_success") is not None:
                self.ep_success_buffer.append(infos[i]["is_success"])  # type: ignore[union-attr]
            self._add_episode_keywords(infos[i])
            self._episode_num += 1
            if log_interval is not None and self._episode_num % log_interval == 0:
                self.dump_logs()
        if self._noise is not None:
            done = np.zeros(self.n_envs, dtype=bool)
            done[ended] = True
            self._noise.reset(done)

    # ------------------------------------------------------------------ training

    def train(self, gradient_steps: int, batch_size: int = 128) -> None:
        """
        ``gradient_steps`` updates of the Q network and the parameter actor, each followed by the target update; the
        gradients are explicit matrix products (:mod:`sb3_aac.common.mlp_gradients`). The Q step runs each sample
        through its own type's pass only (with MP-DQN, the other passes do not affect ``Q(s, k, x)``).
        """
        policy = self.policy
        progress = self._current_progress_remaining
        q_lr, actor_lr = self.lr_schedule(progress), self.actor_lr_schedule(progress)
        update_learning_rate(policy.q_optimizer, q_lr)
        update_learning_rate(policy.actor_optimizer, actor_lr)
        q_losses, actor_losses, q_values = [], [], []
        with th.no_grad():
            for _ in range(gradient_steps):
                data = self.replay_buffer.sample(batch_size, self._rng)
                features = policy.features(data.observations)
                q_loss, q = self._q_step(data, features)
                actor_losses.append(self._actor_step(features))
                self._n_updates += 1
                if self._n_updates % self.target_update_interval == 0:
                    polyak_update(policy.q_net_params, policy.q_net_target_params, self.tau)
                    polyak_update(policy.actor_params, policy.actor_target_params, self.actor_tau)
                q_losses.append(q_loss)
                q_values.append(q)

        q_loss_values, actor_loss_values = th.stack(q_losses).cpu().numpy(), th.stack(actor_losses).cpu().numpy()
        if not np.isfinite(q_loss_values).all():
            self._raise_divergence("the Q network's loss")
        if not np.isfinite(actor_loss_values).all():
            self._raise_divergence("the parameter actor's loss (-sum_k Q)")
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        self.logger.record("train/learning_rate", q_lr)
        self.logger.record("train/actor_learning_rate", actor_lr)
        self.logger.record("train/critic_loss", float(q_loss_values.mean()))
        self.logger.record("train/actor_loss", float(actor_loss_values.mean()))
        self._action_stats.add_values(th.cat(q_values).cpu().numpy())

    def _q_step(self, data: ParameterizedReplayBufferSamples, features: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        """The Q network's step on a minibatch; returns its loss and ``Q(s, k, x)`` ``(n,)`` before the step."""
        policy, q_net = self.policy, self.policy.q_net
        next_features = policy.features(data.next_observations)
        next_params = policy.actor_target(next_features)
        if policy.param_bounding == "invert_gradients":  # the env receives clipped parameters
            next_params = next_params.clamp(-1.0, 1.0)
        next_q = policy.q_net_target(next_features, next_params).max(1).values
        target = data.rewards + (1.0 - data.dones) * self.gamma * next_q

        types = data.action_types.unsqueeze(1)
        outputs, saved = mlp_gradients.forward(q_net.net, q_net.chosen_inputs(features, data.params, data.action_types))
        q = outputs.gather(1, types).squeeze(1)
        loss, q_grad = LOSSES[self.loss](q, target)
        output_grads = th.zeros_like(outputs).scatter_(1, types, q_grad.unsqueeze(1))
        self._step(policy.q_optimizer, policy.q_net_params, mlp_gradients.backward(q_net.net, saved, output_grads)[0])
        return loss, q

    def _actor_step(self, features: th.Tensor) -> th.Tensor:
        """The parameter actor's step, ascending ``sum_k Q(s, k, x(s))``; returns its loss ``-mean_s sum_k Q``."""
        policy, q_net, actor = self.policy, self.policy.q_net, self.policy.actor
        mlp_outputs, actor_saved = mlp_gradients.forward(actor.net, features)
        params = actor.bound(mlp_outputs)
        outputs, saved = mlp_gradients.forward(q_net.net, q_net.pass_inputs(features, params))
        loss = -q_net.values(outputs).sum(1).mean()
        value_grads = th.full((len(features), q_net.n_types), -1.0 / len(features), device=features.device)
        _, input_grads = mlp_gradients.backward(q_net.net, saved, q_net.output_grads(value_grads), weights=False)
        descent = q_net.param_grads(input_grads, features.shape[1])  # d loss / dx = -dQ/dx
        if policy.param_bounding == "invert_gradients":
            descent = -invert_gradients(-descent, params)
        actor_grads, _ = mlp_gradients.backward(actor.net, actor_saved, actor.mlp_output_grads(descent, params))
        self._step(policy.actor_optimizer, policy.actor_params, actor_grads)
        return loss

    def _step(self, optimizer: th.optim.Optimizer, params: Sequence[th.Tensor], grads: Sequence[th.Tensor]) -> None:
        """One optimizer step of ``params`` along ``grads``, their joint norm clipped to ``max_grad_norm``."""
        clip_grad_norm(grads, self.max_grad_norm)
        set_grads(params, grads)
        optimizer.step()

    def _raise_divergence(self, what: str) -> None:
        remedy = (
            f"Lower the learning rates (learning_rate={self.learning_rate}, actor_learning_rate={self.actor_learning_rate}) "
            f"or max_grad_norm ({self.max_grad_norm}), or rescale the rewards"
        )
        raise divergence_error(type(self).__name__, what, self.num_timesteps, remedy)

    # ------------------------------------------------------------------ logging

    def dump_logs(self) -> None:
        """
        Write log data: SB3's off-policy ``rollout/`` and ``time/`` keys, the info keywords, epsilon, and the
        executed actions' type shares and per-type parameter statistics, and the Q values of the training batches
        (:class:`~sb3_aac.common.action_stats.ActionStats`, value name ``q``) since the last dump.
        """
        self._record_keyword_means()
        self.logger.record("rollout/exploration_rate", self.exploration_rate)
        self._action_stats.record(self.logger)
        super().dump_logs()
        self._last_dump_timestep = self.num_timesteps

    def learn(
        self: SelfPDQN,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int | None = 4,
        tb_log_name: str = "PDQN",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> SelfPDQN:
        """SB3's off-policy ``learn``, with a last log dump at the end (of what was logged since the previous one)."""
        super().learn(
            total_timesteps=total_timesteps,
            callback=callback,
            log_interval=log_interval,  # type: ignore[arg-type]
            tb_log_name=tb_log_name,
            reset_num_timesteps=reset_num_timesteps,
            progress_bar=progress_bar,
        )
        if log_interval is not None and self.num_timesteps > self._last_dump_timestep:
            self.dump_logs()
        return self

    # ------------------------------------------------------------------ persistence

    def load_replay_buffer(self, path: str | pathlib.Path | io.BufferedIOBase, truncate_last_traj: bool = True) -> None:
        """
        Load a replay buffer saved by :meth:`save_replay_buffer`.

        :param path: Path to the pickled replay buffer
        :param truncate_last_traj: Unused (SB3 uses it for ``HerReplayBuffer`` only)
        :raises ValueError: if the file holds no :class:`ParameterizedReplayBuffer`, or one filled in other spaces or
            with another number of environments; the model's buffer is then left as it was
        """
        buffer = load_from_pkl(path, self.verbose)
        if not isinstance(buffer, ParameterizedReplayBuffer):
            raise ValueError(f"{path} holds a {type(buffer).__name__}, not a ParameterizedReplayBuffer")
        buffer.check_spaces(self.observation_space, self.action_space, self.n_envs)
        buffer.device = self.device
        self.replay_buffer = buffer


class MPDQN(PDQN):
    """
    Multi-Pass Deep Q-Network (MP-DQN): P-DQN whose Q network evaluates each action type in its own pass, with the
    other types' parameters zeroed, so that ``Q_k`` depends only on ``s`` and type ``k``'s parameters (no false
    gradients from the other types' parameters into the actor).

    Paper: C. J. Bester, S. D. James, G. D. Konidaris, "Multi-Pass Q-Networks for Deep Reinforcement Learning with
    Parameterised Action Spaces", 2019, https://arxiv.org/abs/1905.04388

    Everything else, including the arguments, is :class:`PDQN`'s.
    """

    multi_pass: ClassVar[bool] = True

    def learn(
        self: SelfPDQN,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int | None = 4,
        tb_log_name: str = "MPDQN",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> SelfPDQN:
        return super().learn(total_timesteps, callback, log_interval, tb_log_name, reset_num_timesteps, progress_bar)
