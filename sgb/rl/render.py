"""Pictures of Brax bodies with MuJoCo's offscreen renderer: still images and walking GIFs.

MuJoCo renders through a headless OpenGL (EGL on Linux, see ``sgb.rl.envs``). Frames are
RGB arrays of shape (height, width, 3), uint8.
"""

import functools
import io
from pathlib import Path

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from PIL import Image

from sgb.rl import checkpoints
from sgb.rl.agent import Architecture, make_agent
from sgb.rl.envs import EnvSpec, make_env, variant_xml
from sgb.rl.normalizer import Normalizer

CAMERA = "track"  # the Ant's camera, following its centre of mass from the side


@functools.cache
def mj_model(spec: EnvSpec) -> mujoco.MjModel:
    """The MuJoCo model of the body of ``spec``, from its variant's own MJCF."""
    return mujoco.MjModel.from_xml_string(variant_xml(spec.name, spec.variant))


def render_poses(
    spec: EnvSpec, qpos: np.ndarray, width: int = 320, height: int = 240
) -> np.ndarray:
    """Frames (T, height, width, 3) of the body of ``spec`` at joint positions ``qpos`` (T, nq)."""
    model = mj_model(spec)
    data = mujoco.MjData(model)
    camera = CAMERA if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, CAMERA) >= 0 else -1
    frames = []
    with mujoco.Renderer(model, height=height, width=width) as renderer:
        for q in np.asarray(qpos):
            data.qpos[:] = q
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera)
            frames.append(renderer.render().copy())
    return np.stack(frames)


def initial_pose(spec: EnvSpec, width: int = 320, height: int = 240) -> np.ndarray:
    """One frame (height, width, 3) of the body of ``spec`` in Brax's initial pose."""
    model = mj_model(spec)
    qpos = model.numeric("init_qpos").data if model.nnumeric else model.qpos0
    return render_poses(spec, np.asarray(qpos)[None], width, height)[0]


@functools.partial(jax.jit, static_argnames=("spec", "architecture", "steps"))
def _trajectories(
    spec: EnvSpec,
    architecture: Architecture,
    actor_params: dict,
    normalizer: Normalizer,
    ind_keys: jax.Array,
    reset_key: jax.Array,
    steps: int,
) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Joint positions (N, steps + 1, nq) of N individuals from one shared initial state, and
    their returns (N,) over the ``steps``, summed until each one's episode ends."""
    env = make_env(spec)
    agent = make_agent(architecture, env.observation_size, env.action_size)
    layers = agent.actor.layers(actor_params, jax.vmap(agent.actor.draw)(ind_keys))
    n = ind_keys.shape[0]
    state = jax.vmap(env.reset)(jnp.broadcast_to(reset_key, (n, *reset_key.shape)))

    def step(carry, _):
        state, total, alive = carry
        loc, _ = agent.policy(layers, normalizer, state.obs)
        state = jax.vmap(env.step)(state, jnp.tanh(loc))
        total = total + alive * state.reward
        alive = alive * (1.0 - state.done)
        return (state, total, alive), state.pipeline_state.q

    carry = (state, jnp.zeros(n), jnp.ones(n))
    (_, total, _), qs = jax.lax.scan(step, carry, None, steps)
    return jnp.concatenate([state.pipeline_state.q[None], qs]).swapaxes(0, 1), total


def walking_frames(
    checkpoint: str | Path,
    n_individuals: int = 4,
    steps: int = 100,
    every: int = 2,
    seed: int = 0,
    width: int = 200,
    height: int = 200,
) -> tuple[np.ndarray, np.ndarray]:
    """Frames (T, height, n_individuals * width, 3) of individuals side by side, and their
    returns (n_individuals,) over the clip.

    The individuals are drawn from the genome of ``checkpoint`` with keys split from
    ``seed`` and start from the same initial state; each walks ``steps`` control steps
    with deterministic actions, and every ``every``-th step is drawn. A return sums the
    rewards until its individual's episode ends (its torso leaves the healthy heights);
    the clip plays on.
    """
    if n_individuals < 1 or steps < 1 or every < 1:
        raise ValueError(
            "n_individuals, steps and every must be positive, "
            f"got {n_individuals}, {steps}, {every}"
        )
    ppo, params, normalizer, _ = checkpoints.load(checkpoint)
    ind_key, reset_key = jax.random.split(jax.random.PRNGKey(seed))
    keys = jax.random.split(ind_key, n_individuals)
    qpos, returns = _trajectories(
        ppo.env, ppo.network.architecture, params.actor, normalizer, keys, reset_key, steps
    )
    panels = [render_poses(ppo.env, q, width, height) for q in np.asarray(qpos)[:, ::every]]
    return np.concatenate(panels, axis=2), np.asarray(returns)


def to_gif(frames: np.ndarray, seconds_per_frame: float) -> bytes:
    """An endlessly looping GIF of ``frames`` (T, height, width, 3)."""
    images = [Image.fromarray(frame) for frame in frames]
    buffer = io.BytesIO()
    images[0].save(
        buffer,
        format="gif",
        save_all=True,
        append_images=images[1:],
        duration=max(20, round(1000 * seconds_per_frame)),
        loop=0,
    )
    return buffer.getvalue()
