"""The Jensen gap of sampled networks (Theorems A.1/A.3) and the (mu, sigma) dynamics (A.2/A.4).

A population draws weights ``w = mu + sigma * eps`` with ``eps ~ N(0, I)``. The
Jensen gap is ``Delta L = E[L(mu + sigma * eps)] - L(mu)``: positive when the
mean network beats the average individual. To second order it is
``1/2 * sum_i lambda_i E[rho_i^2] = 1/2 * trace(H diag(sigma^2)) = 1/2 * sum_s H_ss sigma_s^2``
with ``H`` the Hessian of ``L`` at ``mu``.

The (mu, sigma) step comes in two forms: the paper's (its eq. (14): data term
plus a weight-decay prior, no entropy; ``gradient_step``, ``train_toy``) and the
one of the ELBO the book trains (data term plus ``kl_weight`` times the closed-form
Gaussian KL, whose entropy part keeps sigma away from zero; ``elbo_sigma_step``,
``elbo_fixed_point``, ``elbo_gradient_step``, ``train_elbo_toy``,
``genome_fixed_point``).

Everything here takes a loss ``loss_fn(w) -> scalar`` of a pytree of weights
``w``; ``mu`` and ``sigma`` are pytrees of the same structure.
"""

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax.flatten_util import ravel_pytree

from sgb import genome
from sgb.celltypes import block_counts, expand_table, sum_blocks
from sgb.divergence import check_trajectory
from sgb.elbo import cross_entropy
from sgb.genome import LayerGenome
from sgb.individuals import individual_kernels
from sgb.layers import SGBMLP
from sgb.priors import GaussianPrior

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


def population_hessian_diagonal(
    loss_fn: LossFn,
    mu: Pytree,
    sigma: Pytree,
    key: jax.Array,
    num_individuals: int,
    chunk_size: int = 256,
) -> Pytree:
    """E_eps[diag H(mu + sigma eps)]: the Hessian diagonal averaged over sampled individuals.

    Same structure as ``mu``; ``num_individuals`` draws, each an exact ``hessian_diagonal``
    (so P Hessian-vector products per draw). For a smooth loss, Gaussian integration by
    parts makes d/d sigma_s E[L(mu + sigma eps)] = sigma_s E[H_ss(mu + sigma eps)] exactly,
    so this, not the diagonal at ``mu``, is the curvature the spreads feel.
    """
    _check_positive("num_individuals", num_individuals)
    _check_same_structure(mu, sigma)

    def one(k):
        return hessian_diagonal(loss_fn, _perturb(mu, sigma, _normal_like(k, mu)), chunk_size)

    draws = jax.lax.map(one, jax.random.split(key, num_individuals))
    return jax.tree_util.tree_map(lambda d: d.mean(axis=0), draws)


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


def _check_step_arguments(learning_rate: float, num_samples: int) -> None:
    _check_positive("num_samples", num_samples)
    if num_samples < 4:
        raise ValueError(f"num_samples must be >= 4 (antithetic pairs), got {num_samples}")
    if learning_rate <= 0:
        raise ValueError(f"learning_rate must be positive, got {learning_rate}")


def _step_mean_and_se(grads: jnp.ndarray, learning_rate: float) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Gradients (n_pairs, P) -> the step -lr * mean and its standard error, each (P,)."""
    n_pairs = grads.shape[0]
    return (
        -learning_rate * grads.mean(axis=0),
        learning_rate * grads.std(axis=0, ddof=1) / jnp.sqrt(n_pairs),
    )


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
    _check_step_arguments(learning_rate, num_samples)
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
    dmu, dmu_se = _step_mean_and_se(grad_mu, learning_rate)
    dsigma, dsigma_se = _step_mean_and_se(grad_sigma, learning_rate)
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
    Jit-able and vmappable over ``mu0``, ``sigma0`` and ``key``. Called outside ``jit``, it
    runs under the divergence guard: a trajectory that is not finite, or whose (mu, sigma)
    grow beyond ``sgb.divergence.BLOWUP_FACTOR`` times their start (at least 1), raises
    ``sgb.divergence.TrainingDiverged``; a caller that jits or vmaps it checks the
    trajectories it gets with ``sgb.divergence.check_trajectory`` (``guard_toy``).
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
    trajectory = Trajectory(
        mu=stack(mus, final[0]),
        sigma=jnp.abs(stack(sigmas, final[1])),
        gap=stack(gaps, last[0]),
        gap_stderr=stack(ses, last[1]),
        prediction=stack(preds, last[2]),
    )
    if not isinstance(trajectory.mu, jax.core.Tracer):
        guard_toy(trajectory)
    return trajectory


def guard_toy(trajectory: Trajectory) -> Trajectory:
    """``trajectory`` (or a batch of them, steps on the last axis) if training did not
    diverge; else ``sgb.divergence.TrainingDiverged`` naming the first step that did."""
    check_trajectory(trajectory._asdict(), trained=("mu", "sigma"), what="the toy's")
    return trajectory


# --- the sigma step of the ELBO the book trains ---------------------------------------------
#
# Per weight q = N(mu, sigma^2), prior N(0, sigma_p^2), lambda = 1 / sigma_p^2, KL weight c:
#   F(mu, sigma) = E[L(mu + sigma eps)] + c KL,
#   KL = log(sigma_p / sigma) + (sigma^2 + mu^2) / (2 sigma_p^2) - 1/2,
#   dF/dsigma ~ H sigma + c (lambda sigma - 1/sigma)   (second order, H = diag of the Hessian).
# The -c/sigma comes from log(1/sigma), minus the entropy of q: the part of the KL that the
# paper's eq. (14) leaves out.

PARAMETERISATIONS = ("sigma", "softplus")


def _check_scalar(name: str, value: Any, positive: bool) -> None:
    """Check a concrete Python number; traced values (under jit or vmap) pass unchecked."""
    if isinstance(value, int | float) and (value <= 0 if positive else value < 0):
        bound = "positive" if positive else "non-negative"
        raise ValueError(f"{name} must be {bound}, got {value!r}")


def _check_parameterisation(parameterisation: str) -> None:
    if parameterisation not in PARAMETERISATIONS:
        raise ValueError(
            f"unknown parameterisation {parameterisation!r}; choose one of {PARAMETERISATIONS}"
        )


def softplus_inverse(sigma: jnp.ndarray) -> jnp.ndarray:
    """rho with softplus(rho) = sigma (sigma > 0): log(exp(sigma) - 1), elementwise."""
    sigma = jnp.asarray(sigma)
    return sigma + jnp.log(-jnp.expm1(-sigma))


class SigmaStep(NamedTuple):
    """The expected gradient-descent step on the spread of the ELBO, term by term.

    Every field has the broadcast shape of ``sigma`` and ``curvature``, in the units of
    the trained parameter (sigma itself, or rho for the softplus parameterisation);
    ``total = data + prior + entropy``.

    ``data = -lr H sigma`` (the data term's curvature; the paper's whole step),
    ``prior = -lr c sigma / sigma_p^2`` (the prior's pull towards 0) and
    ``entropy = +lr c / sigma`` (the entropy of q, which the paper's eq. (14) drops; it
    pushes sigma up and diverges as sigma -> 0). With ``parameterisation="softplus"``
    each is multiplied by d sigma / d rho = sigmoid(rho) = 1 - exp(-sigma).
    """

    data: jnp.ndarray
    prior: jnp.ndarray
    entropy: jnp.ndarray
    total: jnp.ndarray


def elbo_sigma_step(
    sigma: jnp.ndarray,
    curvature: jnp.ndarray,
    kl_weight: float,
    prior_sigma: float,
    learning_rate: float = 1.0,
    parameterisation: str = "sigma",
) -> SigmaStep:
    """Expected step of sigma under gradient descent on the ELBO the book trains.

    The loss per weight is F = E_eps[L(mu + sigma eps)] + c KL(N(mu, sigma^2) || N(0,
    sigma_p^2)), KL = log(sigma_p / sigma) + (sigma^2 + mu^2) / (2 sigma_p^2) - 1/2. To
    second order E[L(mu + sigma eps)] = L(mu) + 1/2 sigma^2 H for the Hessian's diagonal
    entry H, so dF/dsigma = H sigma + c (sigma / sigma_p^2 - 1 / sigma) and

        Delta sigma = -lr [(H + c lambda) sigma - c / sigma],   lambda = 1 / sigma_p^2.

    The book trains rho with sigma = softplus(rho): then Delta rho = sigmoid(rho) times
    that (``parameterisation="softplus"``; to first order in lr, Delta sigma =
    sigmoid(rho)^2 times it). The factor is positive, so the step's zero (the fixed
    point, ``elbo_fixed_point``) is the same for both; only the speed differs.

    ``sigma`` (> 0) and ``curvature`` (H, loss units per weight^2): arrays of any
    broadcastable shape; ``kl_weight`` c >= 0: the KL's weight relative to the loss
    (the book's SGB: 1 / n_train, with L the mean loss per example); ``prior_sigma``:
    sigma_p, in weight units. ``kl_weight = 0`` gives the paper's step -lr H sigma.
    """
    _check_scalar("kl_weight", kl_weight, positive=False)
    _check_scalar("prior_sigma", prior_sigma, positive=True)
    _check_scalar("learning_rate", learning_rate, positive=True)
    _check_parameterisation(parameterisation)
    sigma, curvature = jnp.asarray(sigma), jnp.asarray(curvature)
    factor = 1.0 if parameterisation == "sigma" else -jnp.expm1(-sigma)
    data = -learning_rate * factor * curvature * sigma
    prior = -learning_rate * factor * kl_weight * sigma / prior_sigma**2
    entropy = learning_rate * factor * kl_weight / sigma
    data, prior, entropy = jnp.broadcast_arrays(data, prior, entropy)
    return SigmaStep(data, prior, entropy, data + prior + entropy)


def elbo_fixed_point(curvature: jnp.ndarray, kl_weight: float, prior_sigma: float) -> jnp.ndarray:
    """sigma*^2 = c / (H + c lambda), where the expected ELBO step of sigma vanishes.

    ``curvature``: H, any shape (loss units per weight^2); returns sigma*^2 of that shape
    (weight^2). The fixed point is stable: d(step)/d sigma = -lr [(H + c lambda) + c /
    sigma^2] < 0 there. For H > 0 (convex directions) sigma* < sigma_p: the data pull
    sigma below the prior's scale but never to zero while c > 0. For -c lambda < H <= 0,
    sigma* >= sigma_p: negative curvature grows sigma past the prior, up to where the
    prior stops it. For H <= -c lambda there is no fixed point (returned as ``inf``):
    within the quadratic model sigma grows without bound; on a real loss it grows until
    the curvature the population feels, averaged over the scale sigma, rises above -c
    lambda. ``kl_weight = 0`` gives 0 for H > 0 (the paper's collapse) and ``inf`` else.
    """
    _check_scalar("kl_weight", kl_weight, positive=False)
    _check_scalar("prior_sigma", prior_sigma, positive=True)
    stiffness = jnp.asarray(curvature) + kl_weight / prior_sigma**2
    safe = jnp.where(stiffness > 0, stiffness, 1.0)
    return jnp.where(stiffness > 0, kl_weight / safe, jnp.inf)


def gaussian_kl(mu: Pytree, sigma: Pytree, prior_sigma: float) -> jnp.ndarray:
    """Sum over every weight of KL(N(mu, sigma^2) || N(0, prior_sigma^2)), nats.

    The closed form the book's layers use (``sgb.priors.GaussianPrior.kl``), written as
    log sigma_p - log sigma + (sigma^2 + mu^2) / (2 sigma_p^2) - 1/2 at |sigma| floored at
    the dtype's smallest normal number: its sigma-gradient -1/sigma + sigma/sigma_p^2 stays
    finite for spreads as small as that, and zero for one that underflowed to 0 (as it
    can with no KL, ``kl_weight = 0``).
    """
    _check_scalar("prior_sigma", prior_sigma, positive=True)

    def one(m, s):
        s = jnp.abs(s)
        s = jnp.maximum(s, jnp.finfo(jnp.result_type(s, jnp.float32)).tiny)
        terms = jnp.log(prior_sigma) - jnp.log(s) + (s**2 + m**2) / (2.0 * prior_sigma**2)
        return jnp.sum(terms - 0.5)

    leaves = zip(jax.tree_util.tree_leaves(mu), jax.tree_util.tree_leaves(sigma), strict=True)
    return sum(one(m, s) for m, s in leaves)


def elbo_objective(
    loss_fn: LossFn,
    mu: Pytree,
    sigma: Pytree,
    eps: Pytree,
    kl_weight: float,
    prior_sigma: float,
) -> jnp.ndarray:
    """One draw of the negative ELBO the book trains: L(mu + sigma eps) + c KL(q || p).

    The data term is sampled at ``eps`` (same structure as ``mu``); the KL is the
    closed form ``gaussian_kl``, exact, as in ``sgb.layers`` for a Gaussian prior.
    """
    return loss_fn(_perturb(mu, sigma, eps)) + kl_weight * gaussian_kl(mu, sigma, prior_sigma)


class ElboStepComparison(NamedTuple):
    """One gradient step of the ELBO on (mu, sigma), measured and predicted (flat, (P,)).

    ``dmu``/``dsigma``: the step averaged over noise draws; ``*_stderr``: its Monte
    Carlo standard error. ``dmu_predicted = -lr (grad L(mu) + c mu / sigma_p^2)``;
    ``predicted``: ``elbo_sigma_step`` at diag(H) (data, prior and entropy terms);
    ``paper = -lr H sigma``, the appendix's step.
    """

    dmu: jnp.ndarray
    dmu_stderr: jnp.ndarray
    dsigma: jnp.ndarray
    dsigma_stderr: jnp.ndarray
    dmu_predicted: jnp.ndarray
    predicted: SigmaStep
    paper: jnp.ndarray


def elbo_gradient_step(
    loss_fn: LossFn,
    mu: Pytree,
    sigma: Pytree,
    key: jax.Array,
    learning_rate: float,
    kl_weight: float,
    prior_sigma: float,
    num_samples: int = 1000,
) -> ElboStepComparison:
    """One step of gradient descent on the sampled ELBO (``elbo_objective``), against theory.

    The sampled gradient in (mu, sigma) is averaged over ``num_samples`` draws in
    antithetic pairs. Uses the dense Hessian for the predictions: for small models.
    """
    _check_step_arguments(learning_rate, num_samples)
    _check_scalar("kl_weight", kl_weight, positive=False)
    _check_scalar("prior_sigma", prior_sigma, positive=True)
    _check_same_structure(mu, sigma)
    mu_flat, unravel = ravel_pytree(mu)
    sigma_flat, _ = ravel_pytree(sigma)
    flat_loss = lambda w: loss_fn(unravel(w))  # noqa: E731
    grad_fn = jax.grad(
        lambda m, s, e: elbo_objective(flat_loss, m, s, e, kl_weight, prior_sigma),
        argnums=(0, 1),
    )

    def pair(k):
        eps = jax.random.normal(k, mu_flat.shape, mu_flat.dtype)
        gm_plus, gs_plus = grad_fn(mu_flat, sigma_flat, eps)
        gm_minus, gs_minus = grad_fn(mu_flat, sigma_flat, -eps)
        return 0.5 * (gm_plus + gm_minus), 0.5 * (gs_plus + gs_minus)

    grad_mu, grad_sigma = jax.lax.map(pair, jax.random.split(key, num_samples // 2))
    dmu, dmu_se = _step_mean_and_se(grad_mu, learning_rate)
    dsigma, dsigma_se = _step_mean_and_se(grad_sigma, learning_rate)
    hessian = jax.hessian(flat_loss)(mu_flat)
    mu_gradient = jax.grad(flat_loss)(mu_flat) + kl_weight * mu_flat / prior_sigma**2
    return ElboStepComparison(
        dmu=dmu,
        dmu_stderr=dmu_se,
        dsigma=dsigma,
        dsigma_stderr=dsigma_se,
        dmu_predicted=-learning_rate * mu_gradient,
        predicted=elbo_sigma_step(
            sigma_flat, jnp.diag(hessian), kl_weight, prior_sigma, learning_rate
        ),
        paper=-learning_rate * hessian @ sigma_flat,
    )


class ElboTrajectory(NamedTuple):
    """Gradient descent on the ELBO of a 1-D loss; ``mu`` and ``sigma`` have shape (steps + 1,)."""

    mu: jnp.ndarray
    sigma: jnp.ndarray


def train_elbo_toy(
    loss: Callable[[jnp.ndarray], jnp.ndarray],
    mu0: float,
    sigma0: float,
    key: jax.Array,
    kl_weight: float,
    prior_sigma: float = 1.0,
    steps: int = 1000,
    learning_rate: float = 0.05,
    num_samples: int = 8,
    parameterisation: str = "sigma",
) -> ElboTrajectory:
    """Plain gradient descent on the sampled ELBO of a 1-D weight, as the book trains it.

    Each step draws ``num_samples`` fresh eps for the data term; the KL (weight
    ``kl_weight``, prior N(0, ``prior_sigma``^2)) is exact. ``parameterisation``:
    ``"sigma"`` descends on sigma itself (|sigma| is recorded); ``"softplus"`` on rho with
    sigma = softplus(rho), as the book's layers do. Jit-able and vmappable over ``mu0``,
    ``sigma0``, ``key`` and ``kl_weight``; ``prior_sigma`` must be a Python number.
    """
    for name, value in (("steps", steps), ("num_samples", num_samples)):
        _check_positive(name, value)
    _check_scalar("learning_rate", learning_rate, positive=True)
    _check_scalar("sigma0", sigma0, positive=True)
    _check_parameterisation(parameterisation)
    to_sigma = jnp.abs if parameterisation == "sigma" else jax.nn.softplus

    def objective(params, eps):
        m, raw = params
        draws = jax.vmap(
            lambda e: elbo_objective(loss, m, to_sigma(raw), e, kl_weight, prior_sigma)
        )
        return jnp.mean(draws(eps))

    grad_fn = jax.grad(objective)

    def step(params, k):
        g = grad_fn(params, jax.random.normal(k, (num_samples,)))
        new = tuple(p - learning_rate * gp for p, gp in zip(params, g, strict=True))
        return new, (params[0], to_sigma(params[1]))

    sigma0 = jnp.asarray(sigma0, jnp.float32)
    raw0 = sigma0 if parameterisation == "sigma" else softplus_inverse(sigma0)
    params = (jnp.asarray(mu0, jnp.float32), raw0)
    final, (mus, sigmas) = jax.lax.scan(step, params, jax.random.split(key, steps))
    return ElboTrajectory(
        mu=jnp.concatenate([mus, final[0][None]]),
        sigma=jnp.concatenate([sigmas, to_sigma(final[1])[None]]),
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
    mean = individual_kernels(model, {"params": layers}, x[:1], None)
    tables = genome.of_params(params)
    sigma = {
        name: expand_table(genome.sigma(tables[name]), kernel.shape)
        for name, kernel in mean.items()
    }
    full_model = model.clone(cell_types=(None,) * len(model.cell_types))

    def forward(weights: dict, inputs: jnp.ndarray) -> jnp.ndarray:
        full = {name: {"bias": layer["bias"]} for name, layer in layers.items()}
        return full_model.apply(
            genome.with_tables(
                {"params": full}, {n: LayerGenome(w, jnp.zeros_like(w)) for n, w in weights.items()}
            ),
            inputs,
            mean_network=True,
        )

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


class GenomeFixedPoint(NamedTuple):
    """One SGB layer's learned spreads against the ELBO's fixed point, per type pair.

    Every field has the type table's shape (k_in, k_out). ``sigma2``: the learned
    softplus(rho)^2 (weight^2); ``count``: synapses per pair; ``curvature``: the pair's
    effective H, the sum of the data term's Hessian diagonal over its synapses divided by
    the number of times the KL counts the pair (``count`` with synapse counting, 1 with
    table counting), in loss units per weight^2; ``predicted``: ``elbo_fixed_point`` of
    it, c / (curvature + c lambda) (weight^2).
    """

    sigma2: jnp.ndarray
    count: jnp.ndarray
    curvature: jnp.ndarray
    predicted: jnp.ndarray


def genome_fixed_point(
    model: SGBMLP, params: Pytree, hessian_diag: dict, kl_weight: float
) -> dict[str, GenomeFixedPoint]:
    """Per layer, each type pair's learned sigma^2 next to c / (H + c lambda).

    ``hessian_diag``: per layer, the (n_in, n_out) diagonal of the data term's Hessian
    over the expanded synapses at the trained means (``hessian_diagonal`` of a
    ``network_loss`` of ``synapse_view``), with the data term in the units the ELBO uses
    (the book's: mean loss per training example, so ``kl_weight`` = kl_scale / n_train).
    A type pair's spread multiplies every one of its synapses' noise, so the data term's
    sigma-gradient is sigma times the sum of their H_ss, and the KL counts it ``count``
    times (synapse counting) or once (table counting). Needs a Gaussian prior.
    """
    if not isinstance(model.prior, GaussianPrior):
        raise ValueError(f"the fixed point needs a Gaussian prior, got {model.prior!r}")
    tables = genome.of_params(params)
    out = {}
    for name, diagonal in hessian_diag.items():
        sigma = genome.sigma(tables[name])
        counts = jnp.asarray(block_counts(diagonal.shape, sigma.shape), diagonal.dtype)
        summed = sum_blocks(diagonal, sigma.shape)
        curvature = summed / counts if model.kl_counting == "synapse" else summed
        out[name] = GenomeFixedPoint(
            sigma2=sigma**2,
            count=counts,
            curvature=curvature,
            predicted=elbo_fixed_point(curvature, kl_weight, model.prior.sigma),
        )
    return out
