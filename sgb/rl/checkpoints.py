"""Checkpoints of trained agents: flax msgpack for the arrays, JSON for the configuration.

``save(path, result)`` writes ``path`` (msgpack: actor and critic parameters,
observation statistics) and ``path.with_suffix(".json")`` (the PPO config,
the learning curve and the provenance passed in).
"""

import json
from pathlib import Path
from typing import Any

import jax
import numpy as np
from flax import serialization

from sgb.rl.envs import EnvSpec
from sgb.rl.networks import NetworkConfig
from sgb.rl.normalizer import Normalizer
from sgb.rl.ppo import Params, PPOConfig, TrainResult


def _config_dict(config: PPOConfig) -> dict[str, Any]:
    out = {k: getattr(config, k) for k in config.__dataclass_fields__}
    out["env"] = dict(vars(config.env))
    out["network"] = {**vars(config.network), "hidden": list(config.network.hidden)}
    return out


def config_from_dict(data: dict[str, Any]) -> PPOConfig:
    """Inverse of the JSON config written by ``save``."""
    data = dict(data)
    net = dict(data.pop("network"))
    net["hidden"] = tuple(net["hidden"])
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
    path.write_bytes(serialization.msgpack_serialize(state))
    meta = {
        "config": _config_dict(result.config),
        "eval_steps": result.eval_steps,
        "eval_returns": result.eval_returns,
        "train_steps_per_s": result.train_steps_per_s,
        "wall_time_s": result.wall_time_s,
        "provenance": record or {},
    }
    path.with_suffix(".json").write_text(json.dumps(meta, indent=1) + "\n")
    return path


def load(path: str | Path) -> tuple[PPOConfig, Params, Normalizer, dict[str, Any]]:
    """Read a checkpoint: its config, parameters, observation statistics and metadata."""
    path = Path(path)
    if not path.exists():
        raise ValueError(f"path {path} does not exist")
    state = serialization.msgpack_restore(path.read_bytes())
    meta = json.loads(path.with_suffix(".json").read_text())
    state = jax.tree_util.tree_map(jax.numpy.asarray, state)
    params = Params(state["actor"], state["critic"])
    return config_from_dict(meta["config"]), params, Normalizer(**state["normalizer"]), meta
