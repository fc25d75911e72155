"""Deterministic genomic bottleneck (DGB, after Koulakov et al., 2021), trained as its
authors train it.

Every neuron of the phenotypic network (p-net) carries a fixed code: the binary
digits of its index, as +-1 (``binary_codes``), or a one-hot vector for the output
layer. A genomic network (g-net) maps the concatenated (pre code, post code) of a
synapse through hidden ReLU layers to its weight, so a g-net of P parameters defines
all n_pre x n_post weights of its layer; a biases' g-net maps a neuron's code to its
bias. Which parameters are generated, through which g-nets, is the layout
(``sgb.dgb_layout``: ours, every kernel through (width, 10) and every bias stored, or
the authors'); the rest is stored directly.

``train_dgb`` alternates for ``rounds`` rounds: ``pnet_steps`` Adam minibatches of the
p-net on cross-entropy, then fitting the g-nets to the p-net's parameters (mean squared
error on random minibatches of ``gnet_batch`` entries: under our layout ``gnet_steps``
steps of all g-nets together, under the authors' each g-net alone for its epochs), then
writing the generated parameters back into the p-net. After every write-back the
generated network is scored on a validation set drawn from the training images (as the
authors do); the best one is the innate network. The whole training state is one
``DGBState``, passed and returned.

The genome is the g-nets' parameters plus the p-net's biases stored directly;
``sgb.compression.dgb_param_count`` counts them.
"""

import dataclasses
from collections.abc import Sequence
from functools import lru_cache, partial
from typing import Any

import flax
import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax.training.train_state import TrainState

from sgb import validation
from sgb.classifiers import DenseClassifier, dense_sizes
from sgb.data import Dataset, check_dataset
from sgb.dgb_layout import LAYOUTS, GNetSpec, code_dims, entries, gnet_specs, input_dim
from sgb.divergence import FIT_BOUND, Guard, learning_rate_cause
from sgb.training import accuracy, adam_state, cross_entropy_step, train_loop

GNetParams = list[tuple[jnp.ndarray, jnp.ndarray]]


def binary_codes(n: int) -> np.ndarray:
    """Binary digits of 0..n-1 as +-1, shape (n, max(1, ceil(log2 n))), most significant first."""
    if int(n) != n or n <= 0:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    bits = max(1, int(np.ceil(np.log2(n))))
    digits = (np.arange(n)[:, None] >> np.arange(bits - 1, -1, -1)[None, :]) & 1
    return (2.0 * digits - 1.0).astype(np.float32)


def layer_codes(sizes: Sequence[int]) -> list[np.ndarray]:
    """Codes of every neuron layer of an MLP with ``sizes``: binary, one-hot for the output."""
    if len(sizes) < 2:
        raise ValueError(f"sizes needs at least an input and an output layer, got {sizes}")
    codes = [binary_codes(n) for n in sizes[:-1]] + [np.eye(sizes[-1], dtype=np.float32)]
    assert [c.shape[1] for c in codes] == code_dims(sizes)
    return codes


def init_gnet(key: jax.Array, code_dim: int, hidden: Sequence[int]) -> GNetParams:
    """(kernel, bias) of each layer of a g-net code_dim -> *hidden -> 1, He-initialised."""
    widths = (code_dim, *hidden, 1)
    keys = jax.random.split(key, len(widths) - 1)
    return [
        (jax.random.normal(k, (a, b)) * jnp.sqrt(2.0 / a), jnp.zeros(b))
        for k, a, b in zip(keys, widths[:-1], widths[1:], strict=True)
    ]


def _gnet_tail(layers: GNetParams, h: jnp.ndarray) -> jnp.ndarray:
    """The g-net after its first layer's pre-activation ``h`` (..., width) -> (...)."""
    h = jax.nn.relu(h)
    for kernel, bias in layers[1:-1]:
        h = jax.nn.relu(h @ kernel + bias)
    kernel, bias = layers[-1]
    return (h @ kernel + bias)[..., 0]


def generate_kernel(layers: GNetParams, pre: jnp.ndarray, post: jnp.ndarray) -> jnp.ndarray:
    """The (n_pre, n_post) kernel a g-net encodes, scaled by 1/sqrt(n_pre).

    The first layer is split into its pre and post halves, so each synapse's
    first pre-activation is a sum of two per-neuron terms; rows are generated in
    chunks to bound memory.
    """
    kernel, bias = layers[0]
    a = pre @ kernel[: pre.shape[1]]  # (n_pre, width)
    b = post @ kernel[pre.shape[1] :] + bias  # (n_post, width)
    rows = jax.lax.map(lambda row: _gnet_tail(layers, row + b), a, batch_size=16)
    return rows / jnp.sqrt(pre.shape[0])


def generate_biases(layers: GNetParams, post: jnp.ndarray) -> jnp.ndarray:
    """The biases (n_post,) a biases' g-net encodes from its neurons' codes (n_post, code)."""
    kernel, bias = layers[0]
    return _gnet_tail(layers, post @ kernel + bias)


def bias_fit_loss(
    layers: GNetParams, post: jnp.ndarray, biases: jnp.ndarray, key: jax.Array, batch: int
) -> jnp.ndarray:
    """Mean squared error, on ``batch`` random neurons, between a biases' g-net's outputs
    and the biases."""
    j = jax.random.randint(key, (batch,), 0, post.shape[0])
    return jnp.mean((generate_biases(layers, post[j]) - biases[j]) ** 2)


def fit_loss(
    layers: GNetParams,
    pre: jnp.ndarray,
    post: jnp.ndarray,
    kernel: jnp.ndarray,
    key: jax.Array,
    batch: int,
) -> jnp.ndarray:
    """Mean squared error, on ``batch`` random synapses, between the g-net's outputs and
    the kernel times sqrt(n_pre) (dimensionless)."""
    i_key, j_key = jax.random.split(key)
    i = jax.random.randint(i_key, (batch,), 0, pre.shape[0])
    j = jax.random.randint(j_key, (batch,), 0, post.shape[0])
    first, bias = layers[0]
    h = pre[i] @ first[: pre.shape[1]] + post[j] @ first[pre.shape[1] :] + bias
    target = kernel[i, j] * jnp.sqrt(pre.shape[0])
    return jnp.mean((_gnet_tail(layers, h) - target) ** 2)


@dataclasses.dataclass(frozen=True)
class DGBConfig:
    """A DGB classifier and its training (defaults: the authors', ``rounds`` aside).

    ``hidden``: p-net hidden widths; ``gnet_width``: first hidden layer of the kernels'
    g-nets (the second has 10 units); ``layout``: ``sgb.dgb_layout``'s ``"ours"`` or
    ``"authors"``. Per round: ``pnet_steps`` minibatches of ``batch_size``, then the
    g-nets' fit on minibatches of ``gnet_batch`` entries: ``gnet_steps`` steps of all
    together (ours), or each g-net's epochs of its entries (the authors').
    ``validation_size`` training images score each write-back.
    """

    hidden: tuple[int, ...] = (800,)
    gnet_width: int = 50
    rounds: int = 100
    pnet_steps: int = 100
    batch_size: int = 100
    learning_rate: float = 1e-3
    gnet_steps: int = 600
    gnet_batch: int = 1000
    gnet_learning_rate: float = 1e-3
    validation_size: int = 10_000
    seed: int = 0
    conv_features: tuple[int, ...] = ()
    layout: str = "ours"

    def __post_init__(self) -> None:
        validation.integers("hidden", self.hidden)
        validation.choice("layout", self.layout, LAYOUTS)
        for name in (
            "gnet_width",
            "rounds",
            "pnet_steps",
            "batch_size",
            "gnet_steps",
            "gnet_batch",
            "validation_size",
        ):
            validation.integer(name, getattr(self, name))
        validation.positive("learning_rate", self.learning_rate)
        validation.positive("gnet_learning_rate", self.gnet_learning_rate)
        validation.integer("seed", self.seed, minimum=0)
        if self.conv_features:
            validation.integers("conv_features", self.conv_features)


@flax.struct.dataclass
class DGBState:
    """Everything a DGB's training carries from step to step.

    ``pnet``: the p-net and its optimizer; ``gnets``/``gnet_opt``: every g-net (in the
    layout's order) and the optimizer state of each group fitted together;
    ``best_params``/``best_gnets``/``best_accuracy``: the generated network with the
    highest validation accuracy so far; ``fit_mse``: the last fit's largest error;
    ``rounds``: write-backs done; ``key``: for synapse sampling.
    """

    pnet: TrainState
    gnets: list[GNetParams]
    gnet_opt: Any
    best_params: Any
    best_gnets: list[GNetParams]
    best_accuracy: jnp.ndarray
    fit_mse: jnp.ndarray
    rounds: jnp.ndarray
    key: jax.Array


class DGB:
    """The codes, layout, optimizers and jitted functions of a DGB for one config and data
    shape.

    ``specs`` are its g-nets (``sgb.dgb_layout.gnet_specs``) and ``groups`` the indices of
    those fitted together, each with its own optimizer and ``steps`` per round.
    ``pnet_step`` and ``write_back_step`` are the compiled steps; both donate the state.
    """

    def __init__(self, config: DGBConfig, input_shape: Sequence[int], num_classes: int):
        self.config = config
        self.sizes = dense_sizes(input_shape, config.conv_features, config.hidden, num_classes)
        self.codes = [jnp.asarray(c) for c in layer_codes(self.sizes)]
        self.specs = gnet_specs(self.sizes, config.gnet_width, config.layout)
        if config.layout == "ours":
            self.groups = [list(range(len(self.specs)))]
            self.steps = [config.gnet_steps]
        else:
            self.groups = [[i] for i in range(len(self.specs))]
            self.steps = [
                s.epochs * -(-entries(s, self.sizes) // self._batch(s)) for s in self.specs
            ]
        self.model = DenseClassifier(
            (*config.hidden, num_classes), config.conv_features, tuple(input_shape)
        )
        self.gnet_tx = optax.adam(config.gnet_learning_rate)
        self.pnet_step = jax.jit(pnet_step, donate_argnums=0)
        self.write_back_step = jax.jit(self.write_back, donate_argnums=0)

    def _batch(self, spec: GNetSpec) -> int:
        """Entries per fitting minibatch: ``gnet_batch`` (drawn with replacement), under the
        authors' layout all of them if fewer (their ``Batch_Size = min(1000, n)``)."""
        if self.config.layout == "ours":
            return self.config.gnet_batch
        return min(self.config.gnet_batch, entries(spec, self.sizes))

    def init(self, x: np.ndarray) -> DGBState:
        """Initial state: a random p-net overwritten by fresh g-nets' parameters."""
        pnet_key, gnet_key, key = jax.random.split(jax.random.key(self.config.seed), 3)
        params = self.model.init(pnet_key, x[:1])
        pnet = adam_state(self.model.apply, params, self.config.learning_rate)
        dims = [c.shape[1] for c in self.codes]
        keys = jax.random.split(gnet_key, len(self.specs))
        gnets = [
            init_gnet(k, input_dim(s, dims), s.hidden)
            for k, s in zip(keys, self.specs, strict=True)
        ]
        pnet = pnet.replace(params=self.with_generated(params, gnets))
        copy = partial(jax.tree_util.tree_map, jnp.copy)  # own buffers, so steps can donate
        return DGBState(
            pnet=pnet,
            gnets=gnets,
            gnet_opt=[self.gnet_tx.init([gnets[i] for i in group]) for group in self.groups],
            best_params=copy(pnet.params),
            best_gnets=copy(gnets),
            best_accuracy=jnp.asarray(-1.0, jnp.float32),  # strong types, as steps return them
            fit_mse=jnp.asarray(jnp.nan, jnp.float32),
            rounds=jnp.asarray(0, jnp.int32),
            key=key,
        )

    def generate(self, spec: GNetSpec, gnet: GNetParams) -> jnp.ndarray:
        """What one g-net encodes: its layer's kernel (n_pre, n_post) or biases (n_post,)."""
        post = self.codes[spec.layer + 1]
        if spec.target == "kernel":
            return generate_kernel(gnet, self.codes[spec.layer], post)
        return generate_biases(gnet, post)

    def with_generated(self, params: Any, gnets: list[GNetParams]) -> Any:
        """``params`` of the p-net with every generated parameter replaced by its g-net's."""
        inner = dict(params["params"])
        for spec, gnet in zip(self.specs, gnets, strict=True):
            name = f"dense_{spec.layer}"
            inner[name] = {**inner[name], spec.target: self.generate(spec, gnet)}
        return {**params, "params": inner}

    def _fit_loss(self, group: list[int], gnets, targets, key) -> jnp.ndarray:
        """Mean over the group's g-nets of each one's fitting error to its target."""
        keys = jax.random.split(key, len(group))
        losses = []
        for i, gnet, layer_key in zip(group, gnets, keys, strict=True):
            spec, post = self.specs[i], self.codes[self.specs[i].layer + 1]
            if spec.target == "kernel":
                pre = self.codes[spec.layer]
                losses.append(fit_loss(gnet, pre, post, targets[i], layer_key, self._batch(spec)))
            else:
                losses.append(bias_fit_loss(gnet, post, targets[i], layer_key, self._batch(spec)))
        return sum(losses) / len(losses)

    def write_back(self, state: DGBState, x_val: jnp.ndarray, y_val: jnp.ndarray) -> DGBState:
        """Fit the g-nets to the p-net's parameters, write theirs back, keep the best."""
        inner = state.pnet.params["params"]
        targets = [inner[f"dense_{s.layer}"][s.target] for s in self.specs]
        key, fit_key = jax.random.split(state.key)
        group_keys = (
            [fit_key] if len(self.groups) == 1 else jax.random.split(fit_key, len(self.groups))
        )
        gnets, opts, last = list(state.gnets), [], []
        for group, steps, opt, group_key in zip(
            self.groups, self.steps, state.gnet_opt, group_keys, strict=True
        ):

            def step(carry, step_key, group=group):
                fitted, opt = carry
                loss, grads = jax.value_and_grad(
                    lambda g: self._fit_loss(group, g, targets, step_key)
                )(fitted)
                updates, opt = self.gnet_tx.update(grads, opt, fitted)
                return (optax.apply_updates(fitted, updates), opt), loss

            (fitted, opt), losses = jax.lax.scan(
                step, ([gnets[i] for i in group], opt), jax.random.split(group_key, steps)
            )
            for i, gnet in zip(group, fitted, strict=True):
                gnets[i] = gnet
            opts.append(opt)
            last.append(losses[-1])
        params = self.with_generated(state.pnet.params, gnets)
        score = accuracy(self.model.apply(params, x_val), y_val)
        better = score > state.best_accuracy

        def pick(new, old):
            return jax.tree_util.tree_map(lambda a, b: jnp.where(better, a, b), new, old)

        return state.replace(
            pnet=state.pnet.replace(params=params),
            gnets=gnets,
            gnet_opt=opts,
            best_params=pick(params, state.best_params),
            best_gnets=pick(gnets, state.best_gnets),
            best_accuracy=jnp.maximum(score, state.best_accuracy),
            fit_mse=jnp.max(jnp.stack(last)),
            rounds=state.rounds + 1,
            key=key,
        )


def pnet_step(state: DGBState, x, y, key) -> tuple[DGBState, dict]:
    """One p-net minibatch step on cross-entropy (the baseline's step)."""
    pnet, metrics = cross_entropy_step(state.pnet, x, y, key)
    return state.replace(pnet=pnet), metrics


@lru_cache(maxsize=4)
def dgb_for(config: DGBConfig, input_shape: tuple[int, ...], num_classes: int) -> DGB:
    """The ``DGB`` of ``config`` for inputs of ``input_shape``, built once per process, so
    that training it again in chunks (``train_dgb`` with a ``state``) compiles nothing anew."""
    return DGB(config, input_shape, num_classes)


def train_dgb(
    config: DGBConfig, data: Dataset, progress: bool = True, state: DGBState | None = None
) -> tuple[DGB, DGBState, list[dict[str, float]]]:
    """Train a DGB on ``data`` for ``config.rounds`` rounds; returns (the DGB, its final
    state, per-epoch history).

    ``state.best_params`` is the innate network (its kernels generated by
    ``state.best_gnets``), chosen on ``config.validation_size`` training images.
    Given a ``state`` (a DGB of this config trained for ``state.rounds`` rounds), training
    continues from it, and the state passed in is consumed (its buffers are reused).
    Training stops (``sgb.divergence.TrainingDiverged``) when the p-net's loss blows up or
    a write-back's fit error exceeds ``sgb.divergence.FIT_BOUND``.
    """
    validation.instance("config", config, DGBConfig)
    check_dataset(data)
    dgb = dgb_for(config, data.x_train.shape[1:], data.num_classes)
    n_val = min(config.validation_size, len(data.x_train))
    pick = np.random.default_rng(config.seed + 1).choice(len(data.x_train), n_val, replace=False)
    x_val, y_val = jnp.asarray(data.x_train[pick]), jnp.asarray(data.y_train[pick])
    state = dgb.init(data.x_train) if state is None else state
    guard = Guard("p-net loss", cause=lambda: learning_rate_cause("learning_rate"))
    fit_guard = Guard(cause=lambda: learning_rate_cause("gnet_learning_rate"))

    def write_back(state: DGBState) -> DGBState:
        state = dgb.write_back_step(state, x_val, y_val)
        rounds = int(state.rounds)
        what = f"the g-nets' fit error after round {rounds}"
        fit_guard.bound(what, state.fit_mse, rounds * config.pnet_steps, FIT_BOUND)
        return state

    # the state is donated: its buffers (the best network among them) are reused, not copied
    state, history = train_loop(
        state,
        dgb.pnet_step,
        data.x_train,
        data.y_train,
        batch_size=config.batch_size,
        num_steps=config.rounds * config.pnet_steps,
        seed=config.seed + int(state.rounds),
        hook=write_back,
        hook_every=config.pnet_steps,
        params_of=lambda state: state.pnet.params,
        progress=progress,
        desc="DGB training",
        num_classes=data.num_classes,
        guard=guard,
    )
    return dgb, state, history
