"""Brax environments and their variants: longer Ant legs and two physical niches.

Every variant is made by editing the environment's own MJCF model (the XML
shipped with Brax) and loading it again with ``brax.io.mjcf.loads``. The model
arrays that the edit changes (body positions, geom sizes, masses, inertias,
initial pose, friction...) are then copied into the environment's system, so
the backend tuning that Brax applies in the environment's constructor (time
step, solver settings) is kept. All variants of one environment have the same
array shapes, so one jitted function can run any of them with the system
passed as an argument.

Variants (Ant only, besides ``normal``):

- ``long_legs``: every leg segment 1.2x longer (capsule ``fromto``, the child
  bodies' ``pos`` and the feet), the initial torso height and the upper bound
  of the healthy torso height raised by the same factor.
- ``slippery``: sliding friction of every geom (floor included) x0.25.
- ``low_gravity``: gravity x0.5.

(A heavier torso was tried first: the ``spring`` backend with the Ant's
``spring_mass_scale=1`` gives every link unit mass, so masses have no effect
there.)

Terrain (rough ground, stairs) needs height-field or mesh contacts; the
``spring`` backend, the only one fast enough here, has neither, so the two
niches are physical ones (friction and gravity).
"""

import contextlib
import functools
import io
import os
import platform
import xml.etree.ElementTree as ET
from dataclasses import dataclass

# MuJoCo's offscreen renderer (sgb.rl.render) needs a headless OpenGL; on Linux that is
# EGL, chosen when mujoco is first imported, which Brax does.
if platform.system() == "Linux":
    os.environ.setdefault("MUJOCO_GL", "egl")

# mujoco.mjx prints a line when its optional warp backend is absent, which it is here.
with contextlib.redirect_stdout(io.StringIO()):
    import mujoco.mjx  # noqa: F401, E402

import brax.envs  # noqa: E402
import jax
import numpy as np
from brax.io import mjcf
from etils import epath

from sgb import validation

VARIANTS = ("normal", "long_legs", "slippery", "low_gravity")
LEG_SCALE = 1.2
FRICTION_SCALE = 0.25
GRAVITY_SCALE = 0.5
_ASSETS = {"ant": "ant.xml", "halfcheetah": "half_cheetah.xml"}


@dataclass(frozen=True)
class EnvSpec:
    """Which environment (any name registered with ``brax.envs``), backend and variant."""

    name: str = "ant"
    backend: str = "spring"
    variant: str = "normal"

    def __post_init__(self) -> None:
        validation.instance("name", self.name, str)
        validation.instance("backend", self.backend, str)
        if self.variant not in VARIANTS:
            raise ValueError(f"variant must be one of {VARIANTS}, got {self.variant!r}")
        if self.variant != "normal" and self.name != "ant":
            raise ValueError(f"variant {self.variant!r} exists for the ant only, not {self.name!r}")


def _base_xml(name: str) -> str:
    return (epath.resource_path("brax") / "envs" / "assets" / _ASSETS[name]).read_text()


def _floats(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.split()])


def _fmt(values: np.ndarray) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def long_legs_xml(xml: str, scale: float = LEG_SCALE) -> str:
    """The Ant's XML with every leg ``scale`` times longer and the torso started higher."""
    if not scale > 0:
        raise ValueError(f"scale must be > 0, got {scale}")
    root = ET.fromstring(xml)
    torso = root.find("./worldbody/body[@name='torso']")
    for body in torso.iter("body"):
        if body is not torso:
            body.set("pos", _fmt(_floats(body.get("pos")) * scale))
        for geom in body.findall("geom"):
            if geom.get("fromto") is not None:
                geom.set("fromto", _fmt(_floats(geom.get("fromto")) * scale))
            elif geom.get("name", "").endswith("foot_geom"):
                geom.set("pos", _fmt(_floats(geom.get("pos")) * scale))
    torso.set("pos", _fmt(_floats(torso.get("pos")) * np.array([1.0, 1.0, scale])))
    init = root.find("./custom/numeric[@name='init_qpos']")
    qpos = _floats(init.get("data"))
    qpos[2] *= scale
    init.set("data", _fmt(qpos))
    return ET.tostring(root, encoding="unicode")


def slippery_xml(xml: str, scale: float = FRICTION_SCALE) -> str:
    """The Ant's XML with the sliding friction of every geom (floor included) times ``scale``."""
    root = ET.fromstring(xml)
    default = root.find("./default/geom")
    friction = _floats(default.get("friction"))
    friction[0] *= scale
    default.set("friction", _fmt(friction))
    return ET.tostring(root, encoding="unicode")


def low_gravity_xml(xml: str, scale: float = GRAVITY_SCALE) -> str:
    """The model's XML with gravity times ``scale``."""
    root = ET.fromstring(xml)
    option = root.find("./option")
    gravity = _floats(option.get("gravity", "0 0 -9.81")) * scale
    option.set("gravity", _fmt(gravity))
    return ET.tostring(root, encoding="unicode")


_EDITS = {"long_legs": long_legs_xml, "slippery": slippery_xml, "low_gravity": low_gravity_xml}


def _transplant(target, reference, edited):
    """``target`` with every array leaf that differs between ``reference`` and ``edited`` replaced.

    The three systems must have the same leaves in the same order (same model
    structure); static metadata may differ and is taken from ``target``.
    """
    leaves, treedef = jax.tree_util.tree_flatten(target)
    ref_leaves = jax.tree_util.tree_leaves(reference)
    new_leaves = jax.tree_util.tree_leaves(edited)
    if not len(leaves) == len(ref_leaves) == len(new_leaves):
        raise ValueError("the edited model has a different structure; it cannot be batched")
    out = []
    for t, r, e in zip(leaves, ref_leaves, new_leaves, strict=True):
        changed = np.shape(r) != np.shape(e) or not np.array_equal(np.asarray(r), np.asarray(e))
        if changed and np.shape(t) != np.shape(e):
            raise ValueError("the edited model changed an array's shape; it cannot be batched")
        out.append(e if changed else t)
    return jax.tree_util.tree_unflatten(treedef, out)


def variant_xml(name: str, variant: str) -> str:
    """The MJCF model (XML text) of environment ``name`` in ``variant``."""
    spec = EnvSpec(name, "spring", variant)
    base = _base_xml(spec.name)
    return base if variant == "normal" else _EDITS[variant](base)


@functools.cache
def make_env(spec: EnvSpec) -> brax.envs.Env:
    """The Brax environment of ``spec`` (cached: one object per spec, so jit caches hit).

    Built eagerly even when first called inside a jitted function, so the
    cached system holds concrete arrays, never tracers.
    """
    with jax.ensure_compile_time_eval():
        return _build_env(spec)


def _build_env(spec: EnvSpec) -> brax.envs.Env:
    kwargs = {"backend": spec.backend}
    if spec.name == "ant" and spec.variant == "long_legs":
        kwargs["healthy_z_range"] = (0.2, 1.0 * LEG_SCALE)
    try:
        env = brax.envs.get_environment(spec.name, **kwargs)
    except KeyError as error:
        raise ValueError(f"name {spec.name!r} is not a registered Brax environment") from error
    if spec.variant != "normal":
        reference = mjcf.loads(_base_xml(spec.name))
        env.sys = _transplant(env.sys, reference, mjcf.loads(variant_xml(spec.name, spec.variant)))
    return env


def leg_lengths(env: brax.envs.Env) -> np.ndarray:
    """Distance (m, in the horizontal plane of the model) from torso centre to each foot centre.

    Computed from the system's arrays: each foot geom's position plus the
    offsets of its chain of bodies up to the torso. Feet are the spheres
    smaller than the torso. Shape (4,) for the Ant.
    """
    sys = env.sys
    parents = np.asarray(sys.body_parentid)
    body_pos = np.asarray(sys.body_pos)
    geom_body = np.asarray(sys.geom_bodyid)
    geom_pos = np.asarray(sys.geom_pos)
    radius = np.asarray(sys.geom_size)[:, 0]
    spheres = np.flatnonzero(np.asarray(sys.geom_type) == 2)
    torso_radius = radius[spheres].max()
    lengths = []
    for g in spheres[radius[spheres] < torso_radius]:
        offset, body = geom_pos[g].copy(), int(geom_body[g])
        while parents[body] != 0:
            offset += body_pos[body]
            body = int(parents[body])
        lengths.append(float(np.linalg.norm(offset[:2])))
    return np.array(lengths)
