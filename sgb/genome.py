"""The genome and the development of individuals from it: pure functions on type tables.

A layer's genome is a pair of type tables, ``mu`` and ``rho`` of shape (k_in, k_out, ...):
every synapse between a neuron of input type a and one of output type b draws its weight
from N(mu[a, b], sigma[a, b]^2), sigma = softplus(rho). A network's genome is a dict of
layer genomes by layer name, input to output. An individual is one draw of standard
normal noise per synapse (``draw_noise``); its kernels are mu + sigma * noise
(``kernels``), and the mean network's are the means alone (``mean_kernels``). ``kl`` is
the genome's KL to a weight prior.

This is the one place that knows where a Flax model keeps its genome (``of_params``):
``sgb.layers`` defines the parameters, everything else reads them through here.
"""

from collections.abc import Mapping, Sequence
from typing import Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from sgb import validation
from sgb.celltypes import block_counts, expand_table, sum_blocks
from sgb.noise import standard_normal
from sgb.priors import PRIOR_TYPES, GaussianPrior, Prior

KLCounting = Literal["synapse", "table"]
KL_COUNTINGS = ("synapse", "table")
SOFTPLUS_LIMIT = 88.0  # the largest x whose exp(x) float32 holds with room to spare
KL_INDEX = 2**32 - 1  # the fold-in of an individual's KL key (``kl_key``), never a layer's


class LayerGenome(NamedTuple):
    """One layer's type tables, each (k_in, k_out, ...): means and raw spreads."""

    mu: jnp.ndarray
    rho: jnp.ndarray


Genome = dict[str, LayerGenome]  # by layer name, input to output
Noise = dict[
    str, jnp.ndarray
]  # an individual's standard normal noise, per layer its kernel's shape
Shapes = Mapping[str, tuple[int, ...]]  # each layer's kernel shape (n_in, n_out, ...)


@jax.custom_jvp
def softplus(x: jnp.ndarray) -> jnp.ndarray:
    """log(1 + e^x): the one softplus of the package's spreads, sigma = softplus(rho) of
    every genome, wherever it is computed (the layers, their KL, the RL agents).

    Computed as log1p(exp(min(x, SOFTPLUS_LIMIT))): bit for bit log1p(exp(x)) wherever
    float32's exp(x) is finite (x <= 88); equal to ``jax.nn.softplus`` to float32 rounding
    (bit for bit for x <= 0, where every trained rho lies). Above 88 it saturates, a
    spread no genome reaches; its gradient stays sigmoid(x) everywhere, so a rho up there
    is still pulled back. Ending in log1p matters for speed: XLA computes it once per
    type-pair table, where ``jax.nn.softplus``, which ends in a max and an add, is fused
    into the per-synapse loop of ``individual_kernel`` (see there).
    """
    return jnp.log1p(jnp.exp(jnp.minimum(x, SOFTPLUS_LIMIT)))


@softplus.defjvp
def _softplus_jvp(primals, tangents):
    (x,), (t,) = primals, tangents
    return softplus(x), t * jax.nn.sigmoid(x)


def sigma(layer: LayerGenome) -> jnp.ndarray:
    """The layer's spreads softplus(rho), shape of the type table (weight units)."""
    return softplus(layer.rho)


def of_params(params: dict) -> Genome:
    """Every SGB layer's genome in a Flax ``{"params": ...}`` tree, keyed by the layer's
    path ("SGBDense_0", "hidden_1", "Encoder/SGBDense_0"), input to output."""
    tree = _params_tree(params)
    return {path: LayerGenome(g["mu"], g["rho"]) for path, g in _genome_nodes(tree)}


def mean_sigma(actor_params: dict) -> float:
    """Mean sigma over every type pair of the actor's SGB hidden layers."""
    return float(np.mean([np.mean(sigma(g)) for g in of_params(actor_params).values()]))


def layer_sigmas(actor_params: dict) -> dict[str, float]:
    """Mean sigma over each SGB layer's type pairs, by the layer's path (none for a
    network without SGB layers)."""
    return {path: float(np.mean(sigma(g))) for path, g in of_params(actor_params).items()}


def with_tables(params: dict, genome: Genome) -> dict:
    """A copy of the Flax ``{"params": ...}`` tree ``params`` whose layers at the paths of
    ``genome`` hold its tables (``of_params``'s inverse). Each layer's ``mu`` and ``rho``
    share a shape, that of the tables they replace where the layer has a genome already;
    a layer without one gets it."""
    out = {"params": dict(_params_tree(params))}
    for path, layer in _layers(genome).items():
        node = out["params"]
        for key in filter(None, path.split("/")):  # "": a lone layer, at the root
            node[key] = dict(node.get(key, {}))
            node = node[key]
        _check_tables(f"genome[{path!r}]", layer, node.get("genome"))
        node["genome"] = {"mu": layer.mu, "rho": layer.rho}
    return out


def _params_tree(params: dict) -> Mapping:
    """The tree under ``"params"`` of a Flax ``{"params": ...}`` tree; a ``TypeError``
    naming ``params`` for anything else."""
    if not isinstance(params, Mapping) or not isinstance(params.get("params"), Mapping):
        got = f"keys {sorted(map(str, params))}" if isinstance(params, Mapping) else params
        raise TypeError(f"params must be a Flax tree {{'params': {{...}}}}, got {got!s:.200}")
    return params["params"]


def _layers(genome: Genome, wanted: Mapping | None = None, by: str = "") -> Genome:
    """The layers of ``genome`` named by the keys of ``wanted`` (the argument called
    ``by``; all of them when ``None``), once ``genome`` is checked to be a mapping that
    holds each of them as a ``LayerGenome``."""
    validation.instance("genome", genome, Mapping)
    names = list(genome if wanted is None else wanted)
    for name in names:
        if name not in genome:
            raise ValueError(f"genome has no layer {name!r} of {by}; its layers: {list(genome)}")
        if not isinstance(genome[name], LayerGenome):
            kind = type(genome[name]).__name__
            raise TypeError(f"genome[{name!r}] must be a LayerGenome, got a {kind}")
    return {name: genome[name] for name in names}


def _check_tables(name: str, layer: LayerGenome, stored: Mapping | None) -> None:
    """``layer``'s ``mu`` and ``rho`` are arrays of one shape, that of the ``stored``
    genome's tables when there is one."""
    mu = validation.array(f"{name}.mu", layer.mu, min_ndim=1)
    rho = validation.array(f"{name}.rho", layer.rho)
    expected = tuple(mu.shape) if stored is None else tuple(np.shape(stored["mu"]))
    whose = "mu's shape" if stored is None else "the shape of the tables it replaces,"
    for field, table in (("mu", mu), ("rho", rho)):
        if tuple(table.shape) != expected:
            raise ValueError(
                f"{name}.{field} must have {whose} {expected}, got {tuple(table.shape)}"
            )


def aliased_table(table: jnp.ndarray) -> jnp.ndarray:
    """The table (k_in, k_out) as the authors' RL layers read it: entry [a, b] is flat
    entry (a + 1)(b + 1) - 1 of ``table`` (``RL/utils.py``, ``gather_nd_torch_dims_flat``,
    whose ``to1d`` gets the type arrays plus one where it wants the table's sizes). Pairs
    whose (a + 1)(b + 1) agree share one Gaussian, and entries no pair reaches are unused;
    the gradient of a shared entry sums over the pairs that read it."""
    table = validation.array("table", table, min_ndim=2)
    if table.ndim != 2:
        raise ValueError(f"table must be (k_in, k_out), got shape {tuple(table.shape)}")
    k_in, k_out = table.shape
    a, b = np.meshgrid(np.arange(k_in), np.arange(k_out), indexing="ij")
    return table.reshape(-1)[(a + 1) * (b + 1) - 1]


def aliased(layer: LayerGenome) -> LayerGenome:
    """A dense layer's genome with both tables read as ``aliased_table`` reads them."""
    return LayerGenome(aliased_table(layer.mu), aliased_table(layer.rho))


def sown(collection: Mapping, name: str) -> dict[str, jnp.ndarray]:
    """What the SGB layers sowed under ``name`` into a Flax collection (``"kernel"`` and
    ``"noise"`` into ``"individual"``, ``"kl"`` into ``"losses"``), by layer path."""
    return {path: node[name] for path, node in _genome_nodes(collection)}


def _genome_nodes(tree: Mapping, path: tuple[str, ...] = ()):
    """(layer path, the layer's genome node) of every SGB layer in ``tree``, in order."""
    for key, sub in tree.items():
        if key == "genome":
            yield "/".join(path), sub
        elif isinstance(sub, Mapping):
            yield from _genome_nodes(sub, (*path, key))


def draw_layer_noise(key: jax.Array, shape: Sequence[int]) -> jnp.ndarray:
    """One layer's standard normal noise, shape ``shape``: the one draw of an individual's
    synapses (``sgb.noise.standard_normal``), used by the layers and the agents alike."""
    return standard_normal(key, tuple(shape))


def layer_key(key: jax.Array, index: int) -> jax.Array:
    """The key of drawn layer ``index`` (0, 1, ... input to output) of the individual born
    from ``key``: ``fold_in(key, index)``, which is ``jax.random.split(key, n)[index]``
    for every n > index (JAX's partitionable threefry, its default). The one derivation
    of an individual's layers, for ``draw_noise`` and the SGB layers (``sgb.layers``)."""
    return jax.random.fold_in(key, index)


def kl_key(key: jax.Array) -> jax.Array:
    """The key the SGB layers of the individual born from ``key`` draw their Monte Carlo
    KL from (``kl``'s key): ``fold_in(key, KL_INDEX)``, apart from every layer's key."""
    return jax.random.fold_in(key, KL_INDEX)


def draw_noise(key: jax.Array, shapes: Shapes) -> Noise:
    """An individual's noise: per layer of ``shapes``, ``draw_layer_noise`` with its own
    key, layer i's ``layer_key(key, i)`` in order. vmap it over keys for many individuals
    (a leading axis N on every layer)."""
    return {
        name: draw_layer_noise(layer_key(key, i), shape)
        for i, (name, shape) in enumerate(shapes.items())
    }


def kernels(genome: Genome, noise: Noise) -> dict[str, jnp.ndarray]:
    """The individuals' kernels of the layers in ``noise``, each ``individual_kernel`` of
    its layer's genome: shape of the noise, (..., n_in, n_out), leading axes individuals."""
    layers = _layers(genome, noise, "noise")
    return {name: individual_kernel(*layers[name], n) for name, n in noise.items()}


def mean_kernels(genome: Genome, shapes: Shapes) -> dict[str, jnp.ndarray]:
    """The mean network's kernels: each type mean expanded to its block of ``shapes``."""
    layers = _layers(genome, shapes, "shapes")
    return {name: expand_table(layers[name].mu, shape) for name, shape in shapes.items()}


def kl(
    genome: Genome, shapes: Shapes, prior: Prior, key: jax.Array, counting: KLCounting = "synapse"
) -> jnp.ndarray:
    """The genome's KL to ``prior``, a scalar (nats): ``layer_kl`` summed over the layers
    of ``shapes``, layer i's with ``layer_key(key, i)``; 0 for none."""
    layers = _layers(genome, shapes, "shapes")
    validation.prng_key("key", key)
    if not shapes:
        return jnp.zeros(())
    return sum(
        layer_kl(prior, layers[name].mu, sigma(layers[name]), shape, counting, layer_key(key, i))
        for i, (name, shape) in enumerate(shapes.items())
    )


def layer_kl(
    prior: Prior,
    mu: jnp.ndarray,
    sigma: jnp.ndarray,
    shape: Sequence[int],
    counting: KLCounting,
    key: jax.Array,
) -> jnp.ndarray:
    """KL of one layer's genome to the prior, a scalar (nats).

    ``mu``, ``sigma``: type tables (k_in, k_out, ...) of a kernel of ``shape``. Every
    synapse of a type pair has that pair's Gaussian, so the KL is computed per pair: in
    closed form for a Gaussian prior, else as the one-draw Monte Carlo term
    log q(w) - log p(w) at w = mu + sigma * eps, eps ~ N(0, 1) from ``key`` (unbiased).
    ``counting="synapse"`` weights each pair by its number of synapses (the KL of the
    full weight matrix, as Bayes by backprop counts it); ``"table"`` counts each pair once.
    The cost is that of the tables, not of the kernel. Its arguments are checked at the
    Python level (shapes always; values, sigma > 0 and finite, only outside ``jit``).
    """
    validation.instance("prior", prior, PRIOR_TYPES)
    validation.choice("counting", counting, KL_COUNTINGS)
    mu = validation.array("mu", mu, min_ndim=1)
    sigma = validation.array("sigma", sigma)
    if tuple(sigma.shape) != tuple(mu.shape):
        raise ValueError(f"sigma must have mu's shape {tuple(mu.shape)}, got {tuple(sigma.shape)}")
    shape = validation.integers("shape", shape)
    if len(shape) != len(mu.shape):
        raise ValueError(f"shape {shape} must have one entry per axis of mu {tuple(mu.shape)}")
    if not validation.is_traced(sigma) and not bool(np.all(np.asarray(sigma) > 0)):
        raise ValueError("sigma must be > 0 (and not nan)")
    if isinstance(prior, GaussianPrior):
        per_pair = prior.kl(mu, sigma)
    else:
        validation.prng_key("key", key)
        per_pair = prior.kl(mu, sigma, mu + sigma * standard_normal(key, mu.shape))
    counts = jnp.asarray(block_counts(shape, mu.shape), dtype=mu.dtype)
    return jnp.sum(per_pair * counts) if counting == "synapse" else jnp.sum(per_pair)


def individual_kernel(mu: jnp.ndarray, rho: jnp.ndarray, noise: jnp.ndarray) -> jnp.ndarray:
    """Individuals' full kernels from type tables ``mu``, ``rho`` (k_in, k_out, ...) and
    their ``noise`` (..., n_in, n_out, ...): mu + softplus(rho) * noise, each synapse from
    its pair. Axes of ``noise`` before the table's are individuals (none for one).

    Three things keep its cost near that of the noise alone (``benchmarks/bench_layers.py``):

    - ``softplus`` ends in log1p(exp(.)), which XLA computes once per type pair;
      ``jax.nn.softplus`` also reads rho through a max that XLA fused into the
      per-synapse loop (7x slower for 784 x 800 of 30 x 100 types);
    - the gradient takes the noise back from the kernel, (kernel - mu) / sigma, instead
      of from ``noise``, which XLA would compute a second time inside the backward pass;
    - the gradient sums over individuals by pairwise halving (``_sum_leading``).

    The shapes are checked when it is traced (``ValueError``/``TypeError`` naming the
    argument), at no cost per call of a compiled step.
    """
    mu = validation.array("mu", mu, min_ndim=1)
    rho = validation.array("rho", rho)
    noise = validation.array("noise", noise, min_ndim=len(mu.shape))
    if tuple(rho.shape) != tuple(mu.shape):
        raise ValueError(f"rho must have mu's shape {tuple(mu.shape)}, got {tuple(rho.shape)}")
    for name, value in (("mu", mu), ("rho", rho), ("noise", noise)):
        if not jnp.issubdtype(value.dtype, jnp.floating):
            raise TypeError(f"{name} must be a float array, got dtype {value.dtype}")
    for axis, (k, n) in enumerate(zip(mu.shape, noise.shape[noise.ndim - mu.ndim :], strict=True)):
        if not 0 < k <= n:
            raise ValueError(
                f"noise has {n} neurons along axis {axis} of the kernel, fewer than mu's {k} "
                "cell types (or none)"
            )
    return _individual_kernel(mu, rho, noise)


@jax.custom_vjp
def _individual_kernel(mu: jnp.ndarray, rho: jnp.ndarray, noise: jnp.ndarray) -> jnp.ndarray:
    shape = noise.shape[noise.ndim - mu.ndim :]
    return expand_table(mu, shape) + expand_table(softplus(rho), shape) * noise


def _sum_leading(x: jnp.ndarray, n: int) -> jnp.ndarray:
    """``x`` summed over its first ``n`` axes, by adding halves until one is left.

    XLA on CPU fuses a sum over a leading axis of a product into a slow loop (4-5x the
    halving's time for 32 individuals of 128 x 128 before a block sum).
    """
    x = x.reshape((-1, *x.shape[n:]))
    while x.shape[0] > 1:
        half = x.shape[0] // 2
        x = jnp.concatenate([x[:half] + x[half : 2 * half], x[2 * half :]])
    return x[0]


def _individual_kernel_forward(mu, rho, noise):
    kernel = _individual_kernel(mu, rho, noise)
    return kernel, (mu, rho, kernel)


def _individual_kernel_backward(residuals, grad):
    mu, rho, kernel = residuals
    n = kernel.ndim - mu.ndim
    shape = kernel.shape[n:]
    spread = softplus(rho)
    # d sigma / d rho = sigmoid(rho); divided by sigma it tends to 1 as rho -> -inf
    dsigma_over_sigma = jnp.where(rho < -20.0, 1.0, jax.nn.sigmoid(rho) / spread)
    sigma_noise = kernel - expand_table(mu, shape)
    return (
        sum_blocks(_sum_leading(grad, n), mu.shape),
        sum_blocks(_sum_leading(grad * sigma_noise, n), mu.shape) * dsigma_over_sigma,
        expand_table(spread, shape) * grad,
    )


_individual_kernel.defvjp(_individual_kernel_forward, _individual_kernel_backward)
