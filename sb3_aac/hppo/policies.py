from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor, create_mlp
from stable_baselines3.common.type_aliases import PyTorchObs, Schedule
from torch import nn

from sb3_aac.common.observations import check_box_observation_space, observation_batch
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.common.layer_calls import run_layers
from sb3_aac.common.updates import make_optimizer
from sb3_aac.hppo.torch_layers import BoundsScaledFlatten
from sb3_aac.hppo.distributions import HybridDistribution

NET_ARCH_KEYS = ("shared", "type", "params", "vf")
DEFAULT_HIDDEN = [64, 64]  # SB3's PPO MlpPolicy default, for each of the three networks


def parse_action_space(action_space: spaces.Space[Any]) -> ParameterizedActionSpec:
    """The space's spec, or a ``ValueError`` saying what HybridPPO supports."""
    try:
        return ParameterizedActionSpec.from_space(action_space)
    except ValueError as error:
        raise ValueError(
            f"HybridPPO cannot act in this action space: {error} HybridPPO needs a discrete part of K >= 1 action "
            "types with parameters in Boxes of finite bounds: it samples Gaussian parameters and clips them to the "
            "bounds (there is no squashing for unbounded parameters). A space without a discrete part (a plain Box) is "
            "for SB3's PPO."
        ) from None


def _net_arch(net_arch: list[int] | dict[str, list[int]] | None) -> dict[str, list[int]]:
    """``net_arch`` as hidden sizes per network: ``shared`` (first layers of both actors), ``type``, ``params``, ``vf``."""
    if net_arch is None:
        return {"shared": [], "type": DEFAULT_HIDDEN, "params": DEFAULT_HIDDEN, "vf": DEFAULT_HIDDEN}
    if isinstance(net_arch, dict):
        unknown = set(net_arch) - set(NET_ARCH_KEYS)
        if unknown:
            raise ValueError(f"Unknown net_arch keys {sorted(unknown)}, valid keys: {list(NET_ARCH_KEYS)}")
        arch = {key: list(net_arch.get(key, [] if key == "shared" else DEFAULT_HIDDEN)) for key in NET_ARCH_KEYS}
    elif isinstance(net_arch, (list, tuple)):
        arch = {"shared": [], "type": list(net_arch), "params": list(net_arch), "vf": list(net_arch)}
    else:
        raise ValueError(f"net_arch must be a list of layer sizes or a dict with keys {list(NET_ARCH_KEYS)}, got {net_arch!r}")
    for key, sizes in arch.items():
        if not all(isinstance(size, int) and size >= 1 for size in sizes):  # type: ignore[redundant-expr]
            raise ValueError(f"net_arch[{key!r}] must hold integer layer sizes >= 1, got {sizes}")
    return arch


def _mlp(n_inputs: int, sizes: list[int], activation_fn: type[nn.Module]) -> tuple[nn.Sequential, int]:
    """Hidden layers (no output layer) and their output width (``n_inputs`` if there are none)."""
    return nn.Sequential(*create_mlp(n_inputs, -1, sizes, activation_fn)), sizes[-1] if sizes else n_inputs


class HybridActorCriticPolicy(BasePolicy):
    """
    Policy of H-PPO (Fan et al. 2019): a discrete actor (type logits), a parameter actor (every type's parameter
    means, scaled to ``[-1, 1]``, plus state-independent log standard deviations) and a critic ``V(s)``, on one
    features extractor. The two actors may share their first layers (``net_arch["shared"]``); the critic has its own.
    The action distribution is :class:`~sb3_aac.hppo.distributions.HybridDistribution`.

    ``predict`` returns env actions: the sampled (or, with ``deterministic=True``, the most probable) type and its
    parameters, clipped to the bounds; the nested and flat layouts also carry the other types' parameters.

    :param observation_space: The observation space (a ``Box``, as for every policy of this package)
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param lr_schedule: Learning rate schedule (of the one optimizer over all networks)
    :param net_arch: Hidden layer sizes: a list (each of the discrete actor, the parameter actor and the critic gets
        these layers) or a dict with the keys ``shared`` (first layers of both actors, default none), ``type``,
        ``params`` and ``vf`` (default ``[64, 64]`` each, SB3's PPO default)
    :param activation_fn: Hidden activation (SB3's PPO default, tanh)
    :param ortho_init: Orthogonal initialisation as SB3's PPO (gain sqrt(2) for hidden layers, 0.01 for the actors'
        outputs, 1 for the value)
    :param log_std_init: Initial log standard deviation of every parameter (scaled units: 0 means sigma = 1, half the
        range)
    :param features_extractor_class: Features extractor (default :class:`~sb3_aac.hppo.torch_layers.BoundsScaledFlatten`:
        a Box observation flattened and scaled to ``[-1, 1]`` where its bounds are finite)
    :param features_extractor_kwargs: Keyword arguments of the features extractor
    :param normalize_images: Whether to divide image observations by 255 (SB3's preprocessing)
    :param optimizer_class: The optimizer
    :param optimizer_kwargs: Extra arguments of the optimizer (SB3's PPO default: Adam with ``eps=1e-5``)
    """

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        lr_schedule: Schedule,
        net_arch: list[int] | dict[str, list[int]] | None = None,
        activation_fn: type[nn.Module] = nn.Tanh,
        ortho_init: bool = True,
        log_std_init: float = 0.0,
        features_extractor_class: type[BaseFeaturesExtractor] = BoundsScaledFlatten,
        features_extractor_kwargs: dict[str, Any] | None = None,
        normalize_images: bool = True,
        optimizer_class: type[th.optim.Optimizer] = th.optim.Adam,
        optimizer_kwargs: dict[str, Any] | None = None,
    ):
        if optimizer_kwargs is None:
            optimizer_kwargs = {"eps": 1e-5} if optimizer_class == th.optim.Adam else {}
        check_box_observation_space(observation_space, "HybridPPO policies")
        if isinstance(log_std_init, bool) or not isinstance(log_std_init, (int, float)) or not math.isfinite(log_std_init):  # type: ignore[redundant-expr]
            raise ValueError(f"log_std_init must be a finite number (0: sigma = 1, half the range), got {log_std_init!r}")
        self.spec = parse_action_space(action_space)
        super().__init__(
            observation_space,
            action_space,
            features_extractor_class,
            features_extractor_kwargs,
            normalize_images=normalize_images,
            optimizer_class=optimizer_class,
            optimizer_kwargs=optimizer_kwargs,
        )
        self.net_arch = net_arch
        self.arch = _net_arch(net_arch)
        self.activation_fn, self.ortho_init, self.log_std_init = activation_fn, ortho_init, log_std_init
        self.action_dist = HybridDistribution(self.spec.param_type, self.spec.n_types)
        self._build(lr_schedule)

    def _build(self, lr_schedule: Schedule) -> None:
        self.features_extractor = self.make_features_extractor()
        n_features = self.features_extractor.features_dim
        arch, activation = self.arch, self.activation_fn
        self.shared_net, n_shared = _mlp(n_features, arch["shared"], activation)
        self.type_net, n_type = _mlp(n_shared, arch["type"], activation)
        self.params_net, n_params = _mlp(n_shared, arch["params"], activation)
        self.value_net, n_value = _mlp(n_features, arch["vf"], activation)
        self.type_head, self.mean_head, self.log_std = self.action_dist.proba_distribution_net(
            n_type, n_params, self.log_std_init
        )
        self.value_head = nn.Linear(n_value, 1)
        if self.ortho_init:
            gains = {
                self.features_extractor: np.sqrt(2),
                self.shared_net: np.sqrt(2),
                self.type_net: np.sqrt(2),
                self.params_net: np.sqrt(2),
                self.value_net: np.sqrt(2),
                self.type_head: 0.01,
                self.mean_head: 0.01,
                self.value_head: 1.0,
            }
            for module, gain in gains.items():
                module.apply(lambda m, gain=gain: self.init_weights(m, gain=gain))  # type: ignore[misc]
        self.optimizer = make_optimizer(self.optimizer_class, self.parameters(), lr_schedule(1), self.optimizer_kwargs)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data.update(
            lr_schedule=self._dummy_schedule,
            net_arch=self.net_arch,
            activation_fn=self.activation_fn,
            ortho_init=self.ortho_init,
            log_std_init=self.log_std_init,
            features_extractor_class=self.features_extractor_class,
            features_extractor_kwargs=self.features_extractor_kwargs,
        )
        return data

    def actor_parameters(self) -> list[nn.Parameter]:
        """The parameters of both actors' own layers (the features extractor excluded)."""
        modules = (self.shared_net, self.type_net, self.params_net, self.type_head, self.mean_head)
        return [p for module in modules for p in module.parameters()] + [self.log_std]

    def critic_parameters(self) -> list[nn.Parameter]:
        """The parameters of the critic's own layers (the features extractor excluded)."""
        return [*self.value_net.parameters(), *self.value_head.parameters()]

    def _actor_outputs(self, features: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        latent = run_layers(self.shared_net, features)
        return self.type_head(run_layers(self.type_net, latent)), self.mean_head(run_layers(self.params_net, latent))

    def actor_outputs(self, obs: PyTorchObs) -> tuple[th.Tensor, th.Tensor]:
        """The type logits ``(n, K)`` (not normalised) and the parameter means ``(n, n_params)`` (scaled space)."""
        return self._actor_outputs(self.extract_features(obs, self.features_extractor))

    def _distribution_and_value(self, obs: PyTorchObs) -> tuple[HybridDistribution, th.Tensor]:
        features = self.extract_features(obs, self.features_extractor)
        # a copy per call: predict from several threads shares no distribution state
        distribution = copy.copy(self.action_dist).proba_distribution(*self._actor_outputs(features), self.log_std)
        return distribution, self.value_head(run_layers(self.value_net, features)).squeeze(1)

    def forward(self, obs: PyTorchObs, deterministic: bool = False) -> tuple[th.Tensor, th.Tensor, th.Tensor, th.Tensor]:
        """Packed actions ``(n, 1 + n_params)`` (unclipped), values ``(n,)``, and the type and parameter log-probs."""
        distribution, values = self._distribution_and_value(obs)
        actions = distribution.get_actions(deterministic=deterministic)
        type_log_prob, param_log_prob = distribution.log_prob_parts(actions)
        return actions, values, type_log_prob, param_log_prob

    def evaluate_actions(self, obs: PyTorchObs, actions: th.Tensor) -> tuple[th.Tensor, ...]:
        """
        Values, type and parameter log-probabilities, type entropy and (type-weighted) parameter entropy of packed
        ``actions`` (see :meth:`HybridDistribution.entropy_parts`), each ``(n,)``.
        """
        distribution, values = self._distribution_and_value(obs)
        return values, *distribution.log_prob_parts(actions), *distribution.entropy_parts()

    def get_distribution(self, obs: PyTorchObs) -> HybridDistribution:
        """The action distribution for ``obs``."""
        return self._distribution_and_value(obs)[0]

    def predict_values(self, obs: PyTorchObs) -> th.Tensor:
        """``V(s)``, ``(n,)``."""
        features = self.extract_features(obs, self.features_extractor)
        values: th.Tensor = self.value_head(run_layers(self.value_net, features)).squeeze(1)
        return values

    def _predict(self, observation: PyTorchObs, deterministic: bool = False) -> th.Tensor:
        raise NotImplementedError("A parameterized action is not one tensor: use predict()")

    def predict(  # type: ignore[override]
        self,
        observation: np.ndarray,
        state: tuple[np.ndarray, ...] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = False,
    ) -> tuple[Any, tuple[np.ndarray, ...] | None]:
        """
        Action(s) for one observation or a batch: sampled, or the most probable type with its mean parameters.

        :param observation: one observation, or a batch ``(n, *obs_shape)`` with ``n >= 1``
        :return: one env action (a tuple ``env.step`` accepts) for a single observation, or an object ndarray of
            shape ``(n,)`` holding one per observation for a batch; and ``state`` unchanged
        :raises ValueError: for a wrong observation shape, an empty batch, or NaN or inf values
            (:func:`~sb3_aac.common.observations.observation_batch`)
        """
        self.set_training_mode(False)
        batch, vectorized = observation_batch(observation, self.observation_space)
        obs = th.as_tensor(batch, dtype=th.float32, device=self.device)
        with th.no_grad():
            actions = self.get_distribution(obs).get_actions(deterministic=deterministic).cpu().numpy()
        return self.spec.to_env_predicted(actions[:, 0].astype(np.int64), actions[:, 1:], vectorized), state


MlpPolicy = HybridActorCriticPolicy
