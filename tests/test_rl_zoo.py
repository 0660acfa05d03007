"""rl-zoo3 for every algorithm: the hyperparameter files, the registration, and a smoke test of each flow (train,
enjoy, record_video, push_to_hub with a stand-in Hub, --optimize) run in this process (rl-zoo3 itself is optional)."""

from __future__ import annotations

import ast
import importlib.util
import json
import inspect
from pathlib import Path

import pytest

from tests.helpers import ALGO_CLASSES, algos

ROOT = Path(__file__).resolve().parents[1]
ZOO_KEYS = {"n_timesteps", "policy", "n_envs", "normalize", "policy_kwargs", "env_wrapper", "callback", "frame_stack"}
# The envs every hyperparameter file covers, and those some files cover besides (by rl-zoo3 name).
ZOO_ENVS = {"RoboCupDribblePaper-v0"}
MORE_ZOO_ENVS = {
    "sarsa_aac": {"RoboCupDribble-v0"},
    "pdqn": {"Platform-v0", "sb3_aac/ParameterizedTarget-v0"},
    "mpdqn": {"Platform-v0", "sb3_aac/ParameterizedTarget-v0"},
    "hppo": {"Platform-v0", "RoboCupDribble-v0", "sb3_aac/ParameterizedTarget-v0"},
}


@algos(ALGO_CLASSES)
def test_hyperparameters_are_constructor_arguments(case) -> None:
    yaml = pytest.importorskip("yaml", reason="PyYAML is not installed (rl-zoo3 depends on it)")
    config = yaml.safe_load((ROOT / "hyperparams" / f"{case.cli}.yml").read_text())
    assert ZOO_ENVS | MORE_ZOO_ENVS.get(case.cli, set()) <= set(config)
    ctor = set(inspect.signature(case.algo.__init__).parameters)
    for env_id, params in config.items():
        unknown = set(params) - ZOO_KEYS - ctor
        assert not unknown, f"{env_id}: {unknown} are neither rl-zoo3 keys nor {case.algo.__name__} arguments"
        assert params["policy"] in case.algo.policy_aliases
        if "policy_kwargs" in params:  # rl-zoo3 eval()s this string
            call = ast.parse(params["policy_kwargs"], mode="eval").body
            assert isinstance(call, ast.Call) and call.func.id == "dict"


def test_the_example_script_is_the_zoo_entry_point() -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3); the script needs it")
    spec = importlib.util.spec_from_file_location("rl_zoo3_train", ROOT / "examples" / "rl_zoo3_train.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    import gymnasium as gym

    from sb3_aac.zoo import main

    assert module.main is main and "RoboCupDribblePaper-v0" in gym.registry


# --- every rl-zoo3 flow, through sb3_aac.zoo (what examples/rl_zoo3_train.py runs), in this process ---
DRIBBLE = "RoboCupDribblePaper-v0"  # renders (rgb_array), so record_video and push_to_hub run on it
TOY = "sb3_aac/ParameterizedTarget-v0"


def zoo(*argv: str) -> None:
    from sb3_aac.zoo import main

    main(list(argv))


def small(case) -> list[str]:
    """``--hyperparams`` pairs that keep a run to seconds: 2 lanes, the case's small settings, one gradient step."""
    one_step = {"gradient_steps": 1} if "gradient_steps" in inspect.signature(case.algo.__init__).parameters else {}
    settings = {"n_envs": 2, **case.kwargs, **one_step}
    return ["--hyperparams", *(f"{key}:{value!r}" for key, value in settings.items())]


@pytest.fixture(scope="module")
def zoo_logs(tmp_path_factory) -> tuple[Path, set[str]]:
    """rl-zoo3's log folder of this module's runs, and the algorithms trained into it so far."""
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3)")
    import robocup_dribble  # noqa: F401  (registers the dribbling envs, as the example script does)

    return tmp_path_factory.mktemp("zoo"), set()


def trained(case, zoo_logs) -> Path:
    """rl-zoo3's log folder after ``case`` was trained 64 steps on the dribbling env (once per module)."""
    folder, done = zoo_logs
    if case.cli not in done:
        zoo("--algo", case.cli, "--env", DRIBBLE, "--conf-file", str(ROOT / "hyperparams" / f"{case.cli}.yml"),
            "-n", "64", "--eval-freq", "-1", "-f", str(folder), "--seed", "0", *small(case))  # fmt: skip
        done.add(case.cli)
    return folder


def flow(name: str, case, folder: Path, *argv: str) -> None:
    zoo(name, "--algo", case.cli, "--env", DRIBBLE, "-f", str(folder), *argv)


@algos(ALGO_CLASSES)
def test_train_saves_a_model_that_enjoy_replays(case, zoo_logs, capsys) -> None:
    folder = trained(case, zoo_logs)
    model = case.algo.load(folder / case.cli / f"{DRIBBLE}_1" / f"{DRIBBLE}.zip")
    assert model.num_timesteps >= 64
    capsys.readouterr()
    flow("--enjoy", case, folder, "--no-render", "-n", "40")  # episodes last at most 35 steps
    assert "Episode Reward" in capsys.readouterr().out


@algos(ALGO_CLASSES)
def test_record_video_writes_an_mp4(case, zoo_logs, tmp_path) -> None:
    pytest.importorskip("moviepy", reason="SB3's VecVideoRecorder writes with moviepy")
    pytest.importorskip("pygame", reason="the dribbling env renders with pygame")
    flow("--record-video", case, trained(case, zoo_logs), "-n", "10", "-o", str(tmp_path))
    videos = list(tmp_path.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 0


class StandInHub:
    """huggingface_hub.HfApi's calls that rl_zoo3.push_to_hub makes, recorded; the upload copies the folder."""

    def __init__(self, uploads: Path) -> None:
        self.uploads, self.repos = uploads, []

    def __call__(self, *args, **kwargs) -> StandInHub:
        return self

    def create_repo(self, repo_id: str, **kwargs) -> str:
        self.repos.append(repo_id)
        return f"https://huggingface.co/{repo_id}"

    def snapshot_download(self, repo_id: str, local_dir: Path) -> None:
        Path(local_dir).mkdir(parents=True, exist_ok=True)  # an empty repository

    def upload_folder(self, repo_id: str, folder_path: Path, commit_message: str) -> None:
        import shutil

        shutil.copytree(folder_path, self.uploads / repo_id)


@algos(ALGO_CLASSES)
def test_push_to_hub_uploads_a_loadable_model(case, zoo_logs, tmp_path, monkeypatch) -> None:
    import huggingface_hub

    hf_sb3 = importlib.import_module("huggingface_sb3.push_to_hub")  # the package's attribute is a function

    folder = trained(case, zoo_logs)
    hub = StandInHub(tmp_path / "uploaded")
    monkeypatch.setattr(huggingface_hub, "HfApi", hub)
    if not hasattr(hf_sb3, "generate_metadata"):
        # rl-zoo3 2.9.2 imports a name that sb3-team-hf-integration 3.2 (its latest release) calls _generate_metadata
        # and returns as a ModelCardData; rl-zoo3 saves it as a dict. Without this, rl_zoo3.push_to_hub fails at import.
        monkeypatch.setattr(
            hf_sb3, "generate_metadata", lambda *args: hf_sb3._generate_metadata(*args).to_dict(), raising=False
        )
    monkeypatch.chdir(tmp_path)  # push_to_hub stages the repository in ./hub
    flow("--push-to-hub", case, folder, "-orga", "someone", "--no-render")
    name = f"{case.cli}-{DRIBBLE}"
    assert hub.repos == [f"someone/{name}"]
    uploaded = tmp_path / "uploaded" / "someone" / name
    assert {"README.md", "results.json", "config.yml", f"{name}.zip"} <= {p.name for p in uploaded.iterdir()}
    assert case.algo.load(uploaded / f"{name}.zip").num_timesteps >= 64


@algos(ALGO_CLASSES)
def test_optimize_runs_a_trial_with_the_algorithms_sampler(case, tmp_path) -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3)")
    import optuna

    storage = tmp_path / "study.log"
    zoo("--algo", case.cli, "--env", TOY, "--conf-file", str(ROOT / "hyperparams" / f"{case.cli}.yml"), "-n", "64",
        "--optimize", "--n-trials", "1", "--n-evaluations", "1", "--eval-episodes", "2", "--no-optim-plots",
        "--storage", str(storage), "--study-name", "smoke", "-f", str(tmp_path), "--seed", "0", *small(case))  # fmt: skip
    journal = optuna.storages.JournalStorage(optuna.storages.journal.JournalFileBackend(str(storage)))
    (trial,) = optuna.load_study(study_name="smoke", storage=journal).trials
    assert trial.state == optuna.trial.TrialState.COMPLETE
    assert trial.params["policy"] in case.algo.policy_aliases


def test_every_algorithm_is_tunable_and_in_the_zoo() -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3)")
    import rl_zoo3.hyperparams_opt

    from sb3_aac.tune.search_spaces import ALGORITHMS, policies
    from sb3_aac.zoo import register

    assert ALGORITHMS == {case.cli: case.algo for case in ALGO_CLASSES}  # one table, every algorithm
    register()
    for name, algorithm in ALGORITHMS.items():
        assert policies(name), f"{name} has no search space"
        assert rl_zoo3.ALGOS[name] is algorithm
        assert name in rl_zoo3.hyperparams_opt.HYPERPARAMS_SAMPLER and name in rl_zoo3.hyperparams_opt.HYPERPARAMS_CONVERTER


@algos(ALGO_CLASSES)
def test_the_sampler_gives_arguments_that_train_and_its_converter_restores_them(case) -> None:
    optuna = pytest.importorskip("optuna", reason="--optimize needs Optuna")
    from stable_baselines3.common.env_util import make_vec_env

    from sb3_aac.common.envs import ParameterizedTargetEnv
    from sb3_aac.tune.zoo import convert_params, sample_params

    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1))
    policies = set()
    for _ in range(4):
        trial = study.ask()
        kwargs = sample_params(case.cli, trial)
        assert convert_params(case.cli, trial.params) == kwargs  # what rl-zoo3 trains a stored trial with
        policies.add(kwargs["policy"])
        env = make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0)
        case.algo(env=env, seed=0, info_keywords=(), **{**case.kwargs, **kwargs, **case.rollout}).learn(60)
        json.dumps(trial.params)  # storable in any Optuna storage
    assert policies <= set(case.algo.policy_aliases)
    if len(case.algo.policy_aliases) > 1:
        assert len(policies) > 1  # the policy is sampled too
