"""Rendered bodies: real pixels of the Ant, walking individuals side by side, GIFs."""

import io

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from PIL import Image

from sgb.experiments import fig3
from sgb.paths import committed_results
from sgb.provenance import read_results
from sgb.rl.envs import EnvSpec
from sgb.rl.population import episode_returns
from sgb.rl.protocols import load_agent
from sgb.rl.render import initial_pose, to_gif, walking_frames


def _body_pixels(frame: np.ndarray) -> int:
    """Pixels of the Ant's brown body colour (red clearly above blue)."""
    r, g, b = (frame[..., i].astype(int) for i in range(3))
    return int(np.sum((r - b > 25) & (r > 60)))


def test_initial_pose_shows_a_body_and_longer_legs_show_more_of_it():
    normal = initial_pose(EnvSpec("ant", "spring", "normal"), width=160, height=120)
    long_legs = initial_pose(EnvSpec("ant", "spring", "long_legs"), width=160, height=120)
    assert normal.shape == (120, 160, 3) and normal.dtype == np.uint8
    assert _body_pixels(normal) > 200
    assert _body_pixels(long_legs) > _body_pixels(normal)


def test_best_checkpoint_is_the_sgb_run_with_the_highest_return():
    best = fig3.best_checkpoint(committed_results(), "ant")
    runs = read_results(committed_results() / "rl" / "fig3_ant_cpu.json")["results"]["runs"]
    returns = {r["checkpoint"]: r["final_return"] for r in runs if r["cell_types"] is not None}
    assert best.name == max(returns, key=returns.get) and best.exists()
    assert len(returns) > 1  # a choice among several SGB runs


def test_walking_frames_tile_individuals_that_move_and_score_them_as_the_population_does():
    checkpoint = fig3.best_checkpoint(committed_results(), "ant")
    frames, returns = walking_frames(
        checkpoint, n_individuals=2, steps=6, every=3, width=64, height=48
    )
    assert frames.shape == (3, 48, 128, 3)
    assert all(_body_pixels(panel) > 20 for panel in (frames[0, :, :64], frames[0, :, 64:]))
    assert np.any(frames[0] != frames[-1])
    # the population's own rollout of the same individuals from the same initial state
    ppo, actor, normalizer = load_agent(checkpoint)
    ind_key, reset_key = jax.random.split(jax.random.PRNGKey(0))
    reset_keys = jnp.broadcast_to(reset_key, (2, 1, *reset_key.shape))
    keys = jax.random.split(ind_key, 2)
    args = (ppo.env, ppo.network.architecture, actor, normalizer, keys, reset_keys, 6, None)
    assert returns.shape == (2,) and returns[0] != returns[1]
    np.testing.assert_allclose(returns, np.asarray(episode_returns(*args))[:, 0], rtol=1e-4)
    with pytest.raises(ValueError, match="positive"):
        walking_frames(checkpoint, n_individuals=0)


def test_gif_holds_every_frame():
    frames = np.zeros((3, 8, 8, 3), np.uint8)
    frames[1, :4] = 255
    frames[2, 4:] = 128
    gif = Image.open(io.BytesIO(to_gif(frames, seconds_per_frame=0.05)))
    assert gif.format == "GIF" and gif.n_frames == 3


def test_importing_the_rl_package_prints_nothing():
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-c", "import sgb.rl.envs, sgb.rl.render"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == ""
