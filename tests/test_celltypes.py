import jax.numpy as jnp
import numpy as np
import pytest

from sgb.celltypes import assign_cell_types, block_counts, expand_table, type_sizes


def test_types_are_contiguous_balanced_blocks_with_remainder_first():
    types = assign_cell_types(10, 3)
    np.testing.assert_array_equal(types, [0, 0, 0, 0, 1, 1, 1, 2, 2, 2])
    np.testing.assert_array_equal(type_sizes(10, 3), [4, 3, 3])
    for n in range(1, 40):
        for k in range(1, n + 1):
            sizes = type_sizes(n, k)
            assert sizes.sum() == n and sizes.max() - sizes.min() <= 1
            assert np.all(np.diff(sizes) <= 0)
            assert np.all(np.diff(assign_cell_types(n, k)) >= 0)


def test_expand_table_places_each_type_pair_on_its_block():
    table = jnp.arange(6.0).reshape(2, 3)
    full = np.asarray(expand_table(table, (5, 7)))
    rows, cols = assign_cell_types(5, 2), assign_cell_types(7, 3)
    for a in range(5):
        for b in range(7):
            assert full[a, b] == table[rows[a], cols[b]]


def test_expand_table_four_d_kernel():
    table = jnp.arange(2 * 1 * 3 * 2, dtype=jnp.float32).reshape(2, 1, 3, 2)
    full = np.asarray(expand_table(table, (3, 3, 8, 5)))
    assert full.shape == (3, 3, 8, 5)
    t = [assign_cell_types(n, k) for n, k in zip((3, 3, 8, 5), table.shape, strict=True)]
    idx = np.ix_(*t)
    np.testing.assert_array_equal(full, np.asarray(table)[idx])
    counts = block_counts((3, 3, 8, 5), table.shape)
    assert counts.sum() == 3 * 3 * 8 * 5
    assert counts[0, 0, 0, 0] == 2 * 3 * 3 * 3


@pytest.mark.parametrize(
    ("n", "k", "match"),
    [(3, 4, "more than"), (0, 1, "positive"), (5, 0, "positive"), (5, -2, "positive")],
)
def test_bad_counts_raise_clear_errors(n, k, match):
    with pytest.raises(ValueError, match=match):
        type_sizes(n, k)


def test_expand_table_rejects_mismatched_axes():
    with pytest.raises(ValueError, match="axes"):
        expand_table(jnp.zeros((2, 2)), (4, 4, 4))
