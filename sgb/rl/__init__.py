"""Reinforcement learning with SGB actor-critics: Brax environments and variants, PPO, populations.

Modules: ``envs`` (environments, long-leg Ant, niches), ``networks`` (vanilla
and SGB actor/critic, individuals), ``normalizer`` (observation statistics),
``ppo`` (training), ``population`` (innate returns of N individuals and of
the mean network), ``checkpoints`` (save/load trained agents).
"""

import contextlib
import io
import os
import platform

# MuJoCo's offscreen renderer (sgb.rl.render) needs a headless OpenGL; on Linux that is
# EGL, chosen when mujoco is first imported.
if platform.system() == "Linux":
    os.environ.setdefault("MUJOCO_GL", "egl")

# mujoco.mjx prints a line when its optional warp backend is absent, which it is here.
with contextlib.redirect_stdout(io.StringIO()):
    import mujoco.mjx  # noqa: F401
