"""The deterministic genomic bottleneck: codes, g-net fitting, write-back, parameter counts."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb.compression import tree_param_count
from sgb.data import Dataset
from sgb.dgb import Genome, binary_codes, dgb_param_count, fit_gnets, layer_codes, pair_inputs
from sgb.supervised import DenseConfig, dense_accuracy, train_dense


def test_binary_codes_are_distinct_pm_one_and_one_hot_at_the_output():
    codes = binary_codes(13)
    assert codes.shape == (13, 4) and set(np.unique(codes)) == {-1.0, 1.0}
    assert len({tuple(c) for c in codes}) == 13
    np.testing.assert_array_equal(codes[5], [-1, 1, -1, 1])  # 5 = 0101
    last = layer_codes((13, 7, 3))[-1]
    np.testing.assert_array_equal(last, np.eye(3))
    with pytest.raises(ValueError, match="n must be"):
        binary_codes(0)


def test_pair_inputs_reshape_to_the_kernel_layout():
    pre, post = binary_codes(5), np.eye(3, dtype=np.float32)
    pairs = pair_inputs(pre, post).reshape(5, 3, -1)
    np.testing.assert_array_equal(pairs[4, 2, :3], pre[4])
    np.testing.assert_array_equal(pairs[4, 2, 3:], post[2])


def test_gnet_reproduces_kernels_that_are_a_function_of_the_codes():
    sizes = (16, 8, 4)
    codes = layer_codes(sizes)
    rng = np.random.default_rng(0)
    kernels = []
    for pre, post in zip(codes[:-1], codes[1:], strict=True):
        a, b = rng.normal(size=pre.shape[1]), rng.normal(size=post.shape[1])
        rule = np.maximum(pre @ a, 0.0)[:, None] + 0.5 * (post @ b)[None, :]  # (n_pre, n_post)
        kernels.append(jnp.asarray(rule / np.sqrt(len(pre)), jnp.float32))
    genome = Genome(sizes, (32,))
    params, loss = fit_gnets(genome, kernels, jax.random.key(0), steps=1500, learning_rate=1e-2)
    generated = genome.generate_kernels(params)
    for g, k in zip(generated, kernels, strict=True):
        assert g.shape == k.shape
        assert float(jnp.mean((g - k) ** 2)) < 1e-3
    assert loss < 1e-3


def test_dgb_param_count_matches_the_gnets_and_biases():
    sizes = (20, 12, 5)
    genome = Genome(sizes, (7,))
    expected = tree_param_count(genome.init(jax.random.key(0))) + 12 + 5
    assert dgb_param_count(sizes, (7,)) == expected
    # codes: 5 bits (20) + 4 bits (12) and 4 bits + one-hot 5; each g-net d -> 7 -> 1
    assert expected == (9 * 7 + 7 + 7 + 1) + (9 * 7 + 7 + 7 + 1) + 17


def test_trained_dgb_holds_exactly_the_generated_kernels():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(96, 6)).astype(np.float32)
    y = (x[:, 0] > 0).astype(np.int32)
    data = Dataset("toy", x, y, x, y, 2)
    config = DenseConfig(hidden=(8,), gnet_hidden=(4,), epochs=3, batch_size=32, rounds=3)
    model, params, history = train_dense(config, data, progress=False)
    genome = Genome((6, 8, 2), (4,))
    for i, kernel in enumerate(genome.generate_kernels(params["genome"])):
        np.testing.assert_allclose(params["params"][f"dense_{i}"]["kernel"], kernel, atol=1e-6)
    assert np.isfinite(history[-1]["fit_mse"])
    assert 0.0 <= dense_accuracy(model, params, x, y) <= 1.0
    with pytest.raises(ValueError, match="rounds"):
        train_dense(DenseConfig(hidden=(8,), gnet_hidden=(4,), rounds=0), data, progress=False)
