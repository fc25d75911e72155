"""Property-based checks of the public constructors and calls.

Each example draws every argument from its valid range, then makes at most one of them
invalid. An invalid argument must give a ``ValueError`` or ``TypeError`` whose message
names it; a fully valid draw must give finite output. Anything else (an error from deep
inside jax, flax or numpy, a silent nan or inf, an invalid value accepted) fails.
The examples are derandomised and no database is kept, so every run sees the same ones:
130 per test, 20 for the layer and 15 for the MLP with its ELBO (each of their examples
initialises and runs its model as one jitted program, so it compiles once), 815 in all.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sgb import compression, stats
from sgb.celltypes import expand_table, type_sizes
from sgb.elbo import elbo_loss
from sgb.layers import SGBMLP, SGBDense
from sgb.population import init_params
from sgb.priors import GaussianPrior, ScaleMixturePrior
from sgb.rl.networks import NetworkConfig
from sgb.rl.ppo import PPOConfig
from sgb.supervised import ClassifierConfig, DenseConfig

FUZZ = settings(
    max_examples=130,
    derandomize=True,
    database=None,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

BAD_INTEGERS = st.one_of(
    st.integers(-5, 0), st.sampled_from([2.5, "3", None, True, float("nan"), 3.0])
)
BAD_POSITIVE = st.one_of(
    st.floats(-10, 0), st.sampled_from([float("nan"), float("inf"), -float("inf"), "0.1", None])
)
BAD_NON_NEGATIVE = st.one_of(
    st.floats(-10, -1e-6), st.sampled_from([float("nan"), float("inf"), "1", None])
)
BAD_REAL = st.sampled_from([float("nan"), float("inf"), -float("inf"), "-5", None, [1.0]])


def finite(tree) -> bool:
    leaves = jax.tree_util.tree_leaves(tree)
    return all(np.all(np.isfinite(np.asarray(leaf, dtype=np.float64))) for leaf in leaves)


def compiled_once(init_and_call) -> object:
    """``init_and_call(keys)`` on keys 0 and 1 as one jitted program: one compilation per
    example, not one per operation (a bad argument still raises while it is traced)."""
    return jax.jit(init_and_call)(jnp.stack([jax.random.key(0), jax.random.key(1)]))


def draw_args(draw, valid: dict, invalid: dict) -> tuple[dict, str | None]:
    """Valid values of every argument; then, in most examples, one made invalid.
    Returns the arguments and the name of the invalid one (``None``: all valid)."""
    args = {name: draw(strategy) for name, strategy in valid.items()}
    bad = draw(st.sampled_from([None, None, *invalid]))
    if bad is not None:
        args[bad] = draw(invalid[bad])
    return args, bad


def expect(call, bad: str | None):
    """Run ``call``: finite output if all arguments are valid, else an error naming ``bad``."""
    if bad is None:
        out = call()
        assert finite(out), out
        return out
    with pytest.raises((ValueError, TypeError)) as error:
        call()
    assert bad.split("[")[0] in str(error.value), (bad, str(error.value))
    return None


@FUZZ
@given(st.data())
def test_cell_types(data):
    n = data.draw(st.integers(1, 40))
    args, bad = draw_args(
        data.draw,
        {"n": st.just(n), "k": st.integers(1, n)},
        {"n": BAD_INTEGERS, "k": st.one_of(BAD_INTEGERS, st.integers(n + 1, n + 5))},
    )
    sizes = expect(lambda: type_sizes(args["n"], args["k"]), bad)
    if sizes is not None:
        assert sizes.sum() == n and sizes.max() - sizes.min() <= 1
        table = jnp.arange(float(args["k"]))[:, None]
        assert expand_table(table, (n, 1)).shape == (n, 1)


@FUZZ
@given(st.data())
def test_priors(data):
    mu = jnp.linspace(-1.0, 1.0, 5)
    if data.draw(st.booleans()):
        args, bad = draw_args(data.draw, {"sigma": st.floats(1e-3, 10)}, {"sigma": BAD_POSITIVE})
        expect(lambda: GaussianPrior(**args).kl(mu, jnp.full(5, 0.05)), bad)
    else:
        args, bad = draw_args(
            data.draw,
            {"pi": st.floats(0, 1), "sigma1": st.floats(1e-2, 10), "sigma2": st.floats(1e-3, 1)},
            {
                "pi": st.one_of(st.floats(1.01, 5), st.floats(-5, -0.01), BAD_REAL),
                "sigma1": BAD_POSITIVE,
                "sigma2": BAD_POSITIVE,
            },
        )
        expect(lambda: ScaleMixturePrior(**args).log_prob(mu), bad)


@settings(FUZZ, max_examples=20)
@given(st.data())
def test_dense_layer(data):
    n_in = data.draw(st.integers(1, 12))
    features = data.draw(st.integers(1, 12))
    args, bad = draw_args(
        data.draw,
        {
            "features": st.just(features),
            "in_types": st.one_of(st.none(), st.integers(1, n_in)),
            "out_types": st.one_of(st.none(), st.integers(1, features)),
            "prior": st.sampled_from([GaussianPrior(0.1), ScaleMixturePrior()]),
            "kl_counting": st.sampled_from(["synapse", "table"]),
            "rho_init": st.floats(-8, 2),
            "in_features": st.just(n_in),
        },
        {
            "features": BAD_INTEGERS,
            "in_types": st.one_of(BAD_INTEGERS.filter(lambda v: v is not None), st.just(n_in + 1)),
            "out_types": st.one_of(
                BAD_INTEGERS.filter(lambda v: v is not None), st.just(features + 1)
            ),
            "prior": st.sampled_from(["gaussian", 0.1, None]),
            "kl_counting": st.sampled_from(["bogus", "", None]),
            "rho_init": BAD_REAL,
            "in_features": st.sampled_from([n_in + 1, max(1, n_in - 1) if n_in > 1 else 2]),
        },
    )
    x = jnp.linspace(-1.0, 1.0, 2 * n_in).reshape(2, n_in)

    def call():
        layer = SGBDense(**args)

        def init_and_apply(keys):
            params = init_params(layer, keys[0], x)
            return layer.apply(params, x, rngs={"sample": keys[1]}, mutable=["losses"])

        return compiled_once(init_and_apply)

    expect(call, bad)


@settings(FUZZ, max_examples=15)
@given(st.data())
def test_mlp_and_elbo(data):
    width = data.draw(st.integers(1, 8))
    args, bad = draw_args(
        data.draw,
        {
            "widths": st.just((width, 3)),
            "cell_types": st.tuples(st.just(None), st.integers(1, width), st.just(None)),
            "num_samples": st.integers(1, 3),
            "kl_weight": st.floats(0, 1),
        },
        {
            "widths": st.sampled_from([(), (0, 3), (2.5, 3), "8", None]),
            "cell_types": st.sampled_from([(None,), (None, width + 1, None), (None, 0, None), 3]),
            "num_samples": BAD_INTEGERS,
            "kl_weight": BAD_NON_NEGATIVE,
        },
    )
    x = jnp.ones((4, 5))
    y = jnp.array([0, 1, 2, 0])

    def call():
        model = SGBMLP(widths=args["widths"], cell_types=args["cell_types"], in_features=5)

        def init_and_loss(keys):
            params = init_params(model, keys[0], x)
            return elbo_loss(
                model,
                params,
                x,
                y,
                keys[1],
                num_samples=args["num_samples"],
                kl_weight=args["kl_weight"],
            )

        return compiled_once(init_and_loss)

    expect(call, bad)


@FUZZ
@given(st.data())
def test_compression(data):
    sizes = data.draw(st.lists(st.integers(1, 50), min_size=2, max_size=4).map(tuple))
    types = tuple(data.draw(st.one_of(st.none(), st.integers(1, n))) for n in sizes)
    args, bad = draw_args(
        data.draw,
        {"sizes": st.just(sizes), "cell_types": st.just(types)},
        {
            "sizes": st.sampled_from([(5,), (), (5, 0), (5, 2.5), "784", None]),
            "cell_types": st.sampled_from([(1,), (0,) * len(sizes), (2.5,) * len(sizes)]),
        },
    )

    def call():
        dense = compression.dense_param_count(args["sizes"])
        sgb = compression.sgb_param_count(args["sizes"], args["cell_types"])
        return compression.compression_ratio(dense, sgb)

    ratio = expect(call, bad)
    if ratio is not None:
        assert ratio > 0


@FUZZ
@given(st.data())
def test_statistics(data):
    n = data.draw(st.integers(2, 30))
    values = st.lists(st.integers(-1000, 1000), min_size=n, max_size=n, unique=True).map(
        lambda v: [0.37 * x for x in v]
    )
    bad_values = st.sampled_from([[1.0], [1.0, float("nan")] + [0.0] * (n - 2), ["a"] * n, None])
    bad_level = st.one_of(st.floats(1, 5), st.floats(-5, 0), BAD_REAL)
    which = data.draw(st.sampled_from(["sem", "mean_ci", "pearson", "paired_t"]))
    valid = {
        "sem": {"values": values},
        "mean_ci": {"values": values, "level": st.floats(0.5, 0.99)},
        "pearson": {"x": values, "y": values},
        "paired_t": {"a": values, "b": values},
    }[which]
    invalid = {name: bad_level if name == "level" else bad_values for name in valid}
    args, bad = draw_args(data.draw, valid, invalid)
    if which == "paired_t" and bad is None:
        # a constant difference has no t statistic: an error that names it
        constant = len(set(np.subtract(args["a"], args["b"]))) == 1
        bad = "a - b" if constant else None
    expect(lambda: getattr(stats, which)(**args), bad)


@FUZZ
@given(st.data())
def test_rl_configs(data):
    args, bad = draw_args(
        data.draw,
        {
            "learning_rate": st.floats(1e-6, 1e-1),
            "clip": st.floats(0.01, 1),
            "discount": st.floats(0.5, 1),
            "gae_lambda": st.floats(0, 1),
            "kl_coef": st.floats(0, 1),
            "entropy_coef": st.floats(0, 1),
            "num_envs": st.sampled_from([4, 8, 128]),
            "env": st.just(PPOConfig().env),
            "cell_types": st.one_of(st.none(), st.integers(1, 16)),
            "hidden": st.just((16, 16)),
            "rho_init": st.floats(-10, 0),
        },
        {
            "learning_rate": BAD_POSITIVE,
            "clip": BAD_POSITIVE,
            "discount": st.one_of(st.floats(1.01, 3), st.floats(-1, 0), BAD_REAL),
            "gae_lambda": st.one_of(st.floats(1.01, 3), st.floats(-1, -0.01), BAD_REAL),
            "kl_coef": BAD_NON_NEGATIVE,
            "entropy_coef": BAD_NON_NEGATIVE,
            "num_envs": BAD_INTEGERS,
            "env": st.sampled_from(["ant", None]),
            "cell_types": st.one_of(st.just(2.5), st.just(0), st.just(17)),
            "hidden": st.sampled_from([(), (64.5,), (0, 8), "64"]),
            "rho_init": BAD_REAL,
        },
    )
    network_keys = ("cell_types", "hidden", "rho_init")

    def call():
        network = NetworkConfig(**{k: args[k] for k in network_keys})
        ppo = {k: v for k, v in args.items() if k not in network_keys}
        return [PPOConfig(network=network, num_minibatches=4, **ppo).learning_rate]

    expect(call, bad)


@FUZZ
@given(st.data())
def test_classifier_configs(data):
    args, bad = draw_args(
        data.draw,
        {
            "learning_rate": st.floats(1e-6, 1e-1),
            "kl_scale": st.floats(0, 10),
            "batch_size": st.integers(1, 256),
            "epochs": st.integers(1, 50),
            "hidden": st.just((32,)),
            "cell_types": st.just((None, 8, None)),
            "kl_counting": st.sampled_from(["synapse", "table"]),
            "prior": st.sampled_from([GaussianPrior(0.1), ScaleMixturePrior()]),
            "rho_init": st.floats(-10, 0),
        },
        {
            "learning_rate": BAD_POSITIVE,
            "kl_scale": BAD_NON_NEGATIVE,
            "batch_size": BAD_INTEGERS,
            "epochs": BAD_INTEGERS,
            "hidden": st.sampled_from([(), (32.5,), "32"]),
            "cell_types": st.sampled_from([(None, 8), (None, 0, None), (2.5, 8, None)]),
            "kl_counting": st.sampled_from(["bogus", None]),
            "prior": st.sampled_from(["gaussian", None]),
            "rho_init": BAD_REAL,
        },
    )
    dense_keys = ("learning_rate", "batch_size", "epochs", "hidden")

    def call():
        config = ClassifierConfig(**args)
        dense = DenseConfig(**{k: args[k] for k in dense_keys})
        return [config.learning_rate, dense.learning_rate]

    expect(call, bad)
