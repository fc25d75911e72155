"""Standard normal weight noise from a counter-based hash, about 3x faster than threefry here.

Drawing an individual needs one normal per synapse: 1.3 million for a 784-800-800-10
network, where ``jax.random.normal`` (threefry, 20 rounds per pair of words) costs
more than the whole training step of the plain network on a CPU. Here each synapse's
flat index is mixed with two 32-bit words drawn from the key by murmur3's 32-bit
finaliser, applied twice (a bijection of the index with full avalanche), and the top
23 bits become a uniform variate strictly inside (0, 1) that the inverse error function
turns into a normal, as ``jax.random.normal`` does (23 bits, so that every value and its
image 2u - 1 are exact in float32: no draw rounds to 1 and becomes infinite; the normals
reach about 5.3 sigma). Different keys give independent streams for all
practical purposes; the noise is not meant for cryptography.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

_MAX_SIZE = 2**32


def _mix(x: jnp.ndarray) -> jnp.ndarray:
    """murmur3's 32-bit finaliser, elementwise on uint32."""
    x = x ^ (x >> 16)
    x = x * jnp.uint32(0x85EBCA6B)
    x = x ^ (x >> 13)
    x = x * jnp.uint32(0xC2B2AE35)
    return x ^ (x >> 16)


def standard_normal(key: jax.Array, shape: tuple[int, ...]) -> jnp.ndarray:
    """float32 N(0, 1) noise of ``shape``, a deterministic function of ``key``."""
    size = int(np.prod(shape, dtype=np.int64))
    if size >= _MAX_SIZE:
        raise ValueError(f"shape {shape} has {size} elements; at most 2**32 - 1 are supported")
    seed = jax.random.bits(key, (2,), jnp.uint32)
    hashed = _mix(_mix(lax.iota(jnp.uint32, size) ^ seed[0]) + seed[1])
    return normal_from_bits(hashed).reshape(shape)


def normal_from_bits(bits: jnp.ndarray) -> jnp.ndarray:
    """uint32 words -> float32 N(0, 1) by the inverse CDF of their top 23 bits; finite for
    every word."""
    uniform = ((bits >> 9).astype(jnp.float32) + 0.5) * 2.0**-23
    return jnp.sqrt(2.0) * lax.erf_inv(2.0 * uniform - 1.0)
