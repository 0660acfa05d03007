"""The benchmark runner and report (benchmarks/): a tiny grid end to end, resuming, atomic writes, the baseline
adapters, and the report from synthetic cell files."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

import robocup_dribble
from benchmarks import cells as cell_files
from benchmarks import domains
from benchmarks import run as bench_run
from benchmarks.models import build_model
from benchmarks.adapters import DiscreteActionAdapter, FlatActionAdapter, baseline_env, env_action_space
from benchmarks.presets import (
    ENV_IDS,
    FULL,
    HFO_ID,
    HFO_SECONDS,
    LONG_BUDGET,
    WALL_CLOCK_SECONDS,
    Cell,
    build_cells,
    is_tuned,
    select,
)
from benchmarks.report import build_report
from benchmarks.tuning import plan_studies
from benchmarks.significance import MIN_SEEDS
from sb3_aac import DiscretizeParameterizedAction, FlattenParameterizedAction

ENV_ID = "RoboCupDribblePaper-v0"
EVAL = {"eval_every": 100, "eval_episodes": 20, "final_episodes": 40}


def tiny_cells() -> list[Cell]:
    return [
        Cell(ENV_ID, "Reference", "references", eval_episodes=20, final_episodes=40),
        Cell(ENV_ID, "SarsaAAC", "rbf10", 0, 2000, **EVAL),
        Cell(ENV_ID, "SarsaAAC", "rbf10", 1, 2000, **EVAL),
        Cell(ENV_ID, "PPO", "ppo", 0, 512, **EVAL, overrides={"n_envs": 2, "n_steps": 128, "batch_size": 128, "n_epochs": 1}),
        Cell(ENV_ID, "DQN", "dqn", 0, 512, **EVAL, overrides={"n_envs": 2, "learning_starts": 100}),
    ]


def mtimes(out) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in (out / "cells").glob("*.json")}


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    """The tiny grid, run as if interrupted: first the seed-0 cells only, then everything."""
    out = tmp_path_factory.mktemp("bench")
    cells = tiny_cells()
    first = bench_run.run_grid(select(cells, "s0"), out, workers=1, progress=False)
    before = mtimes(out)
    second = bench_run.run_grid(cells, out, workers=1, progress=False)
    return out, cells, first, before, second


def test_tiny_grid_writes_cells_models_and_tensorboard(tiny_run):
    out, cells, first, _, second = tiny_run
    assert not first["failed"] and not second["failed"]
    results = {r["cell_id"]: r for r in cell_files.load_cells(out)}
    assert set(results) == {c.cell_id for c in cells}
    for cell in cells:
        result = results[cell.cell_id]
        assert result["cell"] == cell.to_dict()
        assert result["versions"]["stable_baselines3"] and result["machine"]["cores"]
        if cell.algo == "Reference":
            refs = result["references"]
            assert refs["handcoded"]["final"]["episodes"] == 40
            bound = refs["bound"]
            assert bound["mean"] > 20 and len(bound["episode_bounds"]) == 40
            # no episode of the dribbler's goes past its bound (the same episodes: common random numbers)
            assert all(
                d <= b for d, b in zip(refs["handcoded"]["final"]["episode_scores"], bound["episode_bounds"], strict=True)
            )
            continue
        curve = result["curve"]
        assert curve[0]["episodes"] == 0 and curve[0]["env_steps"] == 0  # a point before training
        assert curve[-1]["env_steps"] == result["env_steps"] >= cell.budget  # and one where training ended
        assert [p["episodes"] for p in curve] == sorted(p["episodes"] for p in curve)
        for point in curve:
            assert {"distance_mean", "reach20_share", "ball_loss_rate", "wall_s", "train_s"} <= set(point)
            assert 0 <= point["reach20_share"] <= 1 and 0 <= point["ball_loss_rate"] <= 1
        assert result["final"]["episodes"] == 40
        assert result["predict_us"] > 0
        assert (out / result["model"]).is_file()
        tb = out / "tb" / cell.cell_id
        assert any(tb.glob("events.out.tfevents.*")), f"no TensorBoard run for {cell.cell_id}"
    # SarsaAAC trains long enough here for more than the first and last points
    assert len(results[cells[1].cell_id]["curve"]) > 2


def scalar_tags(folder):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(folder))
    events.Reload()
    return events, set(events.Tags()["scalars"])


def test_eval_metrics_reach_tensorboard(tiny_run):
    out, cells, *_ = tiny_run
    events, tags = scalar_tags(out / "tb" / cells[1].cell_id)
    assert {"eval/distance_mean", "eval/reach20_share", "eval/ball_loss_rate", "eval/final_distance_mean"} <= tags
    result = json.loads((out / "cells" / f"{cells[1].cell_id}.json").read_text())
    logged = [e.value for e in events.Scalars("eval/distance_mean")]
    assert np.allclose(logged, [p["distance_mean"] for p in result["curve"]], atol=1e-4)


def test_sb3_baselines_log_the_env_metric_through_the_callback(tiny_run):
    """The PPO and DQN cells (SB3's algorithms on the batched dribbling VecEnv) log rollout/ep_distance_mean and
    rollout/ep_ball_lost_mean (benchmarks.execution adds EpisodeKeywordsCallback), at least wherever ep_rew_mean is."""
    out, cells, *_ = tiny_run
    for cell in cells[3:]:
        events, tags = scalar_tags(out / "tb" / cell.cell_id)
        assert {"rollout/ep_distance_mean", "rollout/ep_ball_lost_mean"} <= tags, cell.cell_id
        distance_steps = {e.step for e in events.Scalars("rollout/ep_distance_mean")}
        reward_steps = {e.step for e in events.Scalars("rollout/ep_rew_mean")} if "rollout/ep_rew_mean" in tags else set()
        assert reward_steps <= distance_steps
        assert all(0.0 <= e.value <= 1.0 for e in events.Scalars("rollout/ep_ball_lost_mean"))
        assert all(np.isfinite(e.value) for e in events.Scalars("rollout/ep_distance_mean"))  # metres along +x


def test_rerun_skips_finished_cells_without_rewriting_them(tiny_run):
    out, cells, first, before, second = tiny_run
    first_ids = {c.cell_id for c in select(cells, "s0")}
    assert set(first["done"]) == first_ids
    # the "interrupted" sweep's cells were skipped and left untouched; only the others ran
    assert set(second["skipped"]) == first_ids
    assert set(second["done"]) == {c.cell_id for c in cells} - first_ids
    after = mtimes(out)
    assert all(after[name] == stamp for name, stamp in before.items())
    # a third run does nothing
    third = bench_run.run_grid(cells, out, workers=1, progress=False)
    assert not third["done"] and set(third["skipped"]) == {c.cell_id for c in cells}
    assert mtimes(out) == after


def test_report_from_the_tiny_run(tiny_run):
    out, *_ = tiny_run
    text = build_report(out, figures=False).read_text()  # the figures are drawn in test_report_from_synthetic_cells
    assert "python -m benchmarks.report" in text and "PPO" in text and "DQN" in text and "hand-coded" in text
    assert "RBF arrays (10/input)" in text and "| config |" in text


def test_a_failing_cell_leaves_no_result_file(tmp_path):
    bad = Cell(ENV_ID, "SarsaAAC", "rbf10", 0, 200, **EVAL, overrides={"gamma": 5.0})  # SarsaAAC rejects gamma > 1
    status = bench_run.run_grid([bad], tmp_path, workers=1, progress=False)
    assert status["failed"] == [bad.cell_id]
    assert not list((tmp_path / "cells").iterdir())
    assert "gamma" in (tmp_path / "errors" / f"{bad.cell_id}.txt").read_text()


def test_atomic_write_keeps_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "cells" / "x.json"
    cell_files.atomic_write_json(path, {"a": 1})
    with pytest.raises(ValueError):
        cell_files.atomic_write_json(path, {"a": float("nan")})  # refused before writing
    assert json.loads(path.read_text()) == {"a": 1}

    def crash(*args):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", crash)
    with pytest.raises(OSError):
        cell_files.atomic_write_json(path, {"a": 2})
    assert json.loads(path.read_text()) == {"a": 1}
    assert [p.name for p in path.parent.iterdir()] == ["x.json"]


def test_a_cell_that_raises_while_writing_leaves_nothing(tmp_path, monkeypatch):
    cell = Cell(ENV_ID, "Reference", "references", eval_episodes=10, final_episodes=10)
    real = cell_files.atomic_write_text

    def write_half_then_fail(path, text):
        if path.suffix == ".json":
            # what a non-atomic writer would leave: half a file, then the process dies
            monkeypatch.setattr(os, "fsync", lambda fd: (_ for _ in ()).throw(KeyboardInterrupt()))
        return real(path, text)

    monkeypatch.setattr(cell_files, "atomic_write_text", write_half_then_fail)
    with pytest.raises(KeyboardInterrupt):
        bench_run.run_grid([cell], tmp_path, workers=1, progress=False)
    assert not list((tmp_path / "cells").iterdir())  # neither the result nor a temporary file


@pytest.mark.parametrize("wrapper", ["flatten", "discretize"])
def test_adapters_give_the_wrappers_env_actions(wrapper):
    space = env_action_space(ENV_ID)
    env = robocup_dribble.DribbleEnv(profile="v11")
    rng = np.random.default_rng(0)
    if wrapper == "flatten":
        wrapped = FlattenParameterizedAction(env)
        raw = rng.uniform(-1.3, 1.3, size=(64, *wrapped.action_space.shape)).astype(np.float32)
    else:
        wrapped = DiscretizeParameterizedAction(env, bins=5)
        raw = rng.integers(wrapped.action_space.n, size=64)

    class Scripted:  # an SB3-like model that returns the given raw actions
        def predict(self, obs, state=None, episode_start=None, deterministic=False):
            return (raw[: len(obs)] if np.ndim(obs) == 2 else raw[0]), state

    adapter = FlatActionAdapter(Scripted(), space) if wrapper == "flatten" else DiscreteActionAdapter(Scripted(), space, 5)
    vec = robocup_dribble.DribbleVecEnv(64, profile="v11")
    obs = vec.reset()
    actions, _ = adapter.predict(obs, deterministic=True)
    assert actions.shape == (64,)
    for action, r in zip(actions, raw, strict=True):
        assert space.contains(action)
        expected = wrapped.action(r)
        assert action[0] == expected[0]
        for got, want in zip(action[1], expected[1], strict=True):
            np.testing.assert_array_equal(got, want)
    vec.step(actions)  # the env accepts them
    single, _ = adapter.predict(obs[0])
    assert space.contains(single) and single[0] == actions[0][0]


@pytest.mark.parametrize("algo", ["PPO", "DQN"])
def test_batched_baseline_env_steps_like_the_gym_wrappers(algo):
    """One lane: the batched env and SB3's DummyVecEnv over the wrapped DribbleEnv give the same trajectory."""
    batched = baseline_env(ENV_ID, algo, n_envs=1, seed=3)
    reference = baseline_env(ENV_ID, algo, n_envs=1, seed=3, batched=False)
    assert batched.action_space == reference.action_space
    batched.action_space.seed(0)
    np.testing.assert_allclose(batched.reset(), reference.reset())
    dones = 0
    for _ in range(120):
        action = np.array([batched.action_space.sample()])
        obs_b, rew_b, done_b, info_b = batched.step(action)
        obs_r, rew_r, done_r, info_r = reference.step(action)
        np.testing.assert_allclose(obs_b, obs_r, atol=1e-6)
        np.testing.assert_allclose(rew_b, rew_r, atol=1e-5)
        assert done_b[0] == done_r[0] and info_b[0]["distance"] == pytest.approx(info_r[0]["distance"])
        dones += int(done_b[0])
    assert dones > 3  # several resets were compared too


def test_building_baselines_leaves_their_settings_alone():
    from benchmarks.adapters import build_baseline
    from benchmarks.presets import BASELINES

    before = json.dumps(BASELINES, sort_keys=True)
    for algo in ("DDPG", "SAC"):  # SB3 writes n_critics / use_sde into the policy_kwargs it is given
        build_baseline(ENV_ID, algo, seed=0, overrides={"n_envs": 1, "buffer_size": 1000})
    assert json.dumps(BASELINES, sort_keys=True) == before


def test_presets_are_well_formed():
    quick, full = build_cells("quick"), build_cells("full")
    for cells in (quick, full):
        ids = [c.cell_id for c in cells]
        assert len(ids) == len(set(ids))
    assert {c.env_id for c in quick} == {ENV_ID}
    assert {c.env_id for c in full} == set(ENV_IDS)
    assert {c.cell_id for c in build_cells("hfo")} <= {c.cell_id for c in full}  # the HFO preset: a part of full
    assert {c.algo for c in full} >= {*("SarsaAAC", "MPDQN", "HybridPPO", "PPO", "A2C", "TD3", "DQN", "Reference")}
    studies = {(s.env_id, s.algo, s.config) for s in plan_studies("full")}
    for env_id in {c.env_id for c in full}:
        trained = [c for c in full if c.algo != "Reference" and c.env_id == env_id and not c.seconds]
        main = min(c.budget for c in trained)
        assert main == FULL["envs"][env_id]["budget"]
        assert {c.budget for c in trained} <= {main, FULL["envs"][env_id].get("long", {}).get("budget")}
        at_main = [c for c in trained if c.budget == main]
        seeds = {(c.algo, c.config): len({d.seed for d in at_main if d.config == c.config}) for c in at_main}
        # both families of SarsaAAC everywhere but on HFO (DeepPolicy only); a headline pair (two learners with >= 10
        # seeds) on every env
        assert ("SarsaAAC", "deep") in seeds and (("SarsaAAC", "tile") in seeds or env_id == HFO_ID), env_id
        assert len({algo for (algo, _), n in seeds.items() if n >= MIN_SEEDS}) >= 2, env_id
        # a tuned twin has the headline's seeds and exactly the study it reads
        tuned = {(algo, config.removesuffix("-tuned")) for algo, config in seeds if is_tuned(config)}
        assert all(seeds[(algo, config + "-tuned")] >= MIN_SEEDS for algo, config in tuned)
        assert tuned == {(algo, config) for e, algo, config in studies if e == env_id}, env_id
    # on the paper env every headline learner is tuned: TilePolicy, MP-DQN and TD3
    assert {("SarsaAAC", "tile"), ("MPDQN", "mpdqn"), ("TD3", "td3")} <= {
        (a, c) for e, a, c in studies if e == "RoboCupDribblePaper-v0"
    }
    assert min(len({c.seed for c in full if c.config == k}) for k in ("rbf50", "mlp2", "rbfmlp2")) >= 5
    # the long budget reaches the paper's episode counts; the wall-clock cells run the same seconds per env
    assert LONG_BUDGET >= 300_000 and WALL_CLOCK_SECONDS >= 120
    assert {(c.env_id, c.seconds) for c in full if c.seconds} == {
        ("RoboCupDribblePaper-v0", WALL_CLOCK_SECONDS),
        (HFO_ID, HFO_SECONDS),
    }
    assert all(
        len({c.seed for c in full if c.seconds and (c.env_id, c.algo) == (e, a)}) >= 5
        for e, a in {(c.env_id, c.algo) for c in full if c.seconds}
    )
    assert select(full, "*SarsaAAC-rbf*") and all("rbf" in c.config for c in select(full, "*SarsaAAC-rbf*"))


# ---------------------------------------------------------------------------------------------------------------------
# The report from synthetic cell files
# ---------------------------------------------------------------------------------------------------------------------


def synthetic_scores(env_id: str, d: float) -> dict:
    """A summary with score ``d`` in the env's metric (the other episodic keys follow from it)."""
    if domains.metric(env_id) == "success_share":
        return {"return_mean": 50 * d - 10, "return_median": 50 * d - 10, "success_share": d}
    if not domains.is_dribbling(env_id):
        return {"return_mean": d, "return_median": d, "success_share": float(d > 0.99)}
    return {
        "distance_mean": d,
        "distance_median": d,
        "distance_max": d + 5,
        "reach20_share": float(d > 20),
        "ball_loss_rate": 0.3,
    }


def synthetic_cell(
    env_id: str, algo: str, config: str, seed: int, final: float, family: str, algo_config: dict | None = None
) -> dict:
    """A finished cell's file whose learning curve rises from ``start`` (0, or -1 for Moving-like returns) to about
    ``final``, seeds spread a little; ``algo_config`` as recorded (default: a stand-in)."""
    rate = {"rbf10": 0.004, "mlp2": 0.001}.get(config, 0.0005)
    episodes = np.arange(0, 12_001, 500)
    spread = 0.3 if domains.is_dribbling(env_id) else 0.003
    start = -1.0 if env_id in ("Moving-v0", "Sliding-v0") else 0.0
    distances = start + (final - start) * (1 - np.exp(-rate * episodes)) + spread * seed
    curve = [
        {
            "episodes": int(e),
            "env_steps": int(e * 14),
            "wall_s": e / 500,
            "train_s": e / 600,
            **synthetic_scores(env_id, float(d)),
        }
        for e, d in zip(episodes, distances, strict=True)
    ]
    cell = Cell(env_id, algo, config, seed, 168_000)
    return {
        "cell_id": cell.cell_id,
        "cell": cell.to_dict(),
        "family": family,
        "command": "python -m benchmarks.run --preset full",
        "algo_config": algo_config
        or {
            "SarsaAAC": {},
            "MPDQN": {"kwargs": {}, "other": "hyperparams/mpdqn.yml"},
        }.get(algo, {"n_envs": 8, "wrapper": "flatten", "kwargs": {}}),
        "versions": {"python": "3.11"},
        "machine": {"cpu": "test CPU", "cores": 2, "platform": "linux", "torch_threads": 1},
        "started": "2026-01-01T00:00:00",
        "curve": curve,
        "final": {"episodes": 1000, **synthetic_scores(env_id, float(distances[-1]))},
        "env_steps": 168_000,
        "episodes": 12_000,
        "train_wall_s": 20.0,
        "eval_wall_s": 2.0,
        "predict_us": 40.0 if algo == "SarsaAAC" else 300.0,
        "wall_s": 22.0,
        "loadavg": {"start": 2.0, "end": 2.5},
        "model": f"models/{cell.cell_id}.zip",
    }


def test_report_from_synthetic_cells(tmp_path):
    cells_dir = tmp_path / "cells"
    cells_dir.mkdir()
    results = [synthetic_cell(ENV_ID, "SarsaAAC", "rbf10", s, 24.0, "RBF") for s in range(10)]  # 10 seeds: a verdict
    results += [synthetic_cell(ENV_ID, "SarsaAAC", "mlp2", s, 15.0, "MLP") for s in range(3)]
    results += [synthetic_cell(ENV_ID, "DQN", "dqn", s, 26.0, "baseline") for s in range(10)]
    results += [synthetic_cell(ENV_ID, "MPDQN", "mpdqn", s, 24.0, "peer") for s in range(10)]  # the same as SarsaAAC
    results += [synthetic_cell("Platform-v0", "SarsaAAC", "tile", s, 0.95, "Tiles") for s in range(10)]
    results += [synthetic_cell("Platform-v0", "MPDQN", "mpdqn", s, 0.99, "peer") for s in range(10)]
    reference = {
        "cell_id": "paper__reference",
        "cell": Cell(ENV_ID, "Reference", "references").to_dict(),
        "family": "reference",
        "references": {
            "handcoded": {
                "final": {
                    "episodes": 1000,
                    "distance_mean": 13.0,
                    "distance_median": 16.0,
                    "distance_max": 27.0,
                    "reach20_share": 0.1,
                    "ball_loss_rate": 0.5,
                },
                "predict_us": 900.0,
            },
            "bound": {
                "label": "upper bound (any policy)",
                "episodes": 1000,
                "mean": 44.7,
                "median": 45.0,
                "min": 39.8,
                "max": 47.6,
            },
        },
        "wall_s": 5.0,
    }
    for r in [*results, reference]:
        (cells_dir / f"{r['cell_id']}.json").write_text(json.dumps(r))
    counts = np.zeros(60, dtype=int)
    counts[[3, 15, 19, 22]] = [1000, 2000, 3000, 4000]
    entry = {
        "cell_id": results[0]["cell_id"],
        "players": 10_000,
        "distance_mean": 17.0,
        "distance_median": 19.0,
        "distance_max": 23.0,
        "share_at_least": {"8": 0.9, "16": 0.7, "18": 0.7, "20": 0.4, "25": 0.0},
        "ball_loss_rate": 0.6,
        "histogram": {"bin_metres": 1.0, "counts": counts.tolist()},
    }
    (tmp_path / "reliability.json").write_text(
        json.dumps({"seed": 30_000, "envs": {ENV_ID: {"sarsa_aac": entry, "handcoded": {**entry, "cell_id": "hand-coded"}}}})
    )

    text = build_report(tmp_path).read_text()
    for needle in (
        "| config |",
        "final distance (m), IQM [95% CI]",
        "episodes to 20 m",
        "decision cost (us/action)",
        "hand-coded dribbler",
        "upper bound (any policy)",
        "paper's claim",
        "RBF arrays: 25 m in under 10,000 episodes",
        "most players run at least 18 m",
        "70.0% of 10,000 players",
        "python -m benchmarks.run --preset full",
        "test CPU",
        "168,000 env steps",
    ):
        assert needle in text, needle
    # the baseline is better here, MP-DQN the same, and the report must say so
    assert "**DQN better**" in text and "Welch p" in text
    peer_line = next(line for line in text.splitlines() if "vs the best parameterized peer, MPDQN" in line)
    assert "at equal env steps (168,000) no significant difference" in peer_line
    assert "too few seeds (< 5)" in text  # the MLP claim rests on 3 seeds: no verdict
    # Platform: the published figures as references, and MP-DQN better than SarsaAAC here
    assert "Platform-v0" in text and "0.987" in text and "Bester" in text
    platform = text[text.index("- **Platform-v0**") :]
    assert "**MPDQN better**" in platform.split("\n- ")[0]
    assert "not reached" in text  # MLP never reaches 20 m
    for name in ("fig_mlp.png", "fig_rbf.png", "fig_best.png", "fig_final.png", "fig_reliability.png"):
        assert (tmp_path / name).stat().st_size > 10_000, name


def test_every_domain_has_a_title_and_reach_marks_in_the_report():
    """A results folder of any preset's env can be reported (the HFO preset's once failed on a missing mark)."""
    from benchmarks.report_text import env_title, reach_marks

    for env_id in ENV_IDS:
        low, high = reach_marks(env_id)
        assert low < high
        assert env_title(env_id).startswith(f"{env_id} (")


def test_report_covers_the_new_learners_and_domains(tmp_path):
    """DeepPolicy and HybridPPO cells, Goal (ranked by P(goal)) and Moving (returns that start below 0): their tables,
    published figures, verdicts and figures; each cell's settings as the runner records them."""
    from benchmarks.execution import algo_config

    def cells(env_id: str, algo: str, config: str, final: float, family: str, seeds: int = 10) -> list[dict]:
        recorded = algo_config(Cell(env_id, algo, config, 0, 100_000))
        return [synthetic_cell(env_id, algo, config, s, final, family, recorded) for s in range(seeds)]

    results = [
        *cells("Goal-v0", "SarsaAAC", "tile", 0.60, "Tiles"),
        *cells("Goal-v0", "SarsaAAC", "deep", 0.75, "Deep"),
        *cells("Goal-v0", "MPDQN", "mpdqn", 0.70, "peer"),
        *cells("Goal-v0", "HybridPPO", "hybridppo", 0.20, "peer", seeds=3),
        *cells("Goal-v0", "TD3", "td3", 0.30, "baseline"),
        *cells("Moving-v0", "SarsaAAC", "tile", 1.20, "Tiles"),
        *cells("Moving-v0", "SarsaAAC", "deep", 1.00, "Deep"),
        *cells("Moving-v0", "MPDQN", "mpdqn", 0.80, "peer"),
        *cells("Moving-v0", "HybridPPO", "hybridppo", 1.60, "peer"),
        *cells("Moving-v0", "PPO", "ppo", 1.10, "baseline"),
    ]
    for r in results:  # an env with evaluation sizes of its own (the full preset's episodic domains)
        if r["cell"]["env_id"] == "Goal-v0":
            r["cell"].update(eval_episodes=50, final_episodes=500)
    (tmp_path / "cells").mkdir()
    for r in results:
        (tmp_path / "cells" / f"{r['cell_id']}.json").write_text(json.dumps(r))
    text = build_report(tmp_path).read_text()
    for needle in (
        "### Goal-v0 (Masson et al.'s Robot Soccer Goal, hybrid_domains)",
        "### Moving-v0 (gym-hybrid's Moving, hybrid_domains)",
        "final P(goal), IQM [95% CI]",
        "final mean return, IQM [95% CI]",
        "DeepPolicy",
        "*MP-DQN (mean over seeds), published* | - | - | - | 0.789",
        "*H-PPO (mean of 5 seeds, read off a plot), published* | - | - | - | 1.700",
        "episodes to 0.7",
        "episodes to 1.5",
        "HybridPPO (Moving-v0): hyperparams/hppo.yml (Platform-v0; no entry for Moving-v0)",
        "- **Episodes per curve point / final evaluation**: Goal-v0: 50 / 500; Moving-v0: 100 / 1,000.",
        "- **Final evaluation**: the greedy episodes of another fixed set",
        "MPDQN (Goal-v0): hyperparams/mpdqn.yml (Goal-v0, the reference code's initial parameter policy)",
        "MPDQN (Moving-v0): MPDQN defaults (no entry for Moving-v0 in hyperparams/mpdqn.yml)",
        "SarsaAAC** runs with its defaults on 16 lanes",
    ):
        assert needle in text, needle
    assert "Bester" in text and "0.987" not in text  # no Platform figures without Platform cells
    goal = text[text.index("- **Goal-v0**") :].split("\n- **")[0]
    assert "best SarsaAAC config, DeepPolicy" in goal
    assert "vs the best parameterized peer, MPDQN" in goal and "**SarsaAAC deep better**" in goal
    assert "against MP-DQN (mean over seeds)'s published 0.789" in goal
    moving = text[text.index("- **Moving-v0**") :].split("\n- **")[0]
    assert "vs the best parameterized peer, HybridPPO" in moving and "**HybridPPO better**" in moving
    assert "against H-PPO (mean of 5 seeds, read off a plot)'s published 1.7" in moving
    policies = text.split("## SarsaAAC's policies across the domains")[1].split("\n## ")[0]
    assert "DeepPolicy better on 1 env(s), TilePolicy better on 1, no significant difference on 0" in policies
    goal_row = next(line for line in policies.splitlines() if line.startswith("| Goal-v0 |"))
    assert (
        "**DeepPolicy better**" in goal_row
        and "(10 seeds)" in goal_row
        and "DeepPolicy - TilePolicy: means +0.150" in goal_row
    )
    moving_row = next(line for line in policies.splitlines() if line.startswith("| Moving-v0 |"))
    assert "**TilePolicy better**" in moving_row
    # relative scores: Goal's learners span 0.20-0.75 (Tile 0.60, Deep 0.75), Moving's 0.80-1.60 (Tile 1.20, Deep 1.00)
    assert "| 0.73 / 1.00 |" in goal_row and "| 0.50 / 0.25 |" in moving_row
    # means (0.727 + 0.5) / 2 = 0.614 and (1 + 0.25) / 2 = 0.625: DeepPolicy's, by a hair
    assert "Mean over the envs: TilePolicy 0.6" in policies and "is **DeepPolicy**" in policies
    for name in ("fig_best.png", "fig_final.png"):
        assert (tmp_path / name).stat().st_size > 10_000, name


def test_the_recommended_policy_is_the_one_the_committed_results_pick():
    """The "(recommended)" label and ``sb3-aac train``'s default SarsaAAC policy are the policy the report's rule picks
    from the committed results (the higher mean score relative to each env's best learner)."""
    from benchmarks.presets import CONFIG_LABELS
    from benchmarks.report import group_results, read_inputs
    from benchmarks.report_budgets import POLICY_CANDIDATES, recommended_policy, split_views
    from sb3_aac.common.algorithms import ALGOS

    results, _, _ = read_inputs(Path(__file__).resolve().parents[1] / "benchmarks" / "results")
    groups, _ = split_views(group_results(results)[0])
    name = recommended_policy(groups)
    assert name is not None and ALGOS["sarsa_aac"].default_policy == name
    config = next(c for c, n in POLICY_CANDIDATES if n == name)
    assert [c for c, label in CONFIG_LABELS.items() if "(recommended)" in label] == [config]
    assert CONFIG_LABELS[config] == f"{name} (recommended)"


@pytest.mark.parametrize("algo", ["MPDQN", "PDQN"])
def test_the_deep_q_peers_take_the_reference_settings_env_and_start_on_goal(algo):
    from benchmarks.models import build_model
    from benchmarks.models import PassthroughPolicy
    from hybrid_domains.reference_inputs import ScaleReward

    goal, _, _ = build_model(Cell("Goal-v0", algo, algo.lower(), 0, 1000))
    assert isinstance(goal.policy, PassthroughPolicy) and goal.gamma == 0.95 and goal.gradient_steps == 4
    assert goal.policy.multi_pass == (algo == "MPDQN")
    lane = goal.get_env().envs[0]
    while not isinstance(lane, ScaleReward):
        lane = lane.env
    assert lane.scale == 0.02
    assert goal.observation_space == domains.episodic_env("Goal-v0").observation_space  # scored on what it saw


def test_the_peers_without_an_entry_take_the_stated_fallback():
    """HybridPPO on Moving: hppo.yml's Platform entry (the rule of all its entries) on the domain's env; MP-DQN on
    Moving: its defaults."""
    from benchmarks.models import build_model

    hppo, _, _ = build_model(Cell("Moving-v0", "HybridPPO", "hybridppo", 0, 1000))
    assert (hppo.n_envs, hppo.n_steps, hppo.batch_size, hppo.ent_coef) == (8, 256, 256, 0.01)
    assert hppo.observation_space == domains.episodic_env("Moving-v0").observation_space
    moving, _, _ = build_model(Cell("Moving-v0", "MPDQN", "mpdqn", 0, 1000))
    assert (moving.gamma, moving.learning_starts, moving.buffer_size) == (0.99, 500, 100_000)  # MPDQN's defaults


def test_the_finished_cells_of_the_results_are_cells_of_the_full_preset(monkeypatch):
    """Adding learners and domains keeps every finished cell's id and definition, a tuned cell's with the settings of
    the committed tuned file: a rerun skips them."""
    from benchmarks.tuned import TUNED_DIR_VAR, resolve_tuned

    monkeypatch.delenv(TUNED_DIR_VAR, raising=False)  # the committed hyperparams/tuned (a --tuned-dir run sets it)

    out = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    files = sorted((out / "cells").glob("*.json"))
    full = {cell.cell_id: cell for cell in resolve_tuned(build_cells("full"))}
    assert files and all(path.stem in full for path in files)
    assert all(cell_files.is_finished(out, full[path.stem]) for path in files)


def test_the_quick_preset_runs_and_reports(tmp_path):
    """The CI-sized preset end to end, as documented: the sweep, then the report."""
    from benchmarks import report as bench_report

    out = tmp_path / "quick"
    assert bench_run.main(["--preset", "quick", "--out", str(out), "--workers", "1", "--allow-dirty"]) == 0
    cells = sorted(p.name for p in (out / "cells").glob("*.json"))
    assert len(cells) == len(build_cells("quick"))
    assert bench_report.main([str(out)]) == 0
    text = (out / "report.md").read_text()
    assert "TilePolicy" in text and "PPO" in text and "hand-coded" in text
    assert str(tmp_path) not in text, "the report names no path of the machine that made it"
    assert (out / "fig_best.png").stat().st_size > 10_000


def test_a_claim_is_not_refuted_by_runs_that_stopped_before_it():
    from benchmarks.groups import Group
    from benchmarks.report_text import _reach_claim

    runs = [synthetic_cell(ENV_ID, "SarsaAAC", "mlp2", s, 12.0, "MLP") for s in range(5)]
    for r in runs:
        r["curve"] = [p for p in r["curve"] if p["episodes"] <= 8_000]  # stopped at 8,000 episodes
    group = Group(ENV_ID, "SarsaAAC", "mlp2", 168_000, runs)
    assert _reach_claim(group, 16.0, None, after=40_000)[1] == "not tested (runs ended before 40,000 episodes)"
    assert _reach_claim(group, 16.0, 15_000)[1] == "not tested (runs ended before 15,000 episodes)"
    assert _reach_claim(group, 16.0, None)[1] == "not met"  # a claim about the end of these runs is refuted
    assert _reach_claim(group, 1.0, 15_000)[1] == "met"  # reached before stopping: met whatever came later


@pytest.mark.parametrize(
    ("field", "value"),
    [("final", {"distance_mean": "25 m"}), ("curve", [{"episodes": None}]), ("env_steps", -1), ("wall_s", "fast")],
)
def test_a_cell_file_with_a_wrong_typed_field_is_damaged(tmp_path, field, value):
    result = synthetic_cell(ENV_ID, "SarsaAAC", "rbf10", 0, 20.0, "RBF")
    path = cell_files.cell_path(tmp_path, result["cell_id"])
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps({**result, field: value}))
    cell = Cell.from_dict(result["cell"])
    with pytest.warns(UserWarning, match=f"wrong-typed fields: {field}"):
        assert not cell_files.is_finished(tmp_path, cell)  # so the runner computes it again
    results, damaged = cell_files.read_cells(tmp_path)
    assert results == [] and len(damaged) == 1 and field in damaged[0]  # the report names it instead of crashing
    path.write_text(json.dumps(result))
    assert cell_files.is_finished(tmp_path, cell)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--only", "no-such-cell"], "matches none of the"),
        (["--only", ""], "expected at least one pattern"),
        (["--only", " , "], "expected at least one pattern"),
        (["--workers", "-3"], "must be >= 1"),
        (["--workers", "two"], "expected a whole number"),
        (["--players", "0"], "must be >= 1"),
        (["--only", "PPO", "--set", "gamma=0.9"], "--set applies to untuned SarsaAAC cells only"),
        (["--only", "tile", "--set", "gama=0.9"], "unknown --set key 'gama'"),
        (["--only", "tile", "--set", "gamma"], "expected key=value"),
        (["--set", "gamma=0.9", "--estimate"], "--set belongs to a grid run"),
    ],
)
def test_runner_refuses_bad_arguments_before_any_work(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as info:
        bench_run.main(["--preset", "quick", "--out", str(tmp_path / "out"), *argv])
    assert info.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out" / "cells").exists()


def test_set_runs_the_selected_sarsa_aac_cells_with_the_keyword_arguments(tmp_path, monkeypatch):
    ran: list[Cell] = []

    def fake_grid(grid, out, workers, engine=None):
        ran.extend(grid)
        return {"done": [c.cell_id for c in grid], "skipped": [], "failed": [], "busy": []}

    monkeypatch.setattr(bench_run, "run_grid", fake_grid)
    argv = ["--preset", "quick", "--only", "tile", "--set", "gamma=0.5", "--set", "n_tilings=4", "--allow-dirty"]
    assert bench_run.main([*argv, "--out", str(tmp_path)]) == 0
    assert [c.cell_id for c in ran] == [c.cell_id for c in select(build_cells("quick"), "tile")]
    assert all(c.overrides == {"gamma": 0.5, "policy_kwargs": {"n_tilings": 4}} for c in ran)
    model, _, _ = build_model(ran[0])
    assert model.gamma == 0.5 and model.policy.n_tilings == 4
    model.env.close()


def test_runner_refuses_an_unwritable_out(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit) as info:
        bench_run.main(["--preset", "quick", "--out", str(tmp_path / "file" / "out")])
    assert info.value.code == 2 and "cannot write --out" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("make", "named"), [("runs.jsonl", "'runs.jsonl' is not a regular file"), ("locks", "'locks' is not a folder")]
)
def test_runner_refuses_a_results_folder_whose_entries_are_in_the_way(tmp_path, capsys, make, named):
    if make == "runs.jsonl":
        (tmp_path / make).mkdir()
    else:
        (tmp_path / make).write_text("a file where the run keeps its lock files")
    with pytest.raises(SystemExit) as info:
        bench_run.main(["--preset", "quick", "--out", str(tmp_path), "--allow-dirty"])
    assert info.value.code == 2 and named in capsys.readouterr().err
    assert not (tmp_path / "cells").exists()


def test_runner_gives_up_on_an_address_where_no_ray_cluster_listens(tmp_path, capsys):
    import socket
    import time

    with socket.socket() as probe:  # a port nobody listens on (bound, then released)
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    start = time.monotonic()
    argv = ["--preset", "quick", "--out", str(tmp_path), "--engine", "ray", "--address", f"127.0.0.1:{port}", "--allow-dirty"]
    assert bench_run.main(argv) == 2
    assert time.monotonic() - start < 30
    err = capsys.readouterr().err
    assert f"no Ray cluster answers at 127.0.0.1:{port}" in err and "ray start --head" in err


def test_the_report_shows_commands_without_their_out_directory():
    from benchmarks.report_text import portable_command

    assert portable_command("python -m benchmarks.run --preset full --out /work/x --workers 2") == (
        "python -m benchmarks.run --preset full --out DIR --workers 2"
    )
    assert (
        portable_command("python -m benchmarks.run --out=/tmp/y --only 'a,b'")
        == "python -m benchmarks.run --out=DIR --only a,b"
    )


def test_the_speed_comparison_with_an_earlier_commit_runs_both_trees_and_cleans_up(capsys):
    """``benchmarks.speed.versus`` against HEAD itself (the machinery, not a figure): one pair of HybridPPO runs, the
    ratio line, and no worktree left behind; a name that is no commit is refused before anything runs."""
    import subprocess

    from benchmarks.speed import versus

    root = Path(__file__).resolve().parents[1]
    before = subprocess.run(["git", "worktree", "list"], cwd=root, capture_output=True, text=True).stdout
    assert versus.main(["HEAD", "--algos", "HybridPPO", "--repeats", "1", "--scale", "0.1"]) == 0
    out = capsys.readouterr().out
    assert "HybridPPO this checkout" in out and "x the earlier commit's env steps/s (median of 1 pairs)" in out
    assert subprocess.run(["git", "worktree", "list"], cwd=root, capture_output=True, text=True).stdout == before
    with pytest.raises(SystemExit):
        versus.main(["no-such-revision-xyz"])
    assert "names no commit" in capsys.readouterr().err


def test_wall_clock_horizons_leave_the_clock_to_end_training():
    """Each wall-clock cell's env-step horizon exceeds what its learner stepped per second of training in the committed
    runs of that cell (any seed) times its seconds, so the clock, not the horizon, ends the next run at those rates."""

    def learner(cell: Cell) -> tuple[str, str, str, int]:
        return cell.env_id, cell.algo, cell.config, cell.seconds

    committed = cell_files.load_cells(Path(__file__).resolve().parents[1] / "benchmarks" / "results")
    cells = [c for c in build_cells("full") if c.seconds]
    assert cells
    for cell in cells:
        runs = [r for r in committed if learner(Cell.from_dict(r["cell"])) == learner(cell)]
        assert runs, cell.cell_id
        fastest = max(r["env_steps"] / r["train_wall_s"] for r in runs)
        assert cell.budget > fastest * cell.seconds, (cell.cell_id, cell.budget, fastest)
