"""A training state on disk, so that a killed run continues where it stopped.

``save(path, state, run, progress)`` writes every array leaf of the pytree ``state``,
the identity of the run (``run``: its configuration and seed, JSON) and how far it got
(``progress``, JSON) to one ``.npz`` file, atomically. ``load(path, template, run)``
rebuilds the state on the tree structure of ``template`` (a freshly initialised state of
the same run) and refuses a file written by another run, naming the file. Typed PRNG
keys are stored as their key data.
"""

import io
import json
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from sgb.provenance import atomic_write


def save(path: str | Path, state: Any, run: dict, progress: dict) -> Path:
    """Write ``state`` (a pytree of arrays), ``run`` and ``progress`` to ``path``."""
    leaves = [_raw(leaf) for leaf in jax.tree_util.tree_leaves(state)]
    arrays = {f"leaf_{i}": np.asarray(leaf) for i, leaf in enumerate(leaves)}
    meta = json.dumps({"run": run, "progress": progress})
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.array(meta), **arrays)
    return atomic_write(path, buffer.getvalue())


def load(path: str | Path, template: Any, run: dict) -> tuple[Any, dict]:
    """The state and progress saved at ``path``, on ``template``'s tree structure."""
    try:
        with np.load(path) as data:
            meta = json.loads(str(data["meta"]))
            arrays = [data[f"leaf_{i}"] for i in range(len(data.files) - 1)]
    except (OSError, ValueError, KeyError) as error:
        raise ValueError(f"training state {path} is unreadable: {error!r}") from error
    if meta["run"] != run:
        raise ValueError(f"training state {path} belongs to another run: {meta['run']}")
    leaves, treedef = jax.tree_util.tree_flatten(template)
    shapes = [(np.shape(a), jnp.asarray(a).dtype) for a in map(_raw, leaves)]
    if shapes != [(a.shape, a.dtype) for a in arrays]:
        raise ValueError(f"training state {path} does not have the arrays of this run's state")
    restored = [_like(leaf, jnp.asarray(a)) for leaf, a in zip(leaves, arrays, strict=True)]
    return jax.tree_util.tree_unflatten(treedef, restored), meta["progress"]


def _is_key(leaf: Any) -> bool:
    return jax.dtypes.issubdtype(getattr(leaf, "dtype", None), jax.dtypes.prng_key)


def _raw(leaf: Any) -> Any:
    """A typed PRNG key as its raw key data; any other leaf as it is."""
    return jax.random.key_data(leaf) if _is_key(leaf) else leaf


def _like(template: Any, raw: jnp.ndarray) -> Any:
    """``raw`` as a leaf of ``template``'s kind: key data back into a typed key."""
    if not _is_key(template):
        return raw
    return jax.random.wrap_key_data(raw, impl=jax.random.key_impl(template))
