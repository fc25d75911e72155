"""Environment variants: the long-leg Ant really has longer legs; niches change the physics."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb.rl.envs import LEG_SCALE, EnvSpec, leg_lengths, make_env


def _sys(variant):
    return make_env(EnvSpec("ant", "spring", variant)).sys


def test_long_legs_are_longer_by_the_scale():
    normal = leg_lengths(make_env(EnvSpec("ant", "spring")))
    long = leg_lengths(make_env(EnvSpec("ant", "spring", "long_legs")))
    assert normal.shape == (4,)
    np.testing.assert_allclose(long / normal, LEG_SCALE, rtol=1e-5)
    # capsule half-lengths of the leg segments scale too, radii do not
    size_n, size_l = np.asarray(_sys("normal").geom_size), np.asarray(_sys("long_legs").geom_size)
    capsules = np.asarray(_sys("normal").geom_type) == 3
    np.testing.assert_allclose(size_l[capsules, 1] / size_n[capsules, 1], LEG_SCALE, rtol=1e-5)
    np.testing.assert_allclose(size_l[capsules, 0], size_n[capsules, 0])
    # the torso starts higher and the legs are heavier
    assert float(_sys("long_legs").init_q[2]) == pytest.approx(0.55 * LEG_SCALE)
    assert np.asarray(_sys("long_legs").body_mass)[2] > np.asarray(_sys("normal").body_mass)[2]


def test_niches_change_only_their_physics():
    normal, slippery, low_g = _sys("normal"), _sys("slippery"), _sys("low_gravity")
    np.testing.assert_allclose(
        np.asarray(slippery.geom_friction)[:, 0], 0.25 * np.asarray(normal.geom_friction)[:, 0]
    )
    np.testing.assert_allclose(np.asarray(low_g.opt.gravity), 0.5 * np.asarray(normal.opt.gravity))
    np.testing.assert_array_equal(np.asarray(low_g.geom_size), np.asarray(normal.geom_size))
    assert float(normal.opt.timestep) == float(slippery.opt.timestep) == 0.005  # spring tuning kept


def test_low_gravity_changes_the_fall():
    """Dropped with zero torques, the torso falls more slowly under half gravity."""
    heights = {}
    for variant in ("normal", "low_gravity"):
        env = make_env(EnvSpec("ant", "spring", variant))
        state = env.reset(jax.random.PRNGKey(0))
        for _ in range(3):
            state = env.step(state, jnp.zeros(env.action_size))
        heights[variant] = float(state.pipeline_state.x.pos[0, 2])
    assert heights["low_gravity"] > heights["normal"]


def test_bad_spec_raises():
    with pytest.raises(ValueError, match="variant"):
        EnvSpec("ant", "spring", "moon")
    with pytest.raises(ValueError, match="ant only"):
        EnvSpec("halfcheetah", "spring", "long_legs")


def test_ppo_on_the_ant_compiles_its_training_step_once():
    # Brax's step returns weakly typed leaves; left as they are, the second chunk of
    # iterations would compile the whole training step again.
    from sgb.rl.ppo import PPOConfig, train, train_iterations

    config = PPOConfig(
        env=EnvSpec("ant", "spring"),
        total_steps=3 * 8 * 4,
        num_envs=8,
        unroll_length=4,
        num_minibatches=2,
        num_evals=3,
        eval_individuals=2,
        episode_length=8,
    )
    before = train_iterations._cache_size()
    train(config, seed=0, progress=False)
    assert train_iterations._cache_size() == before + 1
