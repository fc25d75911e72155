"""The actor-critic agent, vanilla or SGB, built once: its networks, births and one policy.

Both networks are MLPs (swish between layers). In SGB mode the hidden layers are
``sgb.layers.SGBDense`` layers whose neurons fall into ``cell_types`` types (the input
layer keeps one type per observation entry) and the output layer is an ordinary
deterministic ``nn.Dense``, as in the paper. The authors' code does two things more, each
a switch here: ``typed_inputs`` groups the observation entries into types too, and
``sgb_output`` makes the output layer an SGB layer (``min(cell_types, n)`` types for n
neurons), and ``bayesian_biases`` draws every SGB layer's biases too, per neuron. In
vanilla mode every layer is ``nn.Dense``. Two more switches follow the authors' RL code
where it departs from the paper or from us: ``aliased_pairs`` reads a layer's type table
as their layers do (``sgb.genome.aliased_table``), and ``normalizer`` scales the
observations by their convention (``sgb.rl.normalizer``).

An individual is born from a PRNG key (``Agent.birth``): the standard normal noise of
every SGB synapse of its actor and critic (``sgb.genome.draw_noise``), kept for its whole
life. ``Network.layers`` develops that noise under the current genome into its phenotype,
the (kernel, bias) of every layer; ``Agent.policy`` and ``Agent.value`` run phenotypes.
Training, evaluation, populations and rendering all act through ``Agent.policy``, so the
same key always gives the same behaviour. Flax defines the parameters (``MLP``, used to
initialise them); the forward pass is ``forward``.
"""

from dataclasses import dataclass, fields
from functools import cached_property, partial
from typing import NamedTuple

import flax.linen as nn
import jax
import jax.numpy as jnp

from sgb import genome, validation
from sgb.layers import SGBDense, _check_input, individual_matmul
from sgb.priors import GaussianPrior, Prior, ScaleMixturePrior
from sgb.rl.normalizer import CONVENTIONS, Normalizer, normalize

Layers = list[tuple[jnp.ndarray, jnp.ndarray]]  # (kernel, bias) of every layer, input to output
MIN_STD = 1e-3
DENSE_INITS = ("flax", "torch")


@dataclass(frozen=True)
class Architecture:
    """What a network's forward pass and its KL read: its shape and its genome's prior.

    ``cell_types=None`` is the vanilla (deterministic) network; an integer gives SGB
    hidden layers with that many cell types per hidden layer. ``prior`` is ``"mixture"``
    (scale mixture, pi=0.5, sigma1=1, sigma2=e^-6) or ``"gaussian"`` (N(0, 0.1^2)).
    ``typed_inputs`` groups the observation entries into ``cell_types`` types;
    ``sgb_output`` makes the output layer an SGB layer; ``bayesian_biases`` draws the SGB
    layers' biases, each neuron's from its own Gaussian (``sgb.layers.SGBDense``).
    ``aliased_pairs`` makes type pair (a, b) of every SGB kernel read table entry
    (a + 1)(b + 1) - 1, as the authors' RL layers index it (a defect of their code: the
    paper gives every pair its own Gaussian). ``normalizer`` is the convention that
    scales observations, ``"ours"`` or ``"authors"`` (``sgb.rl.normalizer``).
    """

    hidden: tuple[int, ...] = (128, 128)
    cell_types: int | None = None
    prior: str = "mixture"
    typed_inputs: bool = False
    sgb_output: bool = False
    bayesian_biases: bool = False
    aliased_pairs: bool = False
    normalizer: str = "ours"

    def __post_init__(self) -> None:
        validation.integers("hidden", self.hidden)
        for name in ("typed_inputs", "sgb_output", "bayesian_biases", "aliased_pairs"):
            validation.instance(name, getattr(self, name), bool)
        validation.choice("normalizer", self.normalizer, CONVENTIONS)
        if self.aliased_pairs and self.cell_types is None:
            raise ValueError("aliased_pairs needs cell types: a vanilla network has no table")
        if self.cell_types is not None and not (
            0 < validation.integer("cell_types", self.cell_types) <= min(self.hidden)
        ):
            raise ValueError(
                f"cell_types must lie in [1, {min(self.hidden)}], got {self.cell_types}"
            )
        if self.prior not in ("mixture", "gaussian"):
            raise ValueError(f"prior must be 'mixture' or 'gaussian', got {self.prior!r}")

    @property
    def sgb(self) -> bool:
        return self.cell_types is not None


@dataclass(frozen=True)
class NetworkConfig(Architecture):
    """An ``Architecture`` and how its parameters start: ``rho_init`` every spread's raw
    value, each drawn from N(rho_init, rho_init_std^2) (the authors': N(-7, 0.1^2),
    ``RL/custom_layers.py``); ``mean_init`` the standard deviation of the initial type
    means (``None``: 1/sqrt(n_in) of each layer); ``dense_init`` how the deterministic
    layers start: ``"flax"`` (lecun-normal kernels, zero biases) or ``"torch"`` (torch's
    ``nn.Linear``: kernel and bias uniform on +-1/sqrt(n_in)). Only initialisation reads
    these."""

    rho_init: float = -5.0
    rho_init_std: float = 0.0
    mean_init: float | None = None
    dense_init: str = "flax"

    def __post_init__(self) -> None:
        super().__post_init__()
        validation.real("rho_init", self.rho_init)
        validation.non_negative("rho_init_std", self.rho_init_std)
        validation.choice("dense_init", self.dense_init, DENSE_INITS)
        if self.mean_init is not None:
            validation.positive("mean_init", self.mean_init)

    @property
    def architecture(self) -> Architecture:
        return Architecture(**{f.name: getattr(self, f.name) for f in fields(Architecture)})


def prior_of(architecture: Architecture) -> Prior:
    """The weight prior named in ``architecture``."""
    return GaussianPrior(0.1) if architecture.prior == "gaussian" else ScaleMixturePrior()


@partial(jax.jit, static_argnums=0)
def _init_mlp(model: "MLP", key: jax.Array) -> dict:
    dummy = jnp.zeros((1, model.in_features))
    return {"params": model.init({"params": key, "sample": key}, dummy)["params"]}


class MLP(nn.Module):
    """The Flax definition of a network's parameters: ``in_features`` -> hidden layers (SGB
    or dense) -> ``out`` units. Layers are named ``hidden_0``, ``hidden_1``, ... and ``out``."""

    config: NetworkConfig
    out: int
    in_features: int

    @nn.compact
    def __call__(self, x: jnp.ndarray) -> jnp.ndarray:
        cfg = self.config
        _check_input(x, self.in_features)
        network = Network(cfg.architecture, self.in_features, self.out)
        for i, (name, width) in enumerate(zip(network.names, network.widths[1:], strict=True)):
            if name in network.sgb_shapes:
                n_in = network.widths[i]
                k_in = None if i == 0 and not cfg.typed_inputs else cfg.cell_types
                x = SGBDense(
                    width,
                    in_types=None if k_in is None else min(k_in, n_in),
                    out_types=min(cfg.cell_types, width),
                    prior=prior_of(cfg),
                    mean_init_std=1.0 if cfg.mean_init is None else cfg.mean_init * n_in**0.5,
                    rho_init=cfg.rho_init,
                    rho_init_std=cfg.rho_init_std,
                    in_features=n_in,
                    bayesian_bias=cfg.bayesian_biases,
                    index=list(network.sgb_shapes).index(name),
                    name=name,
                )(x)
            else:
                x = _dense(width, n_in=network.widths[i], init=cfg.dense_init, name=name)(x)
            if i < len(cfg.hidden):
                x = nn.swish(x)
        return x


def _dense(width: int, n_in: int, init: str, name: str) -> nn.Dense:
    """A deterministic layer of ``n_in`` inputs, started as ``init`` (``NetworkConfig``)."""
    if init == "flax":
        return nn.Dense(width, name=name)
    bound = n_in**-0.5

    def uniform(key, shape, dtype=jnp.float32):
        return jax.random.uniform(key, shape, dtype, -bound, bound)

    return nn.Dense(width, kernel_init=uniform, bias_init=uniform, name=name)


@dataclass(frozen=True)
class Network:
    """One network of the agent, ``in_features`` -> ``out``, as pure functions of its
    ``{"params": ...}``."""

    architecture: Architecture
    in_features: int
    out: int

    @cached_property
    def names(self) -> list[str]:
        """Its layers' names, input to output."""
        return [f"hidden_{i}" for i in range(len(self.architecture.hidden))] + ["out"]

    @cached_property
    def widths(self) -> tuple[int, ...]:
        return (self.in_features, *self.architecture.hidden, self.out)

    @cached_property
    def sgb_shapes(self) -> dict[str, tuple[int, int]]:
        """The drawn parameters by genome path and their shapes, input to output: each SGB
        layer's kernel (n_in, n_out) and, with ``bayesian_biases``, its biases (1, n_out)
        at the layer's path + ``/bias``."""
        if not self.architecture.sgb:
            return {}
        shapes = {}
        for i, name in enumerate(self.names):
            if name == "out" and not self.architecture.sgb_output:
                continue
            shapes[name] = (self.widths[i], self.widths[i + 1])
            if self.architecture.bayesian_biases:
                shapes[f"{name}/bias"] = (1, self.widths[i + 1])
        return shapes

    def init(self, key: jax.Array, init: NetworkConfig) -> dict:
        """Initial ``{"params": ...}`` of this network with ``init``'s starting values."""
        validation.instance("init", init, NetworkConfig)
        if init.architecture != self.architecture:
            raise ValueError(f"{init} is not a config of {self.architecture}")
        return _init_mlp(MLP(init, self.out, self.in_features), key)

    def draw(self, key: jax.Array) -> genome.Noise | None:
        """An individual's noise (``sgb.genome.draw_noise``); ``None`` for vanilla."""
        return genome.draw_noise(key, self.sgb_shapes) if self.architecture.sgb else None

    def layers(self, params: dict, noise: genome.Noise | None) -> Layers:
        """The phenotype of ``noise`` (a leading axis N on every layer: N individuals)
        under the genome in ``params``: each SGB kernel ``sgb.genome.kernels``, shape
        (N, n_in, n_out), differentiable in ``params``; the other kernels and the biases
        shared. ``noise=None``: the mean network (or the vanilla one), every kernel shared."""
        p = params["params"]
        developed = self.genome(params)
        if noise is None:
            sgb = genome.mean_kernels(developed, self.sgb_shapes)
        else:
            sgb = genome.kernels(developed, noise)
        return [
            (
                sgb[name] if name in sgb else p[name]["kernel"],
                sgb[f"{name}/bias"][..., 0, :] if f"{name}/bias" in sgb else p[name]["bias"],
            )
            for name in self.names
        ]

    def genome(self, params: dict) -> genome.Genome:
        """The type tables its layers read from ``params``: as stored, or with
        ``aliased_pairs`` each kernel's as the authors' layers read it
        (``sgb.genome.aliased_table``; the biases' genomes are per neuron, never aliased)."""
        stored = genome.of_params(params)
        if not self.architecture.aliased_pairs:
            return stored
        return {
            name: layer if name.endswith("/bias") else genome.aliased(layer)
            for name, layer in stored.items()
        }

    def kl(self, params: dict, key: jax.Array) -> jnp.ndarray:
        """KL of the network's genome to its prior, synapses counted (nats); 0 for vanilla."""
        prior = prior_of(self.architecture)
        return genome.kl(self.genome(params), self.sgb_shapes, prior, key)


class Params(NamedTuple):
    actor: dict
    critic: dict


class Individual(NamedTuple):
    """An individual's noise, of its actor and its critic; ``None`` for vanilla agents."""

    actor: genome.Noise | None
    critic: genome.Noise | None


@dataclass(frozen=True)
class Agent:
    """The actor (observation -> 2 x action: Gaussian loc and raw scale) and the critic
    (observation -> value) of one architecture, for observations of ``obs_size`` entries."""

    architecture: Architecture
    obs_size: int
    action_size: int

    @cached_property
    def actor(self) -> Network:
        return Network(self.architecture, self.obs_size, 2 * self.action_size)

    @cached_property
    def critic(self) -> Network:
        return Network(self.architecture, self.obs_size, 1)

    def init(self, key_actor: jax.Array, key_critic: jax.Array, init: NetworkConfig) -> Params:
        return Params(self.actor.init(key_actor, init), self.critic.init(key_critic, init))

    def birth(self, key: jax.Array) -> Individual:
        """The individual born from ``key``: its actor's noise from ``key``, its critic's
        from ``fold_in(key, 1)``. vmap it over keys for many."""
        return Individual(self.actor.draw(key), self.critic.draw(jax.random.fold_in(key, 1)))

    def policy(
        self, actor: Layers, normalizer: Normalizer, obs: jnp.ndarray
    ) -> tuple[jnp.ndarray, jnp.ndarray]:
        """The action distribution of the phenotypes ``actor`` at raw observations ``obs``
        (..., obs): the loc and scale (..., action) of u, the action being tanh(u)."""
        scaled = normalize(normalizer, obs, self.architecture.normalizer)
        return action_distribution(forward(actor, scaled))

    def value(self, critic: Layers, normalizer: Normalizer, obs: jnp.ndarray) -> jnp.ndarray:
        """The critic phenotypes' values at raw observations ``obs`` (...,)."""
        return forward(critic, normalize(normalizer, obs, self.architecture.normalizer))[..., 0]


def make_agent(architecture: Architecture, obs_size: int, action_size: int) -> Agent:
    """The agent of ``architecture`` for an environment's observation and action sizes."""
    validation.instance("architecture", architecture, Architecture)
    if isinstance(architecture, NetworkConfig):
        architecture = architecture.architecture
    return Agent(
        architecture,
        validation.integer("obs_size", obs_size),
        validation.integer("action_size", action_size),
    )


def forward(layers: Layers, x: jnp.ndarray) -> jnp.ndarray:
    """Run phenotypes on inputs ``x`` (..., n_in) -> (..., n_out).

    A kernel (n_in, n_out) is shared by every input; a kernel (N, n_in, n_out) holds one
    individual per row of ``x`` (N, ..., n_in), and so do biases (N, n_out). A shared
    kernel multiplies the inputs flattened to rows (rows, n_in): its gradient is then a
    plain 2-D product, where on 3-D inputs XLA on CPU contracts two axes at a third of the
    core's rate; the arithmetic is the same, bit for bit (tested).
    """
    for i, (kernel, bias) in enumerate(layers):
        if kernel.ndim == 2:
            rows = x.reshape(-1, x.shape[-1])
            x = (rows @ kernel).reshape(x.shape[:-1] + kernel.shape[1:]) + bias
        else:
            if bias.ndim == 2:  # the individuals' own biases, broadcast over the inner axes
                bias = bias.reshape(bias.shape[:1] + (1,) * (x.ndim - 2) + bias.shape[1:])
            x = individual_matmul(x, kernel) + bias
        if i < len(layers) - 1:
            x = nn.swish(x)
    return x


def action_distribution(logits: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Split actor outputs (..., 2 * act) into Gaussian loc and scale (softplus + 1e-3).

    Not a spread: ``jax.nn.softplus``, exact over the whole float32 range (the spreads'
    ``sgb.genome.softplus`` saturates above 88)."""
    loc, raw = jnp.split(logits, 2, axis=-1)
    return loc, jax.nn.softplus(raw) + MIN_STD


def tanh_gaussian_log_prob(u: jnp.ndarray, loc: jnp.ndarray, scale: jnp.ndarray) -> jnp.ndarray:
    """log-density of the action tanh(u) where u ~ N(loc, scale^2), summed over the last axis."""
    log_normal = -0.5 * ((u - loc) / scale) ** 2 - jnp.log(scale) - 0.5 * jnp.log(2 * jnp.pi)
    return jnp.sum(log_normal - _log_det_tanh(u), axis=-1)


def tanh_gaussian_entropy(scale: jnp.ndarray, u: jnp.ndarray) -> jnp.ndarray:
    """One-draw estimate of the entropy of the action tanh(u), u ~ N(loc, scale^2), at a draw
    ``u``, summed over the last axis (nats): the Gaussian's entropy plus log|d tanh(u)/du|.

    The second term penalises saturating the tanh, so the entropy bonus cannot be bought
    by widening the Gaussian beyond the action range.
    """
    gaussian = 0.5 + 0.5 * jnp.log(2 * jnp.pi) + jnp.log(scale)
    return jnp.sum(gaussian + _log_det_tanh(u), axis=-1)


def _log_det_tanh(u: jnp.ndarray) -> jnp.ndarray:
    """log|d tanh(u)/du| = log(1 - tanh(u)^2), elementwise, computed stably."""
    return 2.0 * (jnp.log(2.0) - u - jax.nn.softplus(-2.0 * u))
