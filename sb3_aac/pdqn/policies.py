from __future__ import annotations

from typing import Any, cast

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.torch_layers import create_mlp
from stable_baselines3.common.type_aliases import PyTorchObs, Schedule
from torch import nn

from sb3_aac.common.observations import check_box_observation_space, observation_batch
from sb3_aac.common.sizes import check_layer_sizes
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.common.layer_calls import run_layers
from sb3_aac.common.updates import make_optimizer

PARAM_BOUNDINGS = ("invert_gradients", "tanh")


class QNetwork(nn.Module):
    """
    ``Q(s, k, x)`` for every action type ``k`` at once: an MLP on ``[s, x]`` with ``K`` outputs.

    With ``multi_pass=False`` (P-DQN, Xiong et al. 2018) one pass sees every type's parameters, so ``Q_k`` also
    depends on the parameters of the other types. With ``multi_pass=True`` (MP-DQN, Bester et al. 2019) the
    network runs ``K`` passes; pass ``k`` sees only type ``k``'s parameters (the others are zeroed) and ``Q_k`` is
    read from pass ``k``, so ``Q_k`` depends on ``s`` and ``x_k`` only. The passes run as one batch of ``K * n``.

    :param n_inputs: Observation features
    :param spec: The parameterized action space's structure
    :param net_arch: Hidden layer sizes
    :param activation_fn: Hidden activation
    :param multi_pass: MP-DQN's multi-pass evaluation
    """

    def __init__(
        self,
        n_inputs: int,
        spec: ParameterizedActionSpec,
        net_arch: list[int],
        activation_fn: type[nn.Module],
        multi_pass: bool,
    ):
        super().__init__()
        self.n_types, self.multi_pass = spec.n_types, multi_pass
        self.net = nn.Sequential(*create_mlp(n_inputs + spec.n_params, spec.n_types, net_arch, activation_fn))
        self.owner_mask: th.Tensor
        # owner_mask[k, j] = 1 if scalar parameter j belongs to type k.
        owner_mask = th.as_tensor(spec.param_type == np.arange(spec.n_types)[:, None], dtype=th.float32)
        self.register_buffer("owner_mask", owner_mask, persistent=False)

    def forward(self, features: th.Tensor, params: th.Tensor) -> th.Tensor:
        """``(n, K)`` values of every type, given features ``(n, D)`` and scaled parameters ``(n, n_params)``."""
        return self.values(run_layers(self.net, self.pass_inputs(features, params)))

    def pass_inputs(self, features: th.Tensor, params: th.Tensor) -> th.Tensor:
        """
        The network's input rows: ``[s, x]`` ``(n, D + n_params)``, or with ``multi_pass`` the ``K`` passes as one
        batch ``(K * n, D + n_params)``, pass ``j`` (rows ``j * n`` to ``(j + 1) * n - 1``) holding only type ``j``'s
        parameters.
        """
        if not self.multi_pass:
            return th.cat((features, params), dim=1)
        n, k = len(features), self.n_types
        masked = params.unsqueeze(0) * self.owner_mask.unsqueeze(1)  # (K, n, n_params)
        return th.cat((features.expand(k, n, -1), masked), dim=2).reshape(k * n, -1)

    def values(self, outputs: th.Tensor) -> th.Tensor:
        """``(n, K)`` values from the network's outputs on :meth:`pass_inputs` (with ``multi_pass``, ``Q_j`` of pass ``j``)."""
        if not self.multi_pass:
            return outputs
        k = self.n_types
        diagonal: th.Tensor = outputs.reshape(k, -1, k).diagonal(dim1=0, dim2=2)
        return diagonal

    def output_grads(self, value_grads: th.Tensor) -> th.Tensor:
        """The gradient with respect to the network's outputs on :meth:`pass_inputs`, given that of :meth:`values`."""
        if not self.multi_pass:
            return value_grads
        eye = th.eye(self.n_types, dtype=value_grads.dtype, device=value_grads.device)
        return (value_grads.t().unsqueeze(2) * eye.unsqueeze(1)).reshape(-1, self.n_types)

    def param_grads(self, input_grads: th.Tensor, n_features: int) -> th.Tensor:
        """The gradient with respect to the parameters ``(n, n_params)``, given that of :meth:`pass_inputs`' rows."""
        grads = input_grads[:, n_features:]
        if not self.multi_pass:
            return grads
        k = self.n_types
        return (grads.reshape(k, -1, grads.shape[1]) * self.owner_mask.unsqueeze(1)).sum(0)

    def chosen_inputs(self, features: th.Tensor, params: th.Tensor, types: th.Tensor) -> th.Tensor:
        """
        Input rows ``(n, D + n_params)`` whose outputs hold ``Q(s, k, x)`` at column ``k = types``: ``[s, x]``, or with
        ``multi_pass`` the one pass of each row's type (the other passes do not affect that value).
        """
        if not self.multi_pass:
            return self.pass_inputs(features, params)
        return th.cat((features, params * self.owner_mask[types]), dim=1)


class ParamActor(nn.Module):
    """
    ``x(s)``: every type's parameters in the scaled space, from an MLP plus a fixed (not trained) initial value.

    With ``squash=True`` the output is ``tanh(mlp(s) + atanh(x0))``, inside ``(-1, 1)`` by construction. Otherwise it
    is ``mlp(s) + x0``, unbounded: the algorithm keeps it inside ``[-1, 1]`` with inverting gradients and clips it
    when acting. The last layer starts with tiny weights (std 1e-4, as in the reference code), so initially
    ``x(s) ~= x0``.

    :param n_inputs: Observation features
    :param n_params: Scalar parameters over all types
    :param net_arch: Hidden layer sizes
    :param activation_fn: Hidden activation
    :param initial_params: ``x0``, scaled, shape ``(n_params,)``
    :param squash: Bound the output with tanh
    """

    def __init__(
        self,
        n_inputs: int,
        n_params: int,
        net_arch: list[int],
        activation_fn: type[nn.Module],
        initial_params: np.ndarray,
        squash: bool,
    ):
        super().__init__()
        self.squash = squash
        self.net = nn.Sequential(*create_mlp(n_inputs, n_params, net_arch, activation_fn))
        last = self.net[-1]
        assert isinstance(last, nn.Linear)
        nn.init.normal_(last.weight, std=1e-4)
        nn.init.zeros_(last.bias)
        offset = np.arctanh(np.clip(initial_params, -0.999, 0.999)) if squash else initial_params
        self.offset: th.Tensor
        self.register_buffer("offset", th.as_tensor(offset, dtype=th.float32))

    def forward(self, features: th.Tensor) -> th.Tensor:
        return self.bound(run_layers(self.net, features))

    def bound(self, mlp_outputs: th.Tensor) -> th.Tensor:
        """The parameters ``(n, n_params)`` from the MLP's outputs."""
        out = mlp_outputs + self.offset
        return th.tanh(out) if self.squash else out

    def mlp_output_grads(self, param_grads: th.Tensor, params: th.Tensor) -> th.Tensor:
        """The gradient with respect to the MLP's outputs, given that of the parameters :meth:`bound` gave."""
        return th.ops.aten.tanh_backward(param_grads, params) if self.squash else param_grads


class PDQNPolicy(BasePolicy):
    """
    Policy of P-DQN / MP-DQN: the parameter actor ``x(s)``, the Q network ``Q(s, k, x)``, and a target copy of each.

    Observations are flattened and, where the observation space has finite bounds, scaled to ``[-1, 1]``.
    ``predict`` is greedy: ``k = argmax_k Q(s, k, x(s))`` and type ``k``'s parameters ``x_k(s)`` (clipped to the
    bounds); the nested and flat layouts also carry the other types' parameters.

    :param observation_space: A ``Box`` observation space (any shape; it is flattened)
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param lr_schedule: Learning rate schedule of the Q network
    :param actor_lr_schedule: Learning rate schedule of the parameter actor (defaults to ``lr_schedule``)
    :param net_arch: Hidden layers of the Q network (the reference code used ``[128]`` on Platform)
    :param actor_net_arch: Hidden layers of the parameter actor (defaults to ``net_arch``)
    :param activation_fn: Hidden activation of both networks
    :param multi_pass: MP-DQN's multi-pass Q network (set by the algorithm: ``MPDQN`` uses it, ``PDQN`` does not)
    :param param_bounding: ``"invert_gradients"`` (Hausknecht & Stone 2016, as both papers) or ``"tanh"``
        (squash the actor's output)
    :param initial_params: The actor's initial parameters in env units, shape ``(n_params,)`` in the order of
        :class:`~sb3_aac.common.spaces.ParameterizedActionSpec`; defaults to the middle of each range. The
        reference code's Platform run starts from ``[3, 10, 400]``.
    :param optimizer_class: The optimizer of both networks
    :param optimizer_kwargs: Extra arguments of the optimizers
    """

    obs_mid: th.Tensor
    obs_half: th.Tensor

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        lr_schedule: Schedule,
        actor_lr_schedule: Schedule | None = None,
        net_arch: list[int] | None = None,
        actor_net_arch: list[int] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
        multi_pass: bool = False,
        param_bounding: str = "invert_gradients",
        initial_params: np.ndarray | list[float] | None = None,
        optimizer_class: type[th.optim.Optimizer] = th.optim.Adam,
        optimizer_kwargs: dict[str, Any] | None = None,
    ):
        check_box_observation_space(observation_space, "P-DQN policies")
        if param_bounding not in PARAM_BOUNDINGS:
            raise ValueError(f"Unknown param_bounding {param_bounding!r}, valid values: {list(PARAM_BOUNDINGS)}")
        super().__init__(observation_space, action_space, optimizer_class=optimizer_class, optimizer_kwargs=optimizer_kwargs)
        self.spec = ParameterizedActionSpec.from_space(action_space)
        self.net_arch = [128] if net_arch is None else check_layer_sizes("net_arch", net_arch)
        self.actor_net_arch = self.net_arch if actor_net_arch is None else check_layer_sizes("actor_net_arch", actor_net_arch)
        self.activation_fn, self.multi_pass, self.param_bounding = activation_fn, multi_pass, param_bounding
        self.initial_params = initial_params
        self.actor_lr_schedule = lr_schedule if actor_lr_schedule is None else actor_lr_schedule
        self._build(lr_schedule)

    def _build(self, lr_schedule: Schedule) -> None:
        box = cast(spaces.Box, self.observation_space)  # PDQN accepts Box observations only
        spec, n_inputs = self.spec, int(np.prod(box.shape))
        low = np.asarray(box.low, dtype=np.float64).ravel()
        high = np.asarray(box.high, dtype=np.float64).ravel()
        finite = np.isfinite(low) & np.isfinite(high) & (high > low)
        self.register_buffer("obs_mid", th.as_tensor(np.where(finite, (high + low) / 2, 0.0), dtype=th.float32))
        self.register_buffer("obs_half", th.as_tensor(np.where(finite, (high - low) / 2, 1.0), dtype=th.float32))
        if self.initial_params is None:
            initial = np.zeros(spec.n_params)
        else:
            initial = np.asarray(self.initial_params, dtype=np.float64)
            if initial.shape != (spec.n_params,) or not np.all((initial >= spec.low) & (initial <= spec.high)):
                raise ValueError(
                    f"initial_params must hold {spec.n_params} values inside the parameter bounds {spec.low} .. {spec.high}, "
                    f"got {self.initial_params}"
                )
            initial = spec.scale(initial)
        squash = self.param_bounding == "tanh"
        self.actor = ParamActor(n_inputs, spec.n_params, self.actor_net_arch, self.activation_fn, initial, squash)
        self.actor_target = ParamActor(n_inputs, spec.n_params, self.actor_net_arch, self.activation_fn, initial, squash)
        self.q_net = QNetwork(n_inputs, spec, self.net_arch, self.activation_fn, self.multi_pass)
        self.q_net_target = QNetwork(n_inputs, spec, self.net_arch, self.activation_fn, self.multi_pass)
        self.actor_target.load_state_dict(self.actor.state_dict())
        self.q_net_target.load_state_dict(self.q_net.state_dict())
        # The parameter lists of each network, for the training step (moving the policy keeps the tensor objects).
        self.actor_params, self.actor_target_params = list(self.actor.parameters()), list(self.actor_target.parameters())
        self.q_net_params, self.q_net_target_params = list(self.q_net.parameters()), list(self.q_net_target.parameters())
        self.q_optimizer = make_optimizer(self.optimizer_class, self.q_net.parameters(), lr_schedule(1), self.optimizer_kwargs)
        self.actor_optimizer = make_optimizer(
            self.optimizer_class, self.actor.parameters(), self.actor_lr_schedule(1), self.optimizer_kwargs
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data.pop("normalize_images", None)  # not an argument of this policy
        data.update(
            lr_schedule=self._dummy_schedule,
            actor_lr_schedule=self._dummy_schedule,
            net_arch=self.net_arch,
            actor_net_arch=self.actor_net_arch,
            activation_fn=self.activation_fn,
            multi_pass=self.multi_pass,
            param_bounding=self.param_bounding,
            initial_params=self.initial_params,
            optimizer_class=self.optimizer_class,
            optimizer_kwargs=self.optimizer_kwargs,
        )
        return data

    def features(self, obs: th.Tensor) -> th.Tensor:
        """Observations ``(n, *obs_shape)`` flattened and scaled: ``(n, D)`` float32."""
        return (obs.reshape(len(obs), -1).float() - self.obs_mid) / self.obs_half

    def greedy(self, features: th.Tensor) -> tuple[th.Tensor, th.Tensor, th.Tensor]:
        """Q values ``(n, K)``, actor parameters ``(n, n_params)`` (unclipped) and greedy types ``(n,)``."""
        params = self.actor(features)
        q = self.q_net(features, params)
        return q, params, q.argmax(1)

    def forward(self, obs: PyTorchObs, deterministic: bool = True) -> th.Tensor:
        """Greedy ``[k, x]`` as one tensor ``(n, 1 + n_params)`` (the type as a float, then the clipped parameters)."""
        assert isinstance(obs, th.Tensor)
        _, params, k = self.greedy(self.features(obs))
        return th.cat((k.unsqueeze(1).float(), params.clamp(-1.0, 1.0)), dim=1)

    def _predict(self, observation: PyTorchObs, deterministic: bool = True) -> th.Tensor:
        raise NotImplementedError("A parameterized action is not one tensor: use predict()")

    def predict(  # type: ignore[override]
        self,
        observation: np.ndarray,
        state: tuple[np.ndarray, ...] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = False,
    ) -> tuple[Any, tuple[np.ndarray, ...] | None]:
        """
        Greedy action(s) for one observation or a batch (``deterministic`` is accepted for SB3 compatibility;
        the policy has no stochastic mode of its own, exploration belongs to the algorithm).

        :return: one env action (a tuple ``env.step`` accepts) for a single observation, or an object ndarray of
            shape ``(n,)`` holding one per observation for a batch; and ``state`` unchanged
        """
        self.set_training_mode(False)
        obs, vectorized = observation_batch(observation, self.observation_space)
        with th.no_grad():
            _, params, k = self.greedy(self.features(th.as_tensor(obs, device=self.device)))
        return self.spec.to_env_predicted(k.cpu().numpy(), params.cpu().numpy(), vectorized), state


MlpPolicy = PDQNPolicy
