"""Training throughput (samples/s) of SGB, DGB and the uncompressed network at the paper's
MNIST shape, 784-800-10, on random inputs.

    python benchmarks/bench_supervised.py [--batches 1000] [--hidden-types 50] [--gnet-width 50]

Each model is trained for 1 and for 1 + R epochs of ``--batches`` minibatches of 64;
the difference excludes compilation (epochs long enough that training, not the spread
of compile times, sets it). "sgb, S samples" draws S whole individuals per minibatch;
"sgb local" trains the same SGB with the local reparameterisation. The DGB writes back
every ``--pnet-steps`` minibatches, as its authors do every 100 (its g-net fits, kernel
generation and validation scoring included in its rate).
"""

import argparse
import dataclasses
import time

import jax
import numpy as np

from sgb.compression import compression, dense_param_count
from sgb.data import Dataset
from sgb.dgb import DGBConfig, train_dgb
from sgb.supervised import ClassifierConfig, DenseConfig, train_classifier, train_dense


def _timed(train, epochs: int) -> float:
    start = time.perf_counter()
    jax.block_until_ready(train(epochs)[1])
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batches", type=int, default=1000, help="minibatches per epoch")
    parser.add_argument("--pnet-steps", type=int, default=100, help="DGB minibatches a round")
    parser.add_argument("--repeats", type=int, default=3, help="timed epochs R")
    parser.add_argument("--hidden-types", type=int, default=50)
    parser.add_argument("--gnet-width", type=int, default=50)
    parser.add_argument("--gnet-steps", type=int, default=50)
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    n = 64 * args.batches
    x = rng.normal(size=(n, 784)).astype(np.float32)
    y = rng.integers(0, 10, n).astype(np.int32)
    data = Dataset("random-mnist-shape", x, y, x[:256], y[:256], 10)
    sizes = (784, 800, 10)
    sgb = ClassifierConfig(hidden=(800,), cell_types=(30, args.hidden_types, 10))
    dgb = DGBConfig(
        hidden=(800,),
        gnet_width=args.gnet_width,
        pnet_steps=args.pnet_steps,
        batch_size=64,
        gnet_steps=args.gnet_steps,
        validation_size=5000,
    )
    sgb_ratio = compression("sgb", sizes, args.hidden_types, 30, 10)
    models = {
        "uncompressed": (
            lambda e: train_dense(DenseConfig(hidden=(800,), epochs=e), data, False),
            1.0,
        ),
        "sgb, 1 sample": (
            lambda e: train_classifier(
                dataclasses.replace(sgb, epochs=e, num_samples=1), data, False
            ),
            sgb_ratio,
        ),
        "sgb, 2 samples": (
            lambda e: train_classifier(dataclasses.replace(sgb, epochs=e), data, False),
            sgb_ratio,
        ),
        "sgb local": (
            lambda e: train_classifier(
                dataclasses.replace(sgb, epochs=e, local_reparam=True), data, False
            ),
            sgb_ratio,
        ),
        "dgb": (
            lambda e: train_dgb(
                dataclasses.replace(dgb, rounds=e * args.batches // args.pnet_steps), data, False
            ),
            compression("dgb", sizes, args.gnet_width, 30, 10),
        ),
    }
    print(f"backend {jax.default_backend()}, {dense_param_count(sizes)} uncompressed parameters")
    rates = {}
    for name, (train, ratio) in models.items():
        elapsed = _timed(train, 1 + args.repeats) - _timed(train, 1)
        rates[name] = args.repeats * n / elapsed
        print(f"{name:>15}: compression {ratio:7.1f}  {rates[name]:9.0f} samples/s", flush=True)
    for name in models:
        if name != "uncompressed":
            print(f"{name} / uncompressed throughput: {rates[name] / rates['uncompressed']:.3f}")


if __name__ == "__main__":
    main()
