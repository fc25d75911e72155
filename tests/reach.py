"""A cheap Brax environment for the PPO tests, registered as ``reach``, and its PPO settings."""

from dataclasses import replace

import brax.envs
import jax
import jax.numpy as jnp
import pytest
from brax.envs.base import Env, State

from sgb.rl.agent import NetworkConfig
from sgb.rl.envs import EnvSpec
from sgb.rl.ppo import PPOConfig

EPISODE = 32
SGB_TYPES = 16
# Tests that train SGB agents of ``reach_config(SGB_TYPES)`` run on one xdist worker
# (``--dist loadgroup``), where they share one compiled training step.
SHARED_STEP = pytest.mark.xdist_group("reach_sgb_step")


class Reach(Env):
    """A point on a line moves by 0.1 * action per step towards a random target.

    obs = (position, target - position); reward = -|target - position|; its metrics are
    ``x_velocity``, the step's move, 0.1 * action (as Brax's bodies report theirs), and
    ``reward_ctrl``, -0.01 * action^2, a control cost it reports but does not charge.
    Standing still earns about -32 * E|d| = -21 per episode; an optimal agent about -3.
    """

    def __init__(self, **kwargs):
        del kwargs

    def reset(self, rng: jax.Array) -> State:
        pos, target = jax.random.uniform(rng, (2,), minval=-1.0, maxval=1.0)
        obs = jnp.array([pos, target - pos])
        metrics = {"x_velocity": jnp.zeros(()), "reward_ctrl": jnp.zeros(())}
        return State(None, obs, jnp.zeros(()), jnp.zeros(()), metrics, {})

    def step(self, state: State, action: jax.Array) -> State:
        pos = state.obs[0] + 0.1 * action[0]
        target = state.obs[0] + state.obs[1]
        obs = jnp.array([pos, target - pos])
        metrics = {"x_velocity": 0.1 * action[0], "reward_ctrl": -0.01 * action[0] ** 2}
        return state.replace(obs=obs, reward=-jnp.abs(target - pos), metrics=metrics)

    @property
    def observation_size(self) -> int:
        return 2

    @property
    def action_size(self) -> int:
        return 1

    @property
    def backend(self) -> str:
        return "none"


brax.envs.register_environment("reach", Reach)
SPEC = EnvSpec("reach", "none")


def reach_config(cell_types: int | None = None, **kwargs) -> PPOConfig:
    """PPO on Reach with two hidden layers of 32; ``kwargs`` override any setting."""
    defaults = dict(
        env=SPEC,
        network=NetworkConfig(hidden=(32, 32), cell_types=cell_types),
        total_steps=2**15,
        num_envs=64,
        unroll_length=8,
        num_minibatches=4,
        episode_length=EPISODE,
        reward_scaling=1.0,
        num_evals=2,
        eval_individuals=16,
        kl_coef=1e-6,
    )
    defaults.update(kwargs)
    return PPOConfig(**defaults)


def shared_step_config(**kwargs) -> PPOConfig:
    """``reach_config(SGB_TYPES)`` cut to its first chunk of iterations, evaluated once: the
    same compiled training step (same settings and chunk length); ``kwargs`` may change
    only what the step does not read (``rho_init``, ``eval_individuals``)."""
    full = reach_config(SGB_TYPES)
    chunk = full.iterations // full.num_evals
    return replace(full, total_steps=chunk * full.steps_per_iteration, num_evals=1, **kwargs)
