"""``sgb.experiments.regime_gait``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

from pathlib import Path
from types import SimpleNamespace

import pytest

from sgb import grid, prose
from sgb.experiments import regime_gait
from sgb.recording import start
from sgb.rl.regime_runs import RUNS


def test_the_gait_texts_list_each_arms_speeds_and_count_the_walkers():
    """Vanilla first, then the most cell types to the fewest, their aliased pairs an arm
    of their own after the per-pair arm; a run below the walking speed is not counted as
    walking; the table names each run's arm, and its return is 1000 steps' reward over
    the episodes per environment."""

    def run(k, seed, speed, episodes=1.0, genome="authors"):
        walked = {"cell_types": k, "seed": seed, "forward_velocity": speed, "walks": speed >= 1}
        reward = speed + 1.0 - 0.5  # forward reward, upright, control cost
        return walked | {
            "genome": genome,
            "window_return": 1000 * reward / episodes,
            "forward_velocity_sem": 0.1,
            "episodes_per_env": episodes,
            "reward_per_step": reward,
            "control_cost": 0.5,
        }

    aliased = run(16, 0, 0.1, 1.2, genome="authors_aliased")
    runs = [run(16, 0, 0.4), aliased, run(None, 1, 7.0), run(128, 0, 8.0, 1.5), run(None, 0, 7.5)]
    results = regime_gait.RegimeGaitResults.model_validate({"walking_speed": 1.0, "runs": runs})
    texts = regime_gait.regime_gait(results)
    assert texts["gait_runs"] == (
        "vanilla PPO 7.50, 7.00 m/s (seeds 0, 1); 128 types 8.00 m/s (seed 0); "
        "16 types 0.40 m/s (seed 0); 16 types, pairs aliased 0.10 m/s (seed 0)"
    )
    assert texts["gait_walks"] == "3 of the 5 runs walk (at least 1 m/s)"
    assert texts["gait_episodes"] == (
        "vanilla PPO 1.00, 1.00 (seeds 0, 1); 128 types 1.50 (seed 0); 16 types 1.00 "
        "(seed 0); 16 types, pairs aliased 1.20 (seed 0)"
    )
    table = regime_gait.gait_table(SimpleNamespace(results=results))
    assert table.loc[table["forward speed (m/s)"] == 0.1, "arm"].tolist() == [
        "16 types, pairs aliased"
    ]
    made_of = 1000 * table["reward per step"] / table["episodes per environment"]
    assert table["window return"].tolist() == pytest.approx(made_of.tolist())
    assert set(regime_gait.regime_gait(None).values()) == {prose.NOT_RUN}


def test_the_queue_lists_a_gait_per_regime_run_and_waits_for_its_training(tmp_path, monkeypatch):
    """Every run of the regime's profile in its order: one played is done with its wall
    time, one landed is waiting, one whose training has not landed says so."""
    runs = RUNS["cpu"].runs
    landed = {runs[0].checkpoint("cpu"), runs[1].checkpoint("cpu")}

    def checkpoint(r, profile, out_dir):
        return Path(r.checkpoint(profile)) if r.checkpoint(profile) in landed else None

    monkeypatch.setattr(regime_gait, "_landed", checkpoint)
    recording = start(regime_gait.PROFILES, "cpu", tmp_path / "rl", "regime_gait_ant")
    played = {"cell_types": runs[0].cell_types, "seed": runs[0].seed, "genome": runs[0].genome}
    gait = {"window_return": 7000.0, "forward_velocity": 7.4, "forward_velocity_sem": 0.01}
    made_of = {"episodes_per_env": 1.0, "reward_per_step": 7.0, "control_cost": 1.4}
    record = played | gait | made_of | {"walks": True, "wall_time_s": 20.0, "git_commit": "0" * 40}
    regime_gait._write(recording, [record])
    queue = regime_gait.queued("cpu", tmp_path)
    assert queue.results == recording.path and len(queue.runs) == len(runs)
    first, second, third = queue.runs[:3]
    assert first.finished and first.wall_time_s == 20.0
    assert not second.finished and "not landed" not in second.label
    assert third.label == f"{runs[2].label} seed {runs[2].seed} (its training has not landed)"
    assert grid.describe(queue)[0] == f"  {runs[0].label} seed {runs[0].seed}: done (0 min)"
