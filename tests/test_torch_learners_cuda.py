"""The torch learners learn, act, save and load with ``device="cuda"`` (skipped where no GPU is present)."""

import pytest
import torch as th

from sb3_aac import MPDQN, PDQN, HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import HPPO_SMALL, PDQN_SMALL

pytestmark = pytest.mark.skipif(not th.cuda.is_available(), reason="needs a CUDA GPU")


@pytest.mark.parametrize("algo, settings", [(PDQN, PDQN_SMALL), (MPDQN, PDQN_SMALL), (HybridPPO, HPPO_SMALL)])
def test_learns_acts_and_loads_on_the_gpu(algo, settings, tmp_path):
    env = ParameterizedTargetEnv()
    model = algo("MlpPolicy", env, seed=0, device="cuda", **settings)
    model.learn(200)
    assert all(p.is_cuda for p in model.policy.parameters())
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(action)
    model.save(tmp_path / "model")
    loaded = algo.load(tmp_path / "model", env=env, device="cuda")
    assert loaded.predict(obs, deterministic=True)[0][0] == action[0]
    loaded.learn(100)  # the loaded optimizers' state is on the GPU too
