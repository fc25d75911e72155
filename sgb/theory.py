"""The Jensen gap of sampled networks (Theorems A.1/A.3) and the (mu, sigma) dynamics (A.2/A.4).

A population draws weights ``w = mu + sigma * eps`` with ``eps ~ N(0, I)``. The
Jensen gap is ``Delta L = E[L(mu + sigma * eps)] - L(mu)``: positive when the
mean network beats the average individual. To second order it is
``1/2 * sum_i lambda_i E[rho_i^2] = 1/2 * trace(H diag(sigma^2)) = 1/2 * sum_s H_ss sigma_s^2``
with ``H`` the Hessian of ``L`` at ``mu``.

Everything here takes a loss ``loss_fn(w) -> scalar`` of a pytree of weights
``w``; ``mu`` and ``sigma`` are pytrees of the same structure.
"""

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax.flatten_util import ravel_pytree

from sgb.celltypes import expand_table
from sgb.elbo import cross_entropy
from sgb.layers import SGBMLP
from sgb.population import individual_kernels

Pytree = Any
LossFn = Callable[[Pytree], jnp.ndarray]


def _check_positive(name: str, value: int) -> None:
    if int(value) != value or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")


def _check_same_structure(mu: Pytree, sigma: Pytree) -> None:
    if jax.tree_util.tree_structure(mu) != jax.tree_util.tree_structure(sigma):
        raise ValueError("sigma must have the same pytree structure as mu")
    for m, s in zip(jax.tree_util.tree_leaves(mu), jax.tree_util.tree_leaves(sigma), strict=True):
        if jnp.shape(m) != jnp.shape(s):
            raise ValueError(
                f"sigma leaf of shape {jnp.shape(s)} does not match mu's {jnp.shape(m)}"
            )


def _perturb(mu: Pytree, sigma: Pytree, eps: Pytree) -> Pytree:
    return jax.tree_util.tree_map(lambda m, s, e: m + s * e, mu, sigma, eps)


def _normal_like(key: jax.Array, tree: Pytree) -> Pytree:
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    keys = jax.random.split(key, len(leaves))
    noise = [
        jax.random.normal(k, jnp.shape(x), jnp.result_type(x))
        for k, x in zip(keys, leaves, strict=True)
    ]
    return jax.tree_util.tree_unflatten(treedef, noise)


class Estimate(NamedTuple):
    """A Monte Carlo estimate and its standard error (same units)."""

    value: jnp.ndarray
    stderr: jnp.ndarray


class JensenGap(NamedTuple):
    """Measured gap and the loss of the mean network; ``gap = mean_loss - mean_network_loss``."""

    gap: jnp.ndarray
    stderr: jnp.ndarray
    mean_loss: jnp.ndarray
    mean_network_loss: jnp.ndarray


def jensen_gap(
    loss_fn: LossFn,
    mu: Pytree,
    sigma: Pytree,
    key: jax.Array,
    num_samples: int = 1000,
    antithetic: bool = True,
) -> JensenGap:
    """Monte Carlo Delta L = E[L(mu + sigma*eps)] - L(mu), with its standard error.

    ``num_samples`` noise draws (with ``antithetic=True``, ``num_samples // 2``
    pairs (eps, -eps) whose first-order terms cancel, so the estimate stays
    unbiased and its standard error shrinks for small sigma). The draws are
    evaluated one after the other (``lax.map``) to bound memory.
    """
    _check_positive("num_samples", num_samples)
    _check_same_structure(mu, sigma)
    if antithetic and num_samples < 4:
        raise ValueError(f"num_samples must be >= 4 with antithetic pairs, got {num_samples}")
    base = loss_fn(mu)
    n_draws = num_samples // 2 if antithetic else num_samples

    def one_draw(k):
        eps = _normal_like(k, mu)
        value = loss_fn(_perturb(mu, sigma, eps))
        if antithetic:
            minus = jax.tree_util.tree_map(lambda e: -e, eps)
            value = 0.5 * (value + loss_fn(_perturb(mu, sigma, minus)))
        return value

    values = jax.lax.map(one_draw, jax.random.split(key, n_draws))
    mean = values.mean()
    stderr = values.std(ddof=1) / jnp.sqrt(n_draws)
    return JensenGap(mean - base, stderr, mean, base)


def hvp(loss_fn: LossFn, w: Pytree, v: Pytree) -> Pytree:
    """Hessian-vector product H(w) v (forward over reverse), same structure as ``w``."""
    return jax.jvp(jax.grad(loss_fn), (w,), (v,))[1]


class EigenPrediction(NamedTuple):
    """Second-order gap from the dense Hessian: ``gap = 1/2 sum_i eigenvalues_i rho2_i``.

    ``eigenvalues`` (P,) ascending; ``rho2`` (P,) = E[rho_i^2], the noise
    variance along each eigenvector.
    """

    gap: jnp.ndarray
    eigenvalues: jnp.ndarray
    rho2: jnp.ndarray


def second_order_eigen(loss_fn: LossFn, mu: Pytree, sigma: Pytree) -> EigenPrediction:
    """Theorem A.1's prediction 1/2 sum_i lambda_i E[rho_i^2] from ``jax.hessian`` + ``eigh``.

    Builds the dense (P, P) Hessian at ``mu``: for small models only.
    E[rho_i^2] = sum_j sigma_j^2 nu_ij^2 for the unit eigenvector nu_i.
    """
    _check_same_structure(mu, sigma)
    mu_flat, unravel = ravel_pytree(mu)
    sigma_flat, _ = ravel_pytree(sigma)
    hessian = jax.hessian(lambda w: loss_fn(unravel(w)))(mu_flat)
    eigenvalues, vectors = jnp.linalg.eigh(0.5 * (hessian + hessian.T))
    rho2 = (sigma_flat[:, None] ** 2 * vectors**2).sum(axis=0)
    return EigenPrediction(0.5 * jnp.sum(eigenvalues * rho2), eigenvalues, rho2)


def hessian_diagonal(loss_fn: LossFn, w: Pytree, chunk_size: int = 256) -> Pytree:
    """Exact diagonal of the Hessian at ``w``, one HVP per coordinate, ``chunk_size`` at a time.

    Same structure as ``w``. Costs P Hessian-vector products but never holds
    the dense Hessian.
    """
    _check_positive("chunk_size", chunk_size)
    w_flat, unravel = ravel_pytree(w)
    size = w_flat.size
    n_chunks = -(-size // chunk_size)
    flat_loss = lambda v: loss_fn(unravel(v))  # noqa: E731

    def chunk(start):
        index = start + jnp.arange(chunk_size)
        basis = jax.nn.one_hot(index, size, dtype=w_flat.dtype)
        products = jax.vmap(lambda e: hvp(flat_loss, w_flat, e))(basis)
        return jnp.take_along_axis(products, jnp.minimum(index, size - 1)[:, None], axis=1)[:, 0]

    diagonal = jax.lax.map(chunk, jnp.arange(n_chunks) * chunk_size).reshape(-1)[:size]
    return unravel(diagonal)


def second_order_trace(
    loss_fn: LossFn,
    mu: Pytree,
    sigma: Pytree,
    key: jax.Array | None = None,
    num_probes: int = 0,
    chunk_size: int = 256,
) -> Estimate:
    """1/2 trace(H diag(sigma^2)) with Hessian-vector products, no dense Hessian.

    ``num_probes=0``: exact, 1/2 sum_s sigma_s^2 H_ss from ``hessian_diagonal``
    (stderr 0). ``num_probes > 0``: Hutchinson's estimate 1/2 E_z[(sigma z)^T H
    (sigma z)] with Rademacher ``z`` (unbiased; stderr from the probes' spread,
    which comes only from H's off-diagonal entries).
    """
    _check_same_structure(mu, sigma)
    sigma_flat, unravel = ravel_pytree(sigma)
    if num_probes == 0:
        diagonal, _ = ravel_pytree(hessian_diagonal(loss_fn, mu, chunk_size))
        return Estimate(0.5 * jnp.sum(sigma_flat**2 * diagonal), jnp.zeros(()))
    _check_positive("num_probes", num_probes)
    if num_probes < 2:
        raise ValueError(f"num_probes must be 0 (exact) or >= 2, got {num_probes}")
    if key is None:
        raise ValueError("key is required for Hutchinson probes (num_probes > 0)")

    def probe(k):
        z = jax.random.rademacher(k, sigma_flat.shape, sigma_flat.dtype)
        v = sigma_flat * z
        hv, _ = ravel_pytree(hvp(loss_fn, mu, unravel(v)))
        return 0.5 * jnp.dot(v, hv)

    values = jax.lax.map(probe, jax.random.split(key, num_probes))
    return Estimate(values.mean(), values.std(ddof=1) / jnp.sqrt(num_probes))


def reparameterized_loss(
    loss_fn: LossFn, mu: Pytree, sigma: Pytree, eps: Pytree, prior_weight: float = 0.0
) -> jnp.ndarray:
    """One draw of the paper's eq. (14): L(w) + prior_weight/2 * |w|^2 at w = mu + sigma*eps."""
    w = _perturb(mu, sigma, eps)
    penalty = sum(jnp.sum(x**2) for x in jax.tree_util.tree_leaves(w))
    return loss_fn(w) + 0.5 * prior_weight * penalty


class StepComparison(NamedTuple):
    """One gradient-descent step on (mu, sigma), measured and predicted (flat vectors, (P,)).

    ``dmu``/``dsigma``: the step averaged over noise; ``*_stderr`` its Monte
    Carlo standard error per coordinate. ``dmu_theorem`` = -lr (grad L(mu) +
    prior_weight mu) (Theorem A.2). ``dsigma_theorem`` = -lr H sigma as the
    paper states it; ``dsigma_second_order`` = -lr (diag(H) + prior_weight) sigma,
    the exact second-order expectation (see the chapter).
    """

    dmu: jnp.ndarray
    dmu_stderr: jnp.ndarray
    dsigma: jnp.ndarray
    dsigma_stderr: jnp.ndarray
    dmu_theorem: jnp.ndarray
    dsigma_theorem: jnp.ndarray
    dsigma_second_order: jnp.ndarray


def gradient_step(
    loss_fn: LossFn,
    mu: Pytree,
    sigma: Pytree,
    key: jax.Array,
    learning_rate: float,
    num_samples: int = 1000,
    prior_weight: float = 0.0,
) -> StepComparison:
    """Compare one step of gradient descent on the reparameterized loss with Theorem A.2.

    The step is ``-learning_rate`` times the gradient of eq. (14) in (mu,
    sigma), averaged over ``num_samples`` noise draws taken in antithetic pairs.
    Uses the dense Hessian for the predictions: for small models.
    """
    _check_positive("num_samples", num_samples)
    if num_samples < 4:
        raise ValueError(f"num_samples must be >= 4 (antithetic pairs), got {num_samples}")
    if learning_rate <= 0:
        raise ValueError(f"learning_rate must be positive, got {learning_rate}")
    _check_same_structure(mu, sigma)
    mu_flat, unravel = ravel_pytree(mu)
    sigma_flat, _ = ravel_pytree(sigma)
    flat_loss = lambda w: loss_fn(unravel(w))  # noqa: E731
    grad_fn = jax.grad(
        lambda m, s, e: reparameterized_loss(flat_loss, m, s, e, prior_weight), argnums=(0, 1)
    )

    def pair(k):
        eps = jax.random.normal(k, mu_flat.shape, mu_flat.dtype)
        gm_plus, gs_plus = grad_fn(mu_flat, sigma_flat, eps)
        gm_minus, gs_minus = grad_fn(mu_flat, sigma_flat, -eps)
        return 0.5 * (gm_plus + gm_minus), 0.5 * (gs_plus + gs_minus)

    n_pairs = num_samples // 2
    grad_mu, grad_sigma = jax.lax.map(pair, jax.random.split(key, n_pairs))
    scale = -learning_rate

    def mean_and_se(g):
        return scale * g.mean(axis=0), learning_rate * g.std(axis=0, ddof=1) / jnp.sqrt(n_pairs)

    dmu, dmu_se = mean_and_se(grad_mu)
    dsigma, dsigma_se = mean_and_se(grad_sigma)
    hessian = jax.hessian(flat_loss)(mu_flat)
    return StepComparison(
        dmu=dmu,
        dmu_stderr=dmu_se,
        dsigma=dsigma,
        dsigma_stderr=dsigma_se,
        dmu_theorem=scale * (jax.grad(flat_loss)(mu_flat) + prior_weight * mu_flat),
        dsigma_theorem=scale * hessian @ sigma_flat,
        dsigma_second_order=scale * (jnp.diag(hessian) + prior_weight) * sigma_flat,
    )


# --- the 1-D toy losses of the paper's Figure 6 ---------------------------------------------


def convex_loss(w: jnp.ndarray) -> jnp.ndarray:
    """L(w) = w^2 / 2: curvature 1 everywhere."""
    return 0.5 * w**2


def concave_loss(w: jnp.ndarray) -> jnp.ndarray:
    """L(w) = -log cosh(w): curvature -1/cosh(w)^2 < 0 everywhere, bounded slope."""
    return -(jnp.logaddexp(w, -w) - jnp.log(2.0))


def nonconvex_loss(w: jnp.ndarray) -> jnp.ndarray:
    """Double well L(w) = (w^2 - 1)^2 / 4: concave for |w| < 1/sqrt(3), convex outside.

    Its exact gap is Delta L = sigma^2 (3 mu^2 - 1) / 2 + 3 sigma^4 / 4; the
    second-order prediction misses the sigma^4 term.
    """
    return 0.25 * (w**2 - 1.0) ** 2


TOY_LOSSES: dict[str, Callable[[jnp.ndarray], jnp.ndarray]] = {
    "convex": convex_loss,
    "concave": concave_loss,
    "nonconvex": nonconvex_loss,
}


def toy_loss(name: str) -> Callable[[jnp.ndarray], jnp.ndarray]:
    """One of the three 1-D toy losses by name."""
    if name not in TOY_LOSSES:
        raise ValueError(f"unknown toy loss {name!r}; choose one of {sorted(TOY_LOSSES)}")
    return TOY_LOSSES[name]


class Trajectory(NamedTuple):
    """Gradient descent on (mu, sigma) of a 1-D loss; every field has shape (steps + 1,).

    ``gap``/``gap_stderr``: Monte Carlo Delta L at each step; ``prediction``:
    the second-order 1/2 L''(mu) sigma^2.
    """

    mu: jnp.ndarray
    sigma: jnp.ndarray
    gap: jnp.ndarray
    gap_stderr: jnp.ndarray
    prediction: jnp.ndarray


def train_toy(
    loss: Callable[[jnp.ndarray], jnp.ndarray],
    mu0: float,
    sigma0: float,
    key: jax.Array,
    steps: int = 100,
    learning_rate: float = 0.1,
    num_samples: int = 8,
    gap_samples: int = 2000,
    prior_weight: float = 0.0,
) -> Trajectory:
    """Train a 1-D (mu, sigma) by gradient descent on eq. (14) and record Delta L.

    Each step uses ``num_samples`` fresh noise draws for the gradient; Delta L
    is measured with ``gap_samples`` antithetic draws. ``sigma`` is the raw
    scale (it may change sign; only |sigma| matters, and |sigma| is recorded).
    Jit-able and vmappable over ``mu0``, ``sigma0`` and ``key``.
    """
    for name, value in (("steps", steps), ("num_samples", num_samples)):
        _check_positive(name, value)
    if learning_rate <= 0:
        raise ValueError(f"learning_rate must be positive, got {learning_rate}")

    def objective(params, eps):
        m, s = params
        return jnp.mean(reparameterized_loss(loss, m, s, eps, prior_weight))

    grad_fn = jax.grad(objective)

    def measure(params, k):
        m, s = params
        gap = jensen_gap(loss, m, s, k, gap_samples)
        return gap.gap, gap.stderr, 0.5 * jax.grad(jax.grad(loss))(m) * s**2

    def step(params, k):
        train_key, gap_key = jax.random.split(k)
        eps = jax.random.normal(train_key, (num_samples,))
        g = grad_fn(params, eps)
        new = tuple(p - learning_rate * gp for p, gp in zip(params, g, strict=True))
        return new, (*params, *measure(params, gap_key))

    params = (jnp.asarray(mu0, jnp.float32), jnp.asarray(sigma0, jnp.float32))
    keys = jax.random.split(key, steps + 1)
    final, (mus, sigmas, gaps, ses, preds) = jax.lax.scan(step, params, keys[:-1])
    last = measure(final, keys[-1])
    stack = lambda seq, x: jnp.concatenate([seq, jnp.asarray(x)[None]])  # noqa: E731
    return Trajectory(
        mu=stack(mus, final[0]),
        sigma=jnp.abs(stack(sigmas, final[1])),
        gap=stack(gaps, last[0]),
        gap_stderr=stack(ses, last[1]),
        prediction=stack(preds, last[2]),
    )


# --- the gap of a trained SGB network, per synapse ------------------------------------------


class SynapseView(NamedTuple):
    """An SGB MLP seen as a function of its expanded weights.

    ``mean``/``sigma``: per layer, the full (n_in, n_out) mean and spread of
    every synapse (the genome tables expanded); ``forward(weights, x)`` the
    network's logits with those kernels and the trained biases.
    """

    mean: dict
    sigma: dict
    forward: Callable[[dict, jnp.ndarray], jnp.ndarray]


def synapse_view(model: SGBMLP, params: Pytree, x: jnp.ndarray) -> SynapseView:
    """Expand an SGB MLP's genome to per-synapse means and spreads, and a forward pass.

    ``x``: any input batch (n, n_in), used only for the kernel shapes. The
    forward pass is the same ``SGBMLP`` with one type per neuron (so its genome
    table *is* the kernel) applied as a mean network: biases stay as trained,
    kernels are the argument.
    """
    layers = params["params"]
    mean = {
        name: kernels["genome"]["kernel"]
        for name, kernels in individual_kernels(model, {"params": layers}, x[:1], None).items()
    }
    sigma = {
        name: expand_table(jax.nn.softplus(layers[name]["genome"]["rho"]), kernel.shape)
        for name, kernel in mean.items()
    }
    full_model = model.clone(cell_types=(None,) * len(model.cell_types))

    def forward(weights: dict, inputs: jnp.ndarray) -> jnp.ndarray:
        full = {
            name: {
                "genome": {"mu": weights[name], "rho": jnp.zeros_like(weights[name])},
                "bias": layer["bias"],
            }
            for name, layer in layers.items()
        }
        return full_model.apply({"params": full}, inputs, mean_network=True)

    return SynapseView(mean, sigma, forward)


def error_rate(logits: jnp.ndarray, labels: jnp.ndarray) -> jnp.ndarray:
    """Fraction of misclassified examples."""
    return jnp.mean(jnp.argmax(logits, -1) != labels)


NETWORK_METRICS = {"cross_entropy": cross_entropy, "error_rate": error_rate}


def network_loss(view: SynapseView, x: jnp.ndarray, y: jnp.ndarray, metric: str) -> LossFn:
    """The loss ``weights -> metric(forward(weights, x), y)`` of a synapse view on data."""
    if metric not in NETWORK_METRICS:
        raise ValueError(f"unknown metric {metric!r}; choose one of {sorted(NETWORK_METRICS)}")
    fn = NETWORK_METRICS[metric]
    return lambda weights: fn(view.forward(weights, x), y)
