import jax
import jax.numpy as jnp
import pytest

from sgb.compression import (
    compression_ratio,
    dense_param_count,
    hidden_types_sweep,
    sgb_param_count,
    tree_param_count,
)
from sgb.layers import SGBMLP
from sgb.population import init_params


def test_counts_match_the_parameters_flax_creates():
    sizes, types = (20, 12, 5), (4, 3, None)
    model = SGBMLP(widths=sizes[1:], cell_types=types)
    params = init_params(model, jax.random.key(0), jnp.ones((1, 20)))
    assert tree_param_count(params) == sgb_param_count(sizes, types)
    assert sgb_param_count(sizes, (None, None, None)) == 2 * (20 * 12 + 12 * 5) + 12 + 5
    assert dense_param_count(sizes) == 20 * 12 + 12 + 12 * 5 + 5


def test_paper_mnist_shape_compression_grows_as_hidden_types_shrink():
    sizes = (784, 800, 10)
    ratios = hidden_types_sweep(sizes, (800, 100, 10, 1), input_types=30, output_types=10)
    assert ratios == sorted(ratios)
    # hidden types 10: 2*(30*10 + 10*10) means/rhos + 810 biases
    assert ratios[2] == pytest.approx(636_010 / 1_610)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: compression_ratio(10, 0), "positive"),
        (lambda: dense_param_count((5,)), "at least"),
        (lambda: sgb_param_count((5, 3), (6, 3)), "cell types"),
        (lambda: sgb_param_count((5, 3), (5,)), "one entry per layer"),
    ],
)
def test_bad_counts_raise(call, match):
    with pytest.raises(ValueError, match=match):
        call()
