"""A training state on disk, so that a killed run continues where it stopped.

``save(path, state, run, progress)`` writes every array leaf of the pytree ``state``,
the identity of the run (``run``: its configuration and seed, JSON) and how far it got
(``progress``, JSON) to one ``.npz`` file, atomically. ``peek(path)`` reads back the run
and its progress alone. ``load(path, template, run)``
rebuilds the state on the tree structure of ``template`` (a freshly initialised state of
the same run) and refuses a file written by another run, naming the file. Typed PRNG
keys are stored as their key data.

A file that cannot be what ``save`` wrote (a flipped byte, which the zip format's CRC-32
catches; a truncated or empty file; a directory in its place; a missing entry) is a
``sgb.validation.CorruptFile`` that names it and says to delete it and start afresh.
"""

import io
import json
import zipfile
import zlib
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from sgb.provenance import atomic_write
from sgb.validation import RESTART, CorruptFile, finite_tree

_WHAT = "training state"
# what reading a damaged .npz can raise, from the zip layer up to the JSON of its meta
_READ_ERRORS = (
    OSError,
    EOFError,
    ValueError,
    KeyError,
    TypeError,
    SyntaxError,
    zipfile.BadZipFile,
    zlib.error,
)


def save(path: str | Path, state: Any, run: dict, progress: dict) -> Path:
    """Write ``state`` (a pytree of arrays), ``run`` and ``progress`` to ``path``."""
    leaves = [_raw(leaf) for leaf in jax.tree_util.tree_leaves(state)]
    arrays = {f"leaf_{i}": np.asarray(leaf) for i, leaf in enumerate(leaves)}
    meta = json.dumps({"run": run, "progress": progress})
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.array(meta), **arrays)
    return atomic_write(path, buffer.getvalue())


def _read(path: Path, arrays: bool) -> tuple[dict, list[np.ndarray]]:
    """The meta saved at ``path`` (checked to hold a run and a progress) and, with
    ``arrays``, its array leaves in order; a ``CorruptFile`` if it cannot be read."""
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            count = len(data.files) - 1 if arrays else 0
            leaves = [np.asarray(data[f"leaf_{i}"]) for i in range(count)]
    except _READ_ERRORS as error:
        raise CorruptFile(path, f"is unreadable ({error!r})", RESTART, _WHAT) from error
    if not isinstance(meta, dict) or not {"run", "progress"} <= set(meta):
        raise CorruptFile(path, "has no run or progress in its meta", RESTART, _WHAT)
    return meta, leaves


def peek(path: str | Path) -> tuple[dict, dict]:
    """The run and progress saved at ``path``, without its arrays; a ``CorruptFile`` if it
    cannot be read."""
    meta, _ = _read(Path(path), arrays=False)
    return meta["run"], meta["progress"]


def load(
    path: str | Path,
    template: Any,
    run: dict,
    progress_keys: Collection[str] = (),
    finite: Callable[[Any], Any] | None = None,
) -> tuple[Any, dict]:
    """The state and progress saved at ``path``, on ``template``'s tree structure.

    ``progress_keys``: entries the progress must hold. ``finite``: the part of the state
    (a function of it, e.g. its parameters) that must hold no nan or inf. A file that
    fails any check, or cannot be read, is a ``CorruptFile``; a file of another run a
    ``ValueError``.
    """
    path = Path(path)
    meta, arrays = _read(path, arrays=True)
    if meta["run"] != run:
        raise ValueError(f"training state {path} belongs to another run: {meta['run']}")
    progress = meta["progress"]
    missing = [
        key for key in progress_keys if not isinstance(progress, dict) or key not in progress
    ]
    if missing:
        raise CorruptFile(path, f"has no {missing} in its progress", RESTART, _WHAT)
    leaves, treedef = jax.tree_util.tree_flatten(template)
    shapes = [(np.shape(a), jnp.asarray(a).dtype) for a in map(_raw, leaves)]
    if shapes != [(a.shape, a.dtype) for a in arrays]:
        raise CorruptFile(path, "does not hold the arrays of this run's state", RESTART, _WHAT)
    restored = [_like(leaf, jnp.asarray(a)) for leaf, a in zip(leaves, arrays, strict=True)]
    state = jax.tree_util.tree_unflatten(treedef, restored)
    if finite is not None:
        try:
            finite_tree("state", finite(state))
        except ValueError as error:
            raise CorruptFile(path, f"holds {error}", RESTART, _WHAT) from error
    return state, progress


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
