"""Time of one SGB training step relative to a plain Flax Dense network of the same shape.

Network 784-800-800-10, batch 64, Adam, one weight sample per step (S = 1) unless stated;
"local" rows draw pre-activations instead of weights (``local_reparam=True``).
All timings are taken in this one run, interleaved, and reported as medians:
    python benchmarks/bench_layers.py [--repeats 30]
"""

import argparse
import time

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax

from sgb.elbo import cross_entropy, elbo_loss
from sgb.individuals import init_params
from sgb.layers import SGBMLP
from sgb.provenance import package_versions

SIZES = (784, 800, 800, 10)
BATCH = 64


class DenseMLP(nn.Module):
    """The plain baseline: Dense-ReLU-Dense-ReLU-Dense."""

    @nn.compact
    def __call__(self, x):
        for i, width in enumerate(SIZES[1:]):
            x = nn.Dense(width)(x)
            if i < len(SIZES) - 2:
                x = nn.relu(x)
        return x


def make_step(loss_fn, params):
    """A jitted Adam step on ``loss_fn(params, x, y, key)``; returns (step, opt_state)."""
    tx = optax.adam(1e-3)

    @jax.jit
    def step(params, opt_state, x, y, key):
        grads = jax.grad(loss_fn)(params, x, y, key)
        updates, opt_state = tx.update(grads, opt_state, params)
        return optax.apply_updates(params, updates), opt_state

    return step, tx.init(params)


def build_candidates():
    x = jnp.ones((BATCH, SIZES[0]))
    key = jax.random.key(0)
    dense = DenseMLP()
    dense_params = dense.init(key, x)
    candidates = {"dense": (lambda p, x, y, k: cross_entropy(dense.apply(p, x), y), dense_params)}
    bnn, typed = (None, None, None, None), (30, 100, 100, 10)
    for label, types, samples, local in (
        ("SGB k = n (BNN), S = 1", bnn, 1, False),
        ("SGB k = n (BNN), S = 1, local", bnn, 1, True),
        ("SGB 30-100-100-10 types, S = 1", typed, 1, False),
        ("SGB 30-100-100-10 types, S = 1, local", typed, 1, True),
        ("SGB 30-100-100-10 types, S = 4", typed, 4, False),
        ("SGB 30-100-100-10 types, S = 4, local", typed, 4, True),
    ):
        model = SGBMLP(widths=SIZES[1:], cell_types=types)

        def loss(p, x, y, k, model=model, samples=samples, local=local):
            return elbo_loss(
                model, p, x, y, k, num_samples=samples, kl_weight=1 / 60_000, local_reparam=local
            )[0]

        candidates[label] = (loss, init_params(model, key, x))
    return candidates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    x = jnp.asarray(rng.standard_normal((BATCH, SIZES[0])), jnp.float32)
    y = jnp.asarray(rng.integers(0, 10, BATCH))
    states = {}
    for name, (loss, params) in build_candidates().items():
        step, opt_state = make_step(loss, params)
        params, opt_state = step(params, opt_state, x, y, jax.random.key(1))  # compile
        jax.block_until_ready(params)
        states[name] = [step, params, opt_state, []]
    for r in range(args.repeats):
        for state in states.values():
            step, params, opt_state, times = state
            start = time.perf_counter()
            params, opt_state = step(params, opt_state, x, y, jax.random.key(r))
            jax.block_until_ready(params)
            times.append(time.perf_counter() - start)
            state[1], state[2] = params, opt_state
    dense_ms = 1e3 * np.median(states["dense"][3])
    print(f"backend {jax.default_backend()}, versions {package_versions()}")
    print(f"network {'-'.join(map(str, SIZES))}, batch {BATCH}, {args.repeats} repeats")
    print(f"{'model':<40} {'median ms/step':>15} {'ratio to dense':>15}")
    for name, (*_, times) in states.items():
        ms = 1e3 * np.median(times)
        print(f"{name:<40} {ms:>15.2f} {ms / dense_ms:>15.2f}")


if __name__ == "__main__":
    main()
