"""Checkpoints of trained agents: flax msgpack for the arrays, JSON for the configuration.

``save(path, result)`` writes ``path`` (msgpack: actor and critic parameters,
observation statistics) and ``path.with_suffix(".json")`` (the sidecar: the PPO config,
the learning curve, the speed and wall time, the provenance passed in, ``sha256``, the
SHA-256 of the msgpack file, and ``sidecar_sha256``, the SHA-256 of the canonical JSON of
every other sidecar field: it covers the settings and, through ``sha256``, the msgpack's
content, so that neither file can be changed without the other's hash refusing it).

A save never leaves less than it found. It writes the new pair beside the old one, each
file to its pending name (``.<name>.new``, synced), then replaces the sidecar and then
the msgpack. A failure while writing (a full disk, a kill) removes or leaves behind
only pending files, beside the old pair, which still loads; a kill between the two
replaces leaves the new sidecar, whose ``sha256`` names the new msgpack at its pending
name, where ``load`` finds it (the next ``save`` moves it into place first).

``load`` checks both hashes, that the sidecar fields read back have their types, that
the parameter shapes are those the config describes, that the observation statistics
fit the environment's observations and that every array is finite, and names the file
in every error (a ``sgb.validation.CorruptFile``, a ``ValueError``). A sidecar without
``sidecar_sha256`` is one of the earlier format, written before the sidecar was hashed:
it still loads, its fields checked for their types only.
"""

import hashlib
import json
import numbers
import os
from functools import partial
from pathlib import Path
from typing import Any

import jax
import numpy as np
from flax import serialization

from sgb.rl.agent import NetworkConfig, Params
from sgb.rl.envs import EnvSpec, make_env
from sgb.rl.normalizer import Normalizer
from sgb.rl.population import check_normalizer
from sgb.rl.ppo import PPOConfig, TrainResult, initial_params
from sgb.validation import RETRAIN, CorruptFile, finite_tree, shape_differences

SIDECAR_HASH = "sidecar_sha256"


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


def sidecar_hash(meta: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON (sorted keys, no spaces) of every field of the sidecar
    ``meta`` but ``sidecar_sha256`` itself (``sha256``, the msgpack's, among them)."""
    fields = {k: v for k, v in meta.items() if k != SIDECAR_HASH}
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"))
    return _sha256(text.encode())


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _pending(file: Path) -> Path:
    """Where ``save`` writes the new content of ``file`` before it replaces ``file``."""
    return file.with_name(f".{file.name}.new")


def save(path: str | Path, result: TrainResult, record: dict[str, Any] | None = None) -> Path:
    """Write the checkpoint of ``result`` to ``path`` (.msgpack) and its JSON sidecar,
    leaving the old pair loadable until the new one is (module docstring)."""
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
        "eval_sigmas": result.eval_sigmas,
        "train_steps_per_s": result.train_steps_per_s,
        "wall_time_s": result.wall_time_s,
        "cpu_time_s": result.cpu_time_s,
        "provenance": record or {},
        "sha256": _sha256(data),
    }
    meta = json.loads(json.dumps(meta))  # the fields as ``load`` will read them back
    meta[SIDECAR_HASH] = sidecar_hash(meta)
    _finish_interrupted_save(path)
    _replace_pair(path, data, (json.dumps(meta, indent=1) + "\n").encode())
    return path


def _finish_interrupted_save(path: Path) -> None:
    """Move the msgpack of a save killed between its two replaces into place, the one the
    sidecar at ``path`` names: writing the next pair's pending files must not destroy it."""
    pending, sidecar = _pending(path), path.with_suffix(".json")
    if not (pending.is_file() and sidecar.is_file()):
        return
    try:
        expected = json.loads(sidecar.read_bytes())["sha256"]
    except (ValueError, KeyError, TypeError):
        return
    if _sha256(pending.read_bytes()) == expected:
        os.replace(pending, path)


def _replace_pair(path: Path, data: bytes, text: bytes) -> None:
    """Replace the msgpack at ``path`` by ``data`` and its sidecar by ``text``: both
    written to their pending files first (removed again if that fails), then the sidecar
    replaced, then the msgpack."""
    sidecar = path.with_suffix(".json")
    contents = {path: data, sidecar: text}
    try:
        for file, content in contents.items():
            _write_synced(_pending(file), content)
    except BaseException:
        for file in contents:
            _pending(file).unlink(missing_ok=True)
        raise
    os.replace(_pending(sidecar), sidecar)
    os.replace(_pending(path), path)
    _sync_directory(path.parent)


def _write_synced(file: Path, content: bytes) -> None:
    """Write ``content`` to ``file`` and wait until it is on the disk."""
    with open(file, "wb") as handle:
        handle.write(content)
        handle.flush()
        os.fsync(handle.fileno())


def _sync_directory(directory: Path) -> None:
    """Wait until the renames in ``directory`` are on the disk."""
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def load(path: str | Path) -> tuple[PPOConfig, Params, Normalizer, dict[str, Any]]:
    """Read a checkpoint: its config, parameters, observation statistics and metadata."""
    path = Path(path)
    sidecar = path.with_suffix(".json")
    for file in (path, sidecar):
        if not file.exists():
            raise ValueError(f"checkpoint file {file} does not exist")
        if not file.is_file():
            raise CorruptFile(file, "is not a file", RETRAIN, "checkpoint")
    try:
        meta = json.loads(sidecar.read_bytes().decode())
        if not isinstance(meta, dict):
            raise TypeError(f"it holds a {type(meta).__name__}, not an object")
        expected, config = meta["sha256"], config_from_dict(meta["config"])
    except (ValueError, KeyError, TypeError) as error:
        raise CorruptFile(sidecar, f"is unreadable ({error!r})", RETRAIN, "checkpoint") from error
    if SIDECAR_HASH in meta and meta[SIDECAR_HASH] != sidecar_hash(meta):
        raise CorruptFile(
            sidecar, "does not match the SHA-256 it records of itself", RETRAIN, "checkpoint"
        )
    _check_fields(sidecar, meta)
    data = _stored_msgpack(path, expected)
    try:
        state = serialization.msgpack_restore(data)
        params = Params(state["actor"], state["critic"])
        normalizer = Normalizer(**state["normalizer"])
    except (ValueError, KeyError, TypeError) as error:
        raise CorruptFile(path, f"is unreadable ({error!r})", RETRAIN, "checkpoint") from error
    # the shapes the config describes, traced without computing (or compiling) anything
    _check_shapes(path, params, jax.eval_shape(partial(initial_params, config, seed=0)))
    arrays = {"actor": params.actor, "critic": params.critic, "normalizer": state["normalizer"]}
    try:
        finite_tree("", arrays)
    except ValueError as error:
        problem = f"has arrays that are not finite: {error}"
        raise CorruptFile(path, problem, RETRAIN, "checkpoint") from error
    _check_normalizer(path, normalizer, make_env(config.env).observation_size)
    params, normalizer = jax.tree_util.tree_map(jax.numpy.asarray, (params, normalizer))
    return config, params, normalizer, meta


def _stored_msgpack(path: Path, expected: str) -> bytes:
    """The msgpack bytes whose SHA-256 the sidecar records (``expected``): those at
    ``path``, or at its pending name after a save killed between its two replaces."""
    data = path.read_bytes()
    pending = _pending(path)
    if _sha256(data) != expected and pending.is_file():
        data = pending.read_bytes()
    if _sha256(data) != expected:
        sidecar = path.with_suffix(".json")
        raise CorruptFile(
            path, f"does not match the SHA-256 recorded in {sidecar}", RETRAIN, "checkpoint"
        )
    return data


def _check_fields(sidecar: Path, meta: dict[str, Any]) -> None:
    """Raise ``CorruptFile`` naming ``sidecar`` unless the fields read back from it have
    their types: a learning curve of as many integer steps as finite returns, a speed and
    a wall time >= 0, a provenance object."""

    def number(value: Any) -> bool:
        return isinstance(value, numbers.Real) and not isinstance(value, bool)

    steps, returns = meta.get("eval_steps"), meta.get("eval_returns")
    problems = []
    if not isinstance(steps, list) or not all(isinstance(s, int) for s in steps):
        problems.append("eval_steps is not a list of integers")
    if not isinstance(returns, list) or not returns:
        problems.append("eval_returns is not a non-empty list")
    elif not all(number(r) and np.isfinite(r) for r in returns):
        problems.append("eval_returns holds a value that is not a finite number")
    elif isinstance(steps, list) and len(steps) != len(returns):
        problems.append("eval_steps and eval_returns differ in length")
    for key in ("train_steps_per_s", "wall_time_s"):
        if not (number(meta.get(key)) and meta[key] >= 0):
            problems.append(f"{key} is not a number >= 0")
    cpu = meta.get("cpu_time_s")  # absent or null where the run did not record it
    if cpu is not None and not (number(cpu) and cpu >= 0):
        problems.append("cpu_time_s is neither null nor a number >= 0")
    if not isinstance(meta.get("provenance", {}), dict):
        problems.append("provenance is not an object")
    if problems:
        raise CorruptFile(sidecar, f"is damaged: {'; '.join(problems)}", RETRAIN, "checkpoint")


def _check_shapes(path: Path, params: Params, expected: Params) -> None:
    """Raise ``CorruptFile`` naming ``path`` unless ``params`` has the shapes of ``expected``."""
    diff = shape_differences(params, expected)
    if diff:
        raise CorruptFile(
            path,
            "does not hold the parameters its sidecar's config describes "
            f"(first differences, (name, shape, expected shape): {diff})",
            RETRAIN,
            "checkpoint",
        )


def _check_normalizer(path: Path, normalizer: Normalizer, size: int) -> None:
    """Raise ``CorruptFile`` naming ``path`` unless ``normalizer`` holds statistics of
    observations of ``size`` entries (``sgb.rl.population.check_normalizer``)."""
    try:
        check_normalizer(normalizer, size)
    except (TypeError, ValueError) as error:
        problem = f"holds observation statistics that do not fit its config ({error})"
        raise CorruptFile(path, problem, RETRAIN, "checkpoint") from error
