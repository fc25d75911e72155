"""Environment variants: the long-leg Ant really has longer legs; niches change the physics."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from brax.spring import pipeline as spring

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


@jax.jit
def _torso_height_after_drop(sys) -> jax.Array:
    """Torso height after 30 spring steps (three Ant steps) with zero torques, dropped from
    rest 0.5 m above the initial pose; ``sys`` is an argument, so every variant of one
    tree structure runs the same compilation."""
    state = spring.init(sys, sys.init_q.at[2].add(0.5), jnp.zeros(sys.qd_size()))

    def step(state, _):
        return spring.step(sys, state, jnp.zeros(sys.act_size())), None

    state, _ = jax.lax.scan(step, state, None, 30)
    return state.x.pos[0, 2]


def _arrays(variant):
    """The system of ``variant`` in the normal Ant's tree structure: the static metadata
    (the MuJoCo model object) is the normal one's, the arrays are the variant's."""
    structure = jax.tree_util.tree_structure(_sys("normal"))
    return jax.tree_util.tree_unflatten(structure, jax.tree_util.tree_leaves(_sys(variant)))


def test_low_gravity_changes_the_fall():
    """Dropped with zero torques, the torso falls more slowly under half gravity."""
    normal, low_g = (_torso_height_after_drop(_arrays(v)) for v in ("normal", "low_gravity"))
    assert float(low_g) > float(normal)
    assert _torso_height_after_drop._cache_size() == 1


def test_bad_spec_raises():
    with pytest.raises(ValueError, match="variant"):
        EnvSpec("ant", "spring", "moon")
    with pytest.raises(ValueError, match="ant only"):
        EnvSpec("halfcheetah", "spring", "long_legs")
