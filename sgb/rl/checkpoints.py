"""Checkpoints of trained agents: flax msgpack for the arrays, JSON for the configuration.

``save(path, result)`` writes ``path`` (msgpack: actor and critic parameters,
observation statistics) and ``path.with_suffix(".json")`` (the PPO config,
the learning curve, the provenance passed in and the SHA-256 of the msgpack file),
each atomically. ``load`` checks the checksum and that the parameter shapes are those
the config describes, and names the file in every error.
"""

import hashlib
import json
from functools import partial
from pathlib import Path
from typing import Any

import jax
import numpy as np
from flax import serialization

from sgb.provenance import atomic_write
from sgb.rl.envs import EnvSpec
from sgb.rl.networks import NetworkConfig
from sgb.rl.normalizer import Normalizer
from sgb.rl.ppo import Params, PPOConfig, TrainResult, init_params


def _config_dict(config: PPOConfig) -> dict[str, Any]:
    out = {k: getattr(config, k) for k in config.__dataclass_fields__}
    out["env"] = dict(vars(config.env))
    out["network"] = {**vars(config.network), "hidden": list(config.network.hidden)}
    return out


def config_from_dict(data: dict[str, Any]) -> PPOConfig:
    """Inverse of the JSON config written by ``save``. Sidecars written before the input
    typing and the SGB output layer were separate switches hold one ``all_layers_sgb``
    for both; it is read as both."""
    data = dict(data)
    net = dict(data.pop("network"))
    net["hidden"] = tuple(net["hidden"])
    if "all_layers_sgb" in net:
        both = net.pop("all_layers_sgb")
        net.setdefault("typed_inputs", both)
        net.setdefault("sgb_output", both)
    return PPOConfig(env=EnvSpec(**data.pop("env")), network=NetworkConfig(**net), **data)


def save(path: str | Path, result: TrainResult, record: dict[str, Any] | None = None) -> Path:
    """Write the checkpoint of ``result`` to ``path`` (.msgpack) and its JSON sidecar."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    state = {
        "actor": result.params.actor,
        "critic": result.params.critic,
        "normalizer": result.normalizer._asdict(),
    }
    state = jax.tree_util.tree_map(lambda x: np.asarray(x, dtype=np.float32), state)
    data = serialization.msgpack_serialize(state)
    meta = {
        "config": _config_dict(result.config),
        "eval_steps": result.eval_steps,
        "eval_returns": result.eval_returns,
        "train_steps_per_s": result.train_steps_per_s,
        "wall_time_s": result.wall_time_s,
        "provenance": record or {},
        "sha256": hashlib.sha256(data).hexdigest(),
    }
    atomic_write(path, data)
    atomic_write(path.with_suffix(".json"), (json.dumps(meta, indent=1) + "\n").encode())
    return path


def load(path: str | Path) -> tuple[PPOConfig, Params, Normalizer, dict[str, Any]]:
    """Read a checkpoint: its config, parameters, observation statistics and metadata."""
    path = Path(path)
    sidecar = path.with_suffix(".json")
    for file in (path, sidecar):
        if not file.exists():
            raise ValueError(f"checkpoint file {file} does not exist")
    data = path.read_bytes()
    try:
        meta = json.loads(sidecar.read_text())
        expected, config = meta["sha256"], config_from_dict(meta["config"])
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(f"checkpoint sidecar {sidecar} is unreadable: {error!r}") from error
    if hashlib.sha256(data).hexdigest() != expected:
        raise ValueError(f"checkpoint {path} does not match the SHA-256 recorded in {sidecar}")
    try:
        state = serialization.msgpack_restore(data)
        params = Params(state["actor"], state["critic"])
        normalizer = Normalizer(**state["normalizer"])
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(f"checkpoint {path} is unreadable: {error!r}") from error
    # the shapes the config describes, traced without computing (or compiling) anything
    _check_shapes(path, params, jax.eval_shape(partial(init_params, config, seed=0)))
    params, normalizer = jax.tree_util.tree_map(jax.numpy.asarray, (params, normalizer))
    return config, params, normalizer, meta


def _check_shapes(path: Path, params: Params, expected: Params) -> None:
    """Raise ``ValueError`` naming ``path`` unless ``params`` has the shapes of ``expected``."""

    def shapes(tree: Any) -> dict[str, tuple[int, ...]]:
        leaves = jax.tree_util.tree_leaves_with_path(tree)
        return {jax.tree_util.keystr(k): tuple(np.shape(v)) for k, v in leaves}

    got, want = shapes(params), shapes(expected)
    if got != want:
        diff = sorted(set(got.items()) ^ set(want.items()))[:4]
        raise ValueError(
            f"checkpoint {path} does not hold the parameters its sidecar's config describes "
            f"(first differences, (name, shape): {diff})"
        )
