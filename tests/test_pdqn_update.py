"""P-DQN's and MP-DQN's gradient steps (explicit gradients) give the numbers of the plain formulation (module calls,
autograd's ``backward``, torch's ``clip_grad_norm_``, SB3's ``polyak_update``) to rounding when both use the
per-tensor optimizer loop."""

import copy

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.utils import polyak_update

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.envs import ParameterizedTargetEnv
from torch.nn import functional as F

from sb3_aac.pdqn.pdqn import invert_gradients
from sb3_aac.pdqn.policies import PDQNPolicy

LOOP = dict(optimizer_kwargs=dict(foreach=False))  # torch's per-tensor Adam: the arithmetic of the plain update
PLAIN_LOSSES = {"mse": F.mse_loss, "huber": F.smooth_l1_loss}


def plain_train(model, policy: PDQNPolicy, rng: np.random.Generator, gradient_steps: int, batch_size: int) -> None:
    """The gradient steps of ``model`` written plainly, applied to ``policy`` (a copy of the model's)."""
    loss_fn, invert = PLAIN_LOSSES[model.loss], policy.param_bounding == "invert_gradients"
    for n_updates in range(model._n_updates + 1, model._n_updates + gradient_steps + 1):
        data = model.replay_buffer.sample(batch_size, rng)
        features, next_features = policy.features(data.observations), policy.features(data.next_observations)
        with th.no_grad():
            next_params = policy.actor_target(next_features)
            if invert:
                next_params = next_params.clamp(-1.0, 1.0)
            next_q = policy.q_net_target(next_features, next_params).max(1).values
            target = data.rewards + (1.0 - data.dones) * model.gamma * next_q
        q = policy.q_net(features, data.params).gather(1, data.action_types.unsqueeze(1)).squeeze(1)
        policy.q_optimizer.zero_grad()
        loss_fn(q, target).backward()
        th.nn.utils.clip_grad_norm_(policy.q_net.parameters(), model.max_grad_norm)
        policy.q_optimizer.step()

        params = policy.actor(features)
        if invert:
            leaf = params.detach().requires_grad_()
            (ascent,) = th.autograd.grad(policy.q_net(features, leaf).sum(1).mean(), leaf)
            surrogate = -(invert_gradients(ascent, leaf.detach()) * params).sum()
        else:
            surrogate = -policy.q_net(features, params).sum(1).mean()
        policy.actor_optimizer.zero_grad()
        surrogate.backward()
        th.nn.utils.clip_grad_norm_(policy.actor.parameters(), model.max_grad_norm)
        policy.actor_optimizer.step()
        if n_updates % model.target_update_interval == 0:
            polyak_update(policy.q_net.parameters(), policy.q_net_target.parameters(), model.tau)
            polyak_update(policy.actor.parameters(), policy.actor_target.parameters(), model.actor_tau)


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
@pytest.mark.parametrize(
    "settings",
    [
        dict(),
        dict(loss="huber", target_update_interval=2, policy_kwargs=dict(param_bounding="tanh")),
        dict(max_grad_norm=1e-3),  # every step clipped
    ],
)
def test_gradient_steps_are_the_plain_formulation(algo, settings):
    settings = dict(settings)
    policy_kwargs = dict(net_arch=[16, 16], **LOOP, **settings.pop("policy_kwargs", {}))
    env = ParameterizedTargetEnv()
    model = algo("MlpPolicy", env, learning_starts=64, seed=0, device="cpu", policy_kwargs=policy_kwargs, **settings)
    model.learn(64)  # fills the buffer with random actions, no update yet
    model.learn(4, reset_num_timesteps=False)  # some updates, so the optimizers have state
    policy, rng = copy.deepcopy(model.policy), copy.deepcopy(model._rng)
    before = copy.deepcopy(policy.state_dict())
    plain_train(model, policy, rng, gradient_steps=5, batch_size=32)
    model.train(gradient_steps=5, batch_size=32)
    fast, plain = model.policy.state_dict(), policy.state_dict()
    differences = {name: float((fast[name] - plain[name]).abs().max()) for name in plain}
    assert max(differences.values()) < 1e-6, differences
    assert not all(th.equal(fast[name], before[name]) for name in before)


def test_the_default_optimizer_is_fused_and_a_user_choice_is_kept():
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(), device="cpu")
    assert model.policy.q_optimizer.defaults["fused"] and model.policy.actor_optimizer.defaults["fused"]
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(), device="cpu", policy_kwargs=LOOP)
    assert model.policy.q_optimizer.defaults["foreach"] is False and not model.policy.q_optimizer.defaults["fused"]
