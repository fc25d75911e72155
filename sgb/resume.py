"""A training state on disk, so that a killed run continues where it stopped.

``save(path, state, run, progress)`` writes every array leaf of the pytree ``state``,
the identity of the run (``run``: its configuration and seed, JSON) and how far it got
(``progress``, JSON) to one ``.npz`` file, atomically. ``load(path, template, run)``
rebuilds the state on the tree structure of ``template`` (a freshly initialised state of
the same run) and refuses a file written by another run, naming the file.
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
    leaves = jax.tree_util.tree_leaves(state)
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
    shapes = [(np.shape(a), np.asarray(a).dtype) for a in leaves]
    if shapes != [(a.shape, a.dtype) for a in arrays]:
        raise ValueError(f"training state {path} does not have the arrays of this run's state")
    return jax.tree_util.tree_unflatten(treedef, [jnp.asarray(a) for a in arrays]), meta["progress"]
