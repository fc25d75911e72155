"""A checkpoint save never leaves less than it found: a full disk or a kill -9 at any point
of ``sgb.rl.checkpoints.save`` leaves a pair that loads, the old one or the new one; and
a tamper that keeps one side's hash consistent is refused."""

import errno
import hashlib
import json
import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import serialization
from reach import reach_config

from sgb.rl import checkpoints, ppo
from sgb.rl.normalizer import init_normalizer
from sgb.validation import CorruptFile

ROOT = Path(__file__).resolve().parents[1]
COMMITTED = ROOT / "results" / "rl" / "checkpoints"


def _result(returns: list[float], seed: int = 0) -> ppo.TrainResult:
    """An untrained Reach result whose learning curve is ``returns`` (one per 100 steps)."""
    config = reach_config(4)
    params = jax.tree_util.tree_map(np.asarray, ppo.initial_params(config, seed=seed))
    norm = init_normalizer(2)._replace(count=jnp.asarray(5.0), m2=jnp.ones(2))
    steps = [100 * (i + 1) for i in range(len(returns))]
    return ppo.TrainResult(config, params, norm, steps, returns, 1e3, 2.0)


def _files(directory: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir())}


def _returns(path: Path) -> list[float]:
    return checkpoints.load(path)[3]["eval_returns"]


@pytest.mark.parametrize("failing", [1, 2], ids=["msgpack", "sidecar"])
def test_a_full_disk_leaves_the_old_pair_as_it_was(tmp_path, monkeypatch, failing):
    path = checkpoints.save(tmp_path / "agent.msgpack", _result([-20.0]))
    before = _files(tmp_path)
    real, calls = checkpoints._write_synced, []

    def disk_full_part_way(file, content):
        calls.append(file)
        if len(calls) == failing:
            real(file, content[: len(content) // 2])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(file))
        real(file, content)

    monkeypatch.setattr(checkpoints, "_write_synced", disk_full_part_way)
    with pytest.raises(OSError) as error:
        checkpoints.save(path, _result([-5.0, -3.0], seed=1))
    assert error.value.errno == errno.ENOSPC
    assert _files(tmp_path) == before  # nothing left behind, nothing lost
    assert _returns(path) == [-20.0]


CHILD = """
import os, pickle, signal, sys
from sgb.rl import checkpoints

path, result, when = sys.argv[1:]
real_write, real_replace, writes = checkpoints._write_synced, os.replace, []

def write(file, content):
    writes.append(file)
    if when == f"write {len(writes)}":
        real_write(file, content[: len(content) // 2])
        os.kill(os.getpid(), signal.SIGKILL)
    real_write(file, content)

def replace(source, target):
    real_replace(source, target)
    if when == "between the replaces":
        os.kill(os.getpid(), signal.SIGKILL)

checkpoints._write_synced = write
os.replace = replace
with open(result, "rb") as handle:
    checkpoints.save(path, pickle.load(handle))
"""
KILLS = {"write 1": [-20.0], "write 2": [-20.0], "between the replaces": [-5.0, -3.0]}


def test_a_save_killed_at_any_point_leaves_a_pair_that_loads(tmp_path, monkeypatch):
    """kill -9 while the new msgpack or sidecar is half written leaves the old pair; between
    the two replaces, the new one. The next save completes it first, so a full disk then
    still leaves the pair the kill left."""
    result = tmp_path / "result.pickle"
    result.write_bytes(pickle.dumps(_result([-5.0, -3.0], seed=1)))
    children = {}
    for i, when in enumerate(KILLS):
        path = checkpoints.save(tmp_path / f"run{i}" / "agent.msgpack", _result([-20.0]))
        command = [sys.executable, "-c", CHILD, str(path), str(result), when]
        children[when] = (path, subprocess.Popen(command, cwd=ROOT, stderr=subprocess.PIPE))
    for when, (path, child) in children.items():
        _, stderr = child.communicate(timeout=120)
        assert child.returncode == -9, stderr.decode()
        assert _returns(path) == KILLS[when], when

    path = children["between the replaces"][0]
    real = checkpoints._write_synced

    def disk_full(file, content):
        real(file, content[:10])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(file))

    monkeypatch.setattr(checkpoints, "_write_synced", disk_full)
    with pytest.raises(OSError):
        checkpoints.save(path, _result([1.0, 2.0, 3.0], seed=2))
    assert sorted(_files(path.parent)) == ["agent.json", "agent.msgpack"]
    assert _returns(path) == [-5.0, -3.0]
    monkeypatch.setattr(checkpoints, "_write_synced", real)
    for when, (path, _) in children.items():
        checkpoints.save(path, _result([1.0, 2.0, 3.0], seed=2))
        assert sorted(_files(path.parent)) == ["agent.json", "agent.msgpack"], when
        assert _returns(path) == [1.0, 2.0, 3.0]


def _tamper(path: Path, entries: int, rehash_sidecar: bool) -> None:
    """Cut or pad the checkpoint's normaliser to ``entries`` entries, rewrite its msgpack and
    the ``sha256`` its sidecar records, and ``sidecar_sha256`` too if ``rehash_sidecar``."""
    state = serialization.msgpack_restore(path.read_bytes())
    normalizer = state["normalizer"]
    state["normalizer"] = {k: np.resize(v, entries) if v.ndim else v for k, v in normalizer.items()}
    data = serialization.msgpack_serialize(state)
    path.write_bytes(data)
    sidecar = path.with_suffix(".json")
    meta = json.loads(sidecar.read_text())
    meta["sha256"] = hashlib.sha256(data).hexdigest()
    if rehash_sidecar:
        meta[checkpoints.SIDECAR_HASH] = checkpoints.sidecar_hash(meta)
    sidecar.write_text(json.dumps(meta))


def _copy_committed(name: str, directory: Path) -> Path:
    for suffix in (".msgpack", ".json"):
        shutil.copy(COMMITTED / f"{name}{suffix}", directory / f"{name}{suffix}")
    return directory / f"{name}.msgpack"


@pytest.mark.parametrize("side", ["sidecar", "msgpack"])
def test_a_tamper_of_one_side_of_a_committed_checkpoint_is_refused(tmp_path, side):
    """The returns replaced by as many 99999s, or the msgpack rewritten (its normaliser cut
    to 10 entries) with the SHA-256 the sidecar records of it: the sidecar's own hash,
    which covers both, refuses either."""
    path = _copy_committed("ant_k16_s0_cpu", tmp_path)
    sidecar = path.with_suffix(".json")
    if side == "sidecar":
        meta = json.loads(sidecar.read_text())
        meta["eval_returns"] = [99999.0] * len(meta["eval_returns"])
        sidecar.write_text(json.dumps(meta))
    else:
        _tamper(path, 10, rehash_sidecar=False)
    with pytest.raises(CorruptFile, match=f"{sidecar} does not match the SHA-256"):
        checkpoints.load(path)


@pytest.mark.parametrize("entries", [1, 3])
def test_a_normaliser_of_another_size_is_refused_even_with_every_hash_recomputed(tmp_path, entries):
    path = checkpoints.save(tmp_path / "agent.msgpack", _result([-20.0]))
    _tamper(path, entries, rehash_sidecar=True)
    with pytest.raises(CorruptFile, match=f"{path} holds observation statistics.*shape \\(2,\\)"):
        checkpoints.load(path)


def test_every_committed_sidecar_hashes_itself_and_its_msgpack():
    sidecars = sorted(COMMITTED.glob("*.json"))
    assert len(sidecars) >= 125
    for sidecar in sidecars:
        meta = json.loads(sidecar.read_text())
        assert meta.get(checkpoints.SIDECAR_HASH) == checkpoints.sidecar_hash(meta), sidecar
        msgpack = sidecar.with_suffix(".msgpack").read_bytes()
        assert meta["sha256"] == hashlib.sha256(msgpack).hexdigest(), sidecar
