"""Chapter 1's figures of the model draw what they say: the expanded table, the sampled
individuals and the genome behind them."""

import jax
import matplotlib
import numpy as np
import pytest

from sgb.celltypes import expand_table
from sgb.noise import standard_normal
from sgb.plots import subplots, wiring

matplotlib.use("agg")

MU = np.array([[1.0, -0.6], [-0.9, 0.7], [0.3, -0.1]], dtype=np.float32)
SIGMA = np.array([[0.1, 0.4], [0.25, 0.05], [0.6, 0.3]], dtype=np.float32)


def sample(shape, n, seed=0):
    """``n`` individuals of the genome (MU, SIGMA): every synapse from its pair's normal."""
    noise = standard_normal(jax.random.PRNGKey(seed), (n, *shape))
    return np.asarray(expand_table(MU, shape) + expand_table(SIGMA, shape) * noise)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    matplotlib.pyplot.close("all")


def test_expansion_draws_the_table_and_its_expand_table():
    shape = (10, 7)  # uneven: the first types get one neuron more
    _, axes = subplots(1, 2)
    left, right = wiring.expansion(MU, shape, axes=axes)
    np.testing.assert_array_equal(left.images[0].get_array(), MU)
    np.testing.assert_array_equal(right.images[0].get_array(), expand_table(MU, shape))
    assert right.images[0].get_array()[3, 4] == MU[0, 1]  # neuron 3 is of type 0 (4, 3, 3)
    assert right.images[0].get_array()[4, 4] == MU[1, 1]
    # one colour scale for both, symmetric about zero
    for ax in (left, right):
        norm = ax.images[0].norm
        assert norm.vmin == -norm.vmax == pytest.approx(-1.0)
    # the type borders: after neurons 3 and 6 along the rows, after 3 along the columns
    rows = sorted(
        line.get_ydata()[0] for line in right.lines if line.get_ydata()[0] == line.get_ydata()[1]
    )
    assert rows == [3.5, 6.5]
    # the entries are written in the table's cells
    assert sorted(t.get_text() for t in left.texts) == sorted(f"{v:.2g}" for v in MU.ravel())


def test_individuals_draws_each_sampled_matrix_in_one_scale():
    kernels = sample((9, 6), 3)
    _, axes = subplots(1, 3)
    wiring.individuals(kernels, MU.shape, axes=axes)
    limit = np.abs(kernels).max()
    for ax, kernel in zip(axes, kernels, strict=True):
        np.testing.assert_array_equal(ax.images[0].get_array(), kernel)
        assert ax.images[0].norm.vmax == pytest.approx(limit)
    assert [ax.get_title() for ax in axes] == ["individual 1", "individual 2", "individual 3"]
    with pytest.raises(ValueError, match="3 individuals"):
        wiring.individuals(kernels, MU.shape, axes=axes[:2])


def test_sampled_individuals_have_the_genomes_moments():
    kernels = sample((9, 6), 2000)
    # individuals differ, synapse by synapse, and the mean network is not one of them
    assert not np.allclose(kernels[0], kernels[1])
    mean, sd = wiring.pair_moments(kernels, MU.shape)
    # 2000 x 9 synapses per pair: the standard error of the mean is sigma / 134
    np.testing.assert_allclose(mean, MU, atol=4 * SIGMA.max() / 134)
    np.testing.assert_allclose(sd, SIGMA, rtol=0.03)


def test_pair_moments_reads_each_block():
    kernel = np.asarray(expand_table(MU, (10, 7)))
    mean, sd = wiring.pair_moments(kernel, MU.shape)
    np.testing.assert_allclose(mean, MU, rtol=1e-6)
    np.testing.assert_allclose(sd, 0.0, atol=1e-7)


def test_model_schematic_draws_the_genome_and_every_synapse_of_every_individual():
    kernels = sample((6, 4), 3)
    _, ax = subplots(figsize=(11, 3.6))
    assert wiring.model_schematic(MU, SIGMA, kernels, ax=ax) is ax
    limit = max(np.abs(MU).max(), np.abs(kernels).max())
    norm = matplotlib.colors.Normalize(-limit, limit)
    # the table squares: mu's six in the weight colours, then sigma's six, darker = wider
    squares = ax.patches[: 2 * MU.size]
    mu_colors = np.array([s.get_facecolor() for s in squares[: MU.size]])
    np.testing.assert_allclose(mu_colors, wiring.WEIGHTS(norm(MU.ravel())))
    darkness = [1 - np.mean(s.get_facecolor()[:3]) for s in squares[MU.size :]]
    assert np.argsort(darkness).tolist() == np.argsort(SIGMA.ravel()).tolist()
    # one LineCollection per individual, a line per synapse coloured by its weight
    edges = [c for c in ax.collections if isinstance(c, matplotlib.collections.LineCollection)]
    assert len(edges) == len(kernels)
    for collection, kernel in zip(edges, kernels, strict=True):
        assert len(collection.get_segments()) == kernel.size
        np.testing.assert_allclose(collection.get_colors(), wiring.WEIGHTS(norm(kernel.ravel())))
        widths = collection.get_linewidths()
        assert np.argmax(widths) == np.argmax(np.abs(kernel.ravel()))
