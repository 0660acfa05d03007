from __future__ import annotations

import math
from typing import Any, ClassVar, TypeVar

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, Schedule
from stable_baselines3.common.utils import FloatSchedule, explained_variance, obs_as_tensor
from stable_baselines3.common.vec_env import VecEnv
from torch.nn import functional as F

from sb3_aac.common.action_stats import ActionStats
from sb3_aac.common.array_env import array_path, step_as_vec_env
from sb3_aac.common.divergence import divergence_error
from sb3_aac.common.episode_stats import EpisodeStatsMixin
from sb3_aac.common.guards import GuardedAlgorithmMixin, check_finite_step, check_schedule
from sb3_aac.common.hyperparameters import check_counts, check_finite, check_positive, check_unit_interval
from sb3_aac.common.model_files import check_policy_class
from sb3_aac.hppo.acting import RolloutActor
from sb3_aac.hppo.buffers import HybridRolloutBuffer
from sb3_aac.hppo.distributions import sample_packed
from sb3_aac.hppo.policies import HybridActorCriticPolicy, MlpPolicy

SelfHybridPPO = TypeVar("SelfHybridPPO", bound="HybridPPO")
EVALUATION_ROWS = 16_384  # rows of one batched pass over a rollout (bounds its activations' memory)


def clipped_surrogate(advantages: th.Tensor, log_ratio: th.Tensor, clip_range: float) -> tuple[th.Tensor, th.Tensor]:
    """PPO's clipped surrogate loss ``-E[min(r A, clip(r, 1 - eps, 1 + eps) A)]`` and the fraction of clipped ratios."""
    ratio = th.exp(log_ratio)
    loss = -th.min(advantages * ratio, advantages * th.clamp(ratio, 1 - clip_range, 1 + clip_range)).mean()
    return loss, ((ratio - 1).abs() > clip_range).float().mean()


class HybridPPO(GuardedAlgorithmMixin, EpisodeStatsMixin, OnPolicyAlgorithm):
    """
    Hybrid Proximal Policy Optimization (H-PPO) for parameterized actions: pick one of K action types and its
    parameters.

    Paper: Z. Fan, R. Su, W. Zhang, Y. Yu, "Hybrid Actor-Critic Reinforcement Learning in Parameterized Action Space",
    IJCAI 2019, https://arxiv.org/abs/1903.01344

    A discrete actor ``p(k|s)``, a parameter actor (a Gaussian per type over that type's parameters, learned
    state-independent standard deviations) and a critic ``V(s)`` (see :class:`~sb3_aac.hppo.policies.HybridActorCriticPolicy`).
    Rollouts are collected as by SB3's PPO (GAE, time-limit truncations bootstrapped from ``V`` of the terminal
    observation); each actor is then updated with its own clipped surrogate on the same advantages, as in the paper:

    - discrete: ratio ``p(k|s) / p_old(k|s)``, clipped to ``1 +- clip_range``;
    - parameters: ratio ``N(x_k; mu_k(s)) / N_old(x_k; mu_k(s))`` over the chosen type's parameters only, clipped
      to ``1 +- clip_range_params``;

    and the loss ``L_discrete + L_params - ent_coef * H(k) - param_ent_coef * sum_k p(k) H(N_k) + vf_coef * L_V`` takes
    ``n_epochs`` passes of Adam over minibatches (one optimizer: with separate networks the parts' gradients do not
    mix). ``target_kl`` stops the epochs early on the KL estimate of the joint ratio. The executed parameters are the
    Gaussian samples clipped to the bounds (see :class:`~sb3_aac.hppo.distributions.HybridDistribution`). Envs offering
    the array path (:func:`sb3_aac.common.array_env.array_path`) are stepped with arrays; callbacks see the same locals
    on both paths (``infos`` with one dict per lane; ``actions`` the env actions, or ``(k, params)`` on the array path,
    as :mod:`sb3_aac.common.array_env` documents), plus ``k`` and ``params`` (the executed type and clipped scaled
    parameters) and ``packed`` (the sampled ``[k, x]`` rows).

    Training stops with a ``FloatingPointError`` naming the part (the policy's output, the discrete or parameter
    policy loss, the value loss, or a network's gradients) as soon as one becomes non-finite, before the optimizer
    step: the weights stay the last finite ones.

    :param policy: The policy model to use (MlpPolicy, or a HybridActorCriticPolicy subclass)
    :param env: The environment to learn from (if registered in Gym, can be str)
    :param learning_rate: The learning rate, or a schedule of the progress remaining (from 1 to 0)
    :param n_steps: Steps per env of each rollout (the rollout holds ``n_steps * n_envs`` transitions)
    :param batch_size: Minibatch size
    :param n_epochs: Passes over each rollout
    :param gamma: The discount factor
    :param gae_lambda: GAE's bias-variance trade-off (1: Monte-Carlo advantages)
    :param clip_range: Clipping of the discrete actor's ratio, or a schedule
    :param clip_range_params: Clipping of the parameter actor's ratio, or a schedule (None: ``clip_range``)
    :param clip_range_vf: Clipping of the value function's change (None: no clipping), or a schedule; in the units
        of the rewards
    :param normalize_advantage: Normalise the advantages per minibatch
    :param ent_coef: Coefficient of the type entropy bonus
    :param param_ent_coef: Coefficient of the parameter entropy bonus (type-weighted, see above)
    :param vf_coef: Coefficient of the value loss
    :param max_grad_norm: Maximum norm of the gradient of the loss (over all networks)
    :param target_kl: Stop the epochs of an update when the approximate KL divergence exceeds 1.5 times this (None:
        no limit)
    :param info_keywords: Keys of ``info`` read at the step where an episode ends and logged as
        ``rollout/ep_<key>_mean`` (mean over the last ``stats_window_size`` episodes that reported it)
    :param stats_window_size: Window size for the rollout logging
    :param tensorboard_log: the log location for tensorboard (if None, no logging)
    :param policy_kwargs: Additional arguments of the policy on creation (see :class:`HybridActorCriticPolicy`)
    :param verbose: Verbosity level: 0 for no output, 1 for info messages, 2 for debug messages
    :param seed: Seed for the pseudo random generators
    :param device: Device (cpu, cuda, ...) on which the code should be run ("auto": cuda if available)
    :param _init_setup_model: Whether or not to build the network at the creation of the instance
    """

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {"MlpPolicy": MlpPolicy}
    policy: HybridActorCriticPolicy  # type: ignore[assignment]
    rollout_buffer: HybridRolloutBuffer

    def __init__(
        self,
        policy: str | type[HybridActorCriticPolicy],
        env: GymEnv | str | None,
        learning_rate: float | Schedule = 3e-4,
        n_steps: int = 2048,
        batch_size: int = 64,
        n_epochs: int = 10,
        gamma: float = 0.99,
        gae_lambda: float = 0.95,
        clip_range: float | Schedule = 0.2,
        clip_range_params: float | Schedule | None = None,
        clip_range_vf: float | Schedule | None = None,
        normalize_advantage: bool = True,
        ent_coef: float = 0.0,
        param_ent_coef: float = 0.0,
        vf_coef: float = 0.5,
        max_grad_norm: float = 0.5,
        target_kl: float | None = None,
        info_keywords: tuple[str, ...] = ("distance", "ball_lost"),
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: th.device | str = "auto",
        _init_setup_model: bool = True,
    ):
        super().__init__(
            policy,  # type: ignore[arg-type]
            env,  # type: ignore[arg-type]
            learning_rate=learning_rate,
            n_steps=n_steps,
            gamma=gamma,
            gae_lambda=gae_lambda,
            ent_coef=ent_coef,
            vf_coef=vf_coef,
            max_grad_norm=max_grad_norm,
            use_sde=False,
            sde_sample_freq=-1,
            stats_window_size=stats_window_size,
            tensorboard_log=tensorboard_log,
            policy_kwargs=policy_kwargs,
            verbose=verbose,
            device=device,
            seed=seed,
            _init_setup_model=False,
            # The action space is validated (with a ValueError saying what is supported) when the policy parses it.
            supported_action_spaces=None,
        )
        check_policy_class(self, HybridActorCriticPolicy)
        self.batch_size = batch_size
        self.n_epochs = n_epochs
        self.clip_range = clip_range
        self.clip_range_params = clip_range_params
        self.clip_range_vf = clip_range_vf
        self.normalize_advantage = normalize_advantage
        self.param_ent_coef = param_ent_coef
        self.target_kl = target_kl
        self._set_info_keywords(info_keywords)
        if _init_setup_model:
            self._setup_model()

    def _check_hyperparameters(self) -> None:
        check_counts(self, "n_steps", "batch_size", "n_epochs")
        check_unit_interval(self, "gamma", "gae_lambda")
        for name in ("clip_range", "clip_range_params", "clip_range_vf"):
            value = getattr(self, name)
            check_schedule(name, value, allow_none=name != "clip_range")
            if isinstance(value, (int, float)) and not value > 0:
                raise ValueError(f"{name} must be > 0 (or a schedule; None for the default), got {value}")
        check_finite(self, "ent_coef", "param_ent_coef", "vf_coef")
        check_positive(self, "max_grad_norm")
        if self.target_kl is not None and not self.target_kl > 0:
            raise ValueError(f"target_kl must be > 0 or None, got {self.target_kl}")
        if self.normalize_advantage and (self.batch_size < 2 or self.n_steps * self.n_envs < 2):
            raise ValueError(
                "normalize_advantage needs batch_size >= 2 and n_steps * n_envs >= 2 (the advantages' standard deviation), "
                f"got batch_size={self.batch_size}, n_steps={self.n_steps}, n_envs={self.n_envs}"
            )

    def _setup_model(self) -> None:
        self._check_hyperparameters()
        self._setup_lr_schedule()
        self.set_random_seed(self.seed)
        self.policy = self.policy_class(  # type: ignore[assignment]
            self.observation_space, self.action_space, self.lr_schedule, **self.policy_kwargs
        )
        self.policy = self.policy.to(self.device)
        self.rollout_buffer = HybridRolloutBuffer(
            self.n_steps,
            self.observation_space,
            self.policy.spec.n_params,
            device=self.device,
            gamma=self.gamma,
            gae_lambda=self.gae_lambda,
            n_envs=self.n_envs,
        )
        self.clip_range_schedule = FloatSchedule(self.clip_range)
        self.clip_range_params_schedule = FloatSchedule(
            self.clip_range if self.clip_range_params is None else self.clip_range_params
        )
        self.clip_range_vf_schedule = None if self.clip_range_vf is None else FloatSchedule(self.clip_range_vf)
        self._action_stats = ActionStats(self.policy.spec, value_name="value")
        self._reset_keyword_buffers()

    def _excluded_save_params(self) -> list[str]:
        # The schedules are rebuilt by _setup_model from the saved clip_range* values.
        return [
            *super()._excluded_save_params(),
            "_action_stats",
            "clip_range_schedule",
            "clip_range_params_schedule",
            "clip_range_vf_schedule",
        ]

    # ------------------------------------------------------------------ collecting

    def collect_rollouts(  # type: ignore[override]
        self,
        env: VecEnv,
        callback: BaseCallback,
        rollout_buffer: HybridRolloutBuffer,
        n_rollout_steps: int,
    ) -> bool:
        """
        Fill ``rollout_buffer`` with ``n_rollout_steps`` steps of every env (see ``OnPolicyAlgorithm.collect_rollouts``),
        through the array path when the env offers it. The actors act through a :class:`~sb3_aac.hppo.acting.RolloutActor`
        on the rollout's noise, drawn from torch's generator at its start; the values and log-probabilities of its
        steps come from one batched pass of the policy at its end (:meth:`_evaluate_rollout`).
        """
        assert self._last_obs is not None, "No previous observation was provided"
        self.policy.set_training_mode(False)
        arrays, spec = array_path(env), self.policy.spec
        actor = RolloutActor(self.policy)
        std = self.policy.log_std.detach().exp().cpu().numpy()  # fixed within a rollout
        exponential = th.empty((n_rollout_steps, env.num_envs, spec.n_types)).exponential_().numpy()
        normal = th.randn((n_rollout_steps, env.num_envs, spec.n_params)).numpy()
        n_steps = 0
        rollout_buffer.reset()
        callback.on_rollout_start()
        while n_steps < n_rollout_steps:
            type_logits, mean = actor(self._last_obs)  # type: ignore[arg-type]
            if not np.isfinite(type_logits).all():
                self._raise_divergence("the policy's output (the type logits)")
            packed = sample_packed(type_logits, mean, std, exponential[n_steps], normal[n_steps])
            if not np.isfinite(packed).all():
                self._raise_divergence("the policy's output (the parameter means or standard deviations)")
            k, params = packed[:, 0].astype(np.int64), np.clip(packed[:, 1:], -1.0, 1.0)
            # Callbacks see the same locals on both paths (sb3_aac.common.array_env).
            actions: Any
            infos: list[dict[str, Any]]
            if arrays is not None:
                actions = (k, params)
                new_obs, rewards, dones, infos = step_as_vec_env(arrays, k, spec.unscale(params))
                rewards = np.array(rewards, dtype=np.float32)  # an owned copy: truncated lanes get the bootstrap added
            else:
                actions = spec.to_env(k, params)
                new_obs, rewards, dones, infos = env.step(actions)  # type: ignore[assignment]
            self.num_timesteps += env.num_envs
            check_finite_step(new_obs, rewards, self.num_timesteps)
            callback.update_locals(locals())
            if not callback.on_step():
                # The executed actions' statistics: the buffer's steps and this one (which no update learns from).
                self._evaluate_rollout(rollout_buffer)
                self._add_action_stats(rollout_buffer)
                with th.no_grad():
                    values = self.policy.predict_values(obs_as_tensor(self._last_obs, self.device))
                self._action_stats.add(k, params, values.cpu().numpy())
                return False
            if dones.any():
                self._on_episodes_end(dones, infos)
                self._bootstrap_truncated(rewards, dones, infos)
            n_steps += 1
            rollout_buffer.add(self._last_obs, packed, rewards, self._last_episode_starts)  # type: ignore[arg-type]
            self._last_obs = new_obs
            self._last_episode_starts = dones
        self._evaluate_rollout(rollout_buffer)
        self._add_action_stats(rollout_buffer)
        with th.no_grad():
            values = self.policy.predict_values(obs_as_tensor(new_obs, self.device))
        rollout_buffer.compute_returns_and_advantage(last_values=values, dones=dones)
        callback.update_locals(locals())
        callback.on_rollout_end()
        return True

    def _evaluate_rollout(self, rollout_buffer: HybridRolloutBuffer) -> None:
        """The values and both log-probabilities of the buffer's steps under the policy that collected them, in batched
        passes of :meth:`HybridActorCriticPolicy.evaluate_actions` (the arithmetic the update then runs) of at most
        ``EVALUATION_ROWS`` rows."""
        rows = rollout_buffer.pos * rollout_buffer.n_envs
        obs = rollout_buffer.observations[: rollout_buffer.pos].reshape(rows, *rollout_buffer.obs_shape)
        actions = rollout_buffer.actions[: rollout_buffer.pos].reshape(rows, rollout_buffer.action_dim)
        parts: list[list[np.ndarray]] = [[], [], []]
        for start in range(0, rows, EVALUATION_ROWS):
            chunk = slice(start, start + EVALUATION_ROWS)
            with th.no_grad():
                evaluated = self.policy.evaluate_actions(
                    rollout_buffer.to_torch(obs[chunk]), rollout_buffer.to_torch(actions[chunk])
                )
            for part, tensor in zip(parts, evaluated[:3], strict=True):
                part.append(tensor.cpu().numpy())
        if rows:
            rollout_buffer.set_evaluations(*(np.concatenate(part) for part in parts))

    def _add_action_stats(self, rollout_buffer: HybridRolloutBuffer) -> None:
        """The executed types, clipped parameters and values of the steps in ``rollout_buffer`` (one call per rollout)."""
        actions = rollout_buffer.actions[: rollout_buffer.pos].reshape(-1, rollout_buffer.action_dim)
        values = rollout_buffer.values[: rollout_buffer.pos].ravel()
        self._action_stats.add(actions[:, 0].astype(np.int64), np.clip(actions[:, 1:], -1.0, 1.0), values)

    def _bootstrap_truncated(self, rewards: np.ndarray, dones: np.ndarray, infos: list[dict[str, Any]]) -> None:
        """Add ``gamma * V(terminal observation)`` to the rewards of lanes cut by a time limit (as SB3 does, https://github.com/DLR-RM/stable-baselines3/issues/633)."""
        lanes = [
            i
            for i in np.flatnonzero(dones)
            if infos[i].get("terminal_observation") is not None and infos[i].get("TimeLimit.truncated", False)
        ]
        if not lanes:
            return
        terminal = np.stack([infos[i]["terminal_observation"] for i in lanes])
        with th.no_grad():
            terminal_values = self.policy.predict_values(obs_as_tensor(terminal, self.device)).cpu().numpy()
        rewards[lanes] += self.gamma * terminal_values

    def _on_episodes_end(self, dones: np.ndarray, infos: list[dict[str, Any]]) -> None:
        """Episode statistics (SB3's Monitor ``episode``, ``is_success`` and the ``info_keywords``) of ended lanes."""
        self._update_info_buffer(infos, dones)
        for i in np.flatnonzero(dones):
            self._add_episode_keywords(infos[i])
            self._episode_num += 1

    def dump_logs(self, iteration: int = 0) -> None:
        """
        Write log data: SB3's on-policy ``rollout/`` and ``time/`` keys, the info keywords, and the executed actions'
        type shares and per-type parameter statistics and the critic's values since the last dump
        (:class:`~sb3_aac.common.action_stats.ActionStats`).
        """
        self._record_keyword_means()
        self._action_stats.record(self.logger)
        super().dump_logs(iteration)

    # ------------------------------------------------------------------ training

    def train(self) -> None:
        """``n_epochs`` passes over the rollout: both actors' clipped surrogates, the entropy bonuses, the value loss."""
        policy = self.policy
        policy.set_training_mode(True)
        self._update_learning_rate(policy.optimizer)
        progress = self._current_progress_remaining
        clip_type, clip_params = self.clip_range_schedule(progress), self.clip_range_params_schedule(progress)
        clip_vf = None if self.clip_range_vf_schedule is None else self.clip_range_vf_schedule(progress)

        stats: dict[str, list[float]] = {
            key: []
            for key in (
                "policy_loss_discrete",
                "policy_loss_params",
                "clip_fraction_discrete",
                "clip_fraction_params",
                "entropy_discrete",
                "entropy_params",
                "value_loss",
            )
        }
        approx_kl_divs: list[float] = []
        continue_training = True
        for epoch in range(self.n_epochs):
            approx_kl_divs = []
            for data in self.rollout_buffer.get(self.batch_size):
                values, type_log_prob, param_log_prob, type_entropy, param_entropy = policy.evaluate_actions(
                    data.observations, data.actions
                )
                advantages = data.advantages
                if self.normalize_advantage and len(advantages) > 1:
                    advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
                type_log_ratio = type_log_prob - data.old_type_log_prob
                param_log_ratio = param_log_prob - data.old_param_log_prob
                loss_discrete, clipped_discrete = clipped_surrogate(advantages, type_log_ratio, clip_type)
                loss_params, clipped_params = clipped_surrogate(advantages, param_log_ratio, clip_params)
                if clip_vf is not None:
                    values = data.old_values + th.clamp(values - data.old_values, -clip_vf, clip_vf)
                value_loss = F.mse_loss(data.returns, values)
                entropy_discrete, entropy_params = type_entropy.mean(), param_entropy.mean()
                loss = (
                    loss_discrete
                    + loss_params
                    - self.ent_coef * entropy_discrete
                    - self.param_ent_coef * entropy_params
                    + self.vf_coef * value_loss
                )
                values_now = {
                    "policy_loss_discrete": loss_discrete.item(),
                    "policy_loss_params": loss_params.item(),
                    "clip_fraction_discrete": clipped_discrete.item(),
                    "clip_fraction_params": clipped_params.item(),
                    "entropy_discrete": entropy_discrete.item(),
                    "entropy_params": entropy_params.item(),
                    "value_loss": value_loss.item(),
                }
                self._check_losses(values_now)
                for key, value in values_now.items():
                    stats[key].append(value)

                with th.no_grad():
                    log_ratio = type_log_ratio + param_log_ratio
                    approx_kl_div = th.mean(th.exp(log_ratio) - 1 - log_ratio).item()
                    approx_kl_divs.append(approx_kl_div)
                if self.target_kl is not None and approx_kl_div > 1.5 * self.target_kl:
                    continue_training = False
                    if self.verbose >= 1:
                        print(f"Early stopping at step {epoch} due to reaching max kl: {approx_kl_div:.2f}")
                    break

                policy.optimizer.zero_grad()
                loss.backward()  # type: ignore[no-untyped-call]
                grad_norm = th.nn.utils.clip_grad_norm_(policy.parameters(), self.max_grad_norm)
                if not th.isfinite(grad_norm):
                    self._raise_gradient_divergence()
                policy.optimizer.step()
            self._n_updates += 1
            if not continue_training:
                break

        explained_var = explained_variance(self.rollout_buffer.values.flatten(), self.rollout_buffer.returns.flatten())
        for key, values_list in stats.items():
            if values_list:
                self.logger.record(f"train/{key}", float(np.mean(values_list)))
        if approx_kl_divs:
            self.logger.record("train/approx_kl", float(np.mean(approx_kl_divs)))
        self.logger.record("train/loss", loss.item())
        self.logger.record("train/explained_variance", float(explained_var))
        self.logger.record("train/std", th.exp(policy.log_std).mean().item())
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        self.logger.record("train/clip_range", clip_type)
        self.logger.record("train/clip_range_params", clip_params)
        if clip_vf is not None:
            self.logger.record("train/clip_range_vf", clip_vf)

    def _check_losses(self, losses: dict[str, float]) -> None:
        # The value loss first: a non-finite reward reaches the returns (value loss) and the advantages (policy losses).
        parts = {
            "value_loss": "the value loss",
            "policy_loss_discrete": "the discrete policy loss",
            "policy_loss_params": "the parameter policy loss",
            "entropy_params": "the parameter entropy (log-std)",
        }
        for key, what in parts.items():
            if not math.isfinite(losses[key]):
                self._raise_divergence(what)

    def _raise_gradient_divergence(self) -> None:
        policy = self.policy
        for what, parameters in (
            ("the policy's", policy.actor_parameters()),
            ("the value function's", policy.critic_parameters()),
        ):
            if any(p.grad is not None and not th.isfinite(p.grad).all() for p in parameters):
                self._raise_divergence(f"{what} gradients")
        self._raise_divergence("the features extractor's gradients")

    def _raise_divergence(self, what: str) -> None:
        remedy = (
            f"Lower the learning rate (learning_rate={self.learning_rate}) or max_grad_norm ({self.max_grad_norm}), "
            "or rescale the rewards"
        )
        raise divergence_error(type(self).__name__, what, self.num_timesteps, remedy, "the weights are the last finite ones")

    def learn(
        self: SelfHybridPPO,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int | None = 1,
        tb_log_name: str = "HybridPPO",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> SelfHybridPPO:
        """
        SB3's on-policy ``learn``: collect a rollout of ``n_steps`` per env, update on it, until ``total_timesteps``
        (so ``num_timesteps`` ends at the first multiple of ``n_steps * n_envs`` at or beyond it, unless a callback
        stops the run). Each log dump (every ``log_interval`` rollouts; None: never) follows the update, so its
        ``train/`` keys are of the update on the rollout its ``rollout/`` keys describe; the run ends with a dump of
        what was logged since the previous one.
        """
        total_timesteps, callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar
        )
        callback.on_training_start(locals(), globals())
        assert self.env is not None
        iteration, dumped = 0, True
        while self.num_timesteps < total_timesteps:
            dumped = False
            if not self.collect_rollouts(self.env, callback, self.rollout_buffer, n_rollout_steps=self.n_steps):
                break
            iteration += 1
            self._update_current_progress_remaining(self.num_timesteps, total_timesteps)
            self.train()
            if log_interval is not None and iteration % log_interval == 0:
                self.dump_logs(iteration)
                dumped = True
        if log_interval is not None and not dumped:
            self.dump_logs(iteration)
        callback.on_training_end()
        return self
