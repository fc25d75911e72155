import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb.compression import (
    compression,
    compression_ratio,
    dense_param_count,
    hidden_types_sweep,
    setting_for_ratio,
    sgb_param_count,
    tree_param_count,
)
from sgb.individuals import init_params
from sgb.layers import SGBMLP


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


def test_both_conventions_come_from_one_function():
    sizes = (784, 800, 10)
    assert compression("dense", sizes, 0, 30, 10) == 1.0
    # ours: means, rhos and biases against weights and biases
    assert compression("sgb", sizes, 20, 30, 10) == pytest.approx(
        636_010 / (2 * (30 * 20 + 20 * 10) + 810)
    )
    # the authors': the mean table against the weights
    assert compression("sgb", sizes, 20, 30, 10, "authors") == pytest.approx(
        635_200 / (30 * 20 + 20 * 10)
    )
    # DGB: codes of 10 + 10 bits into the hidden layer's g-net, 10 bits + one-hot 10 out
    gnets = 2 * ((20 * 7 + 7) + (7 * 10 + 10) + 11)
    assert compression("dgb", sizes, 7, 30, 10) == pytest.approx(636_010 / (gnets + 810))
    assert compression("dgb", sizes, 7, 30, 10, "authors") == pytest.approx(635_200 / gnets)
    with pytest.raises(ValueError, match="convention"):
        compression("sgb", sizes, 20, 30, 10, "other")


def test_setting_for_ratio_is_nearest_on_a_log_scale():
    sizes = (64, 800, 10)
    for kind in ("sgb", "dgb"):
        setting = setting_for_ratio(kind, sizes, 8.0, 30, 10)
        best = abs(np.log(compression(kind, sizes, setting, 30, 10) / 8.0))
        for other in (setting - 1, setting + 1):
            assert best <= abs(np.log(compression(kind, sizes, other, 30, 10) / 8.0))
    with pytest.raises(ValueError, match="ratio"):
        setting_for_ratio("sgb", sizes, -1.0, 30, 10)
