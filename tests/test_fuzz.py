"""Property-based checks of the public constructors and calls.

Each example draws every argument from its valid range, then makes at most one of them
invalid. An invalid argument must give a ``ValueError`` or ``TypeError`` whose message
names it; a fully valid draw must give finite output. Anything else (an error from deep
inside jax, flax or numpy, a silent nan or inf, an invalid value accepted) fails.
The targets: the configs, layers, priors and statistics; the low-level functions (the
genome's KL, the individual kernel, the noise, the cell-type helpers, the labels of the
loss); the data loaders' seeds and sizes; the population and PPO entry points; the
evaluation's inputs; the one softplus; and the files the package reads, each damaged
one way (a damaged file must be a ``CorruptFile`` naming it, or load exactly as saved).
The examples are derandomised and no database is kept, so every run sees the same ones:
130 per test unless stated (20 for the layer and 15 for the MLP with its ELBO: each of
their examples initialises and runs its model as one jitted program, so it compiles
once), 1515 in all.
"""

import tempfile
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sgb import compression, stats
from sgb.celltypes import expand_table, type_sizes
from sgb.elbo import elbo_loss
from sgb.individuals import init_params
from sgb.layers import SGBMLP, SGBDense
from sgb.priors import GaussianPrior, ScaleMixturePrior
from sgb.rl.agent import NetworkConfig
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
            "y": st.just(jnp.array([0, 1, 2, 0])),
        },
        {
            "widths": st.sampled_from([(), (0, 3), (2.5, 3), "8", None]),
            "cell_types": st.sampled_from([(None,), (None, width + 1, None), (None, 0, None), 3]),
            "num_samples": BAD_INTEGERS,
            "kl_weight": BAD_NON_NEGATIVE,
            "y": st.sampled_from(
                [jnp.array([0, 1, 3, 0]), jnp.array([0, -1, 2, 0]), jnp.zeros(4), jnp.zeros(3, int)]
            ),
        },
    )
    x = jnp.ones((4, 5))
    y = args["y"]

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
    which = data.draw(st.sampled_from(["sem", "mean_ci", "fisher_r", "paired"]))
    valid = {
        "sem": {"values": values},
        "mean_ci": {"values": values, "level": st.floats(0.5, 0.99)},
        "fisher_r": {"x": values, "y": values},
        "paired": {"a": values, "b": values},
    }[which]
    invalid = {name: bad_level if name == "level" else bad_values for name in valid}
    args, bad = draw_args(data.draw, valid, invalid)
    if which == "paired" and bad is None:
        # a constant difference has no t statistic: an error that names it
        constant = len(set(np.subtract(args["a"], args["b"]))) == 1
        bad = "a - b" if constant else None
    if which == "fisher_r" and n < 4:
        bad = "x"  # r needs 4 pairs, x is checked first
    elif which == "fisher_r" and bad is None:
        # Fisher's z is infinite at r = +-1: an error that names x and y
        bad = "x" if abs(np.corrcoef(args["x"], args["y"])[0, 1]) == 1 else None
    call = getattr(stats, which)
    if which in ("fisher_r", "paired"):  # a Test: its numbers, after its name
        expect(lambda: call(**args)[1:], bad)
    else:
        expect(lambda: call(**args), bad)


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


# ------------------------------------------------------------------ damaged files
# Each example damages a good file one way (a flipped bit, a cut, a run of zeros, junk
# appended, an empty file): loading it must raise a ``CorruptFile`` that names it, or
# give back exactly what was saved. Never another error, never other values.

DAMAGE = st.one_of(
    st.tuples(st.just("flip"), st.floats(0, 1, exclude_max=True), st.integers(0, 7)),
    st.tuples(st.just("cut"), st.floats(0, 1, exclude_max=True), st.just(0)),
    st.tuples(st.just("zeros"), st.floats(0, 1, exclude_max=True), st.integers(1, 64)),
    st.tuples(st.just("junk"), st.just(0.0), st.integers(1, 64)),
    st.tuples(st.just("empty"), st.just(0.0), st.just(0)),
)


def damaged(good: bytes, damage: tuple) -> bytes:
    kind, where, size = damage
    i = int(where * len(good))
    if kind == "flip":
        return good[:i] + bytes([good[i] ^ (1 << size)]) + good[i + 1 :]
    if kind == "cut":
        return good[:i]
    if kind == "zeros":
        return good[:i] + bytes(min(size, len(good) - i)) + good[i + size :]
    if kind == "junk":
        return good + bytes(range(size))
    return b""


@pytest.fixture(scope="module")
def state_file(tmp_path_factory):
    from sgb import resume

    state = {"w": jnp.linspace(-1.0, 1.0, 40), "n": jnp.arange(3), "key": jax.random.key(7)}
    path = tmp_path_factory.mktemp("state") / "run.state.npz"
    resume.save(path, state, {"seed": 1}, {"chunks": 2, "records": [0.5]})
    return path, path.read_bytes(), state


@settings(FUZZ, max_examples=200)
@given(damage=DAMAGE)
def test_damaged_state_files(state_file, damage):
    from sgb import resume
    from sgb.validation import CorruptFile

    good_path, good, state = state_file
    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / "run.state.npz"
        path.write_bytes(damaged(good, damage))
        try:
            loaded, progress = resume.load(path, state, {"seed": 1}, ("chunks", "records"))
        except CorruptFile as error:
            assert str(path) in str(error) and "delete it" in str(error)
            return
    assert progress == {"chunks": 2, "records": [0.5]}
    leaves = zip(jax.tree_util.tree_leaves(loaded), jax.tree_util.tree_leaves(state), strict=True)
    for a, b in leaves:
        if jax.dtypes.issubdtype(a.dtype, jax.dtypes.prng_key):
            a, b = jax.random.key_data(a), jax.random.key_data(b)
        np.testing.assert_array_equal(a, b)


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory):
    from reach import reach_config

    from sgb.rl import checkpoints, ppo
    from sgb.rl.normalizer import init_normalizer

    config = reach_config(2, network=NetworkConfig(hidden=(4,), cell_types=2))
    result = ppo.TrainResult(
        config, ppo.initial_params(config, 0), init_normalizer(2), [64], [-9.5], 1e3, 1.0
    )
    path = checkpoints.save(tmp_path_factory.mktemp("agent") / "agent.msgpack", result)
    return path.read_bytes(), path.with_suffix(".json").read_bytes(), checkpoints.load(path)


@settings(FUZZ, max_examples=40)
@given(damage=DAMAGE, which=st.sampled_from(["msgpack", "json"]))
def test_damaged_checkpoints(checkpoint, damage, which):
    from sgb.rl import checkpoints
    from sgb.validation import CorruptFile

    good_msgpack, good_sidecar, (config, params, normalizer, meta) = checkpoint
    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / "agent.msgpack"
        files = {"msgpack": [path, good_msgpack], "json": [path.with_suffix(".json"), good_sidecar]}
        files[which][1] = damaged(files[which][1], damage)
        for file, content in files.values():
            file.write_bytes(content)
        try:
            loaded = checkpoints.load(path)
        except CorruptFile as error:
            assert str(files[which][0]) in str(error) and "delete it" in str(error)
            return
    assert loaded[0] == config and loaded[3] == meta
    expected = jax.tree_util.tree_leaves((params, normalizer))
    for a, b in zip(jax.tree_util.tree_leaves(loaded[1:3]), expected, strict=True):
        np.testing.assert_array_equal(a, b)


# ------------------------------------------------------------------ low-level functions


@settings(FUZZ, max_examples=60)
@given(st.data())
def test_genome_kl_and_individual_kernel(data):
    from sgb.genome import individual_kernel, layer_kl

    k_in, k_out = data.draw(st.sampled_from([(1, 1), (2, 3)]))
    table = jnp.full((k_in, k_out), 0.1)
    key = jax.random.key(0)
    which = data.draw(st.sampled_from(["layer_kl", "individual_kernel"]))
    if which == "layer_kl":
        args, bad = draw_args(
            data.draw,
            {
                "prior": st.sampled_from([GaussianPrior(0.1), ScaleMixturePrior()]),
                "sigma": st.just(table),
                "shape": st.just((4, 5)),
                "counting": st.sampled_from(["synapse", "table"]),
                "key": st.just(key),
            },
            {
                "prior": st.sampled_from([None, "gaussian", 0.1]),
                "sigma": st.sampled_from([jnp.ones((k_in + 1, k_out)), -table, table * jnp.nan]),
                "shape": st.sampled_from([(4,), (4, 0), (4, 5.5), (0, 5), "45", None]),
                "counting": st.sampled_from(["bogus", None]),
                "key": st.sampled_from([None, 3, jnp.zeros(3, jnp.uint32)]),
            },
        )
        if bad == "key" and isinstance(args["prior"], GaussianPrior):
            args["prior"] = ScaleMixturePrior()  # only the Monte Carlo KL draws with the key
        expect(
            lambda: layer_kl(
                args["prior"], table, args["sigma"], args["shape"], args["counting"], args["key"]
            ),
            bad,
        )
    else:
        noise = jnp.ones((2, 4, 5))
        args, bad = draw_args(
            data.draw,
            {"rho": st.just(table - 5.0), "noise": st.sampled_from([noise, noise[0]])},
            {
                "rho": st.sampled_from(
                    [jnp.ones((k_in, k_out + 1)), jnp.ones((k_in, k_out), int), None]
                ),
                "noise": st.sampled_from(
                    [jnp.ones(5), jnp.ones((4, 1)), jnp.ones((4, 5), int), "x"]
                ),
            },
        )
        if bad == "noise" and k_out == 1 and np.shape(args["noise"]) == (4, 1):
            bad = None  # one output type fits one neuron
        expect(lambda: individual_kernel(table, args["rho"], args["noise"]), bad)


@FUZZ
@given(st.data())
def test_noise_and_cell_type_helpers(data):
    from sgb.celltypes import assign_cell_types, block_counts, sum_blocks, type_pair_block
    from sgb.noise import normal_from_bits, standard_normal

    which = data.draw(
        st.sampled_from(["noise", "bits", "assign", "counts", "sum_blocks", "pair_block"])
    )
    n = data.draw(st.integers(1, 9))
    k = data.draw(st.integers(1, n))
    if which == "noise":
        args, bad = draw_args(
            data.draw,
            {"key": st.just(jax.random.key(1)), "shape": st.sampled_from([(), (3,), (n, k)])},
            {
                "key": st.sampled_from([None, 0, jnp.zeros(3, jnp.uint32), "key"]),
                "shape": st.sampled_from([(-1,), (2.5,), "3", None, (2, None)]),
            },
        )
        expect(lambda: standard_normal(args["key"], args["shape"]), bad)
    elif which == "bits":
        args, bad = draw_args(
            data.draw,
            {"bits": st.just(jnp.arange(n, dtype=jnp.uint32))},
            {"bits": st.sampled_from([jnp.arange(3.0), jnp.arange(3), None, "bits"])},
        )
        expect(lambda: normal_from_bits(args["bits"]), bad)
    elif which == "assign":
        args, bad = draw_args(
            data.draw,
            {"n": st.just(n), "k": st.just(k)},
            {"n": BAD_INTEGERS, "k": st.one_of(BAD_INTEGERS, st.just(n + 1), st.just("3"))},
        )
        out = expect(lambda: assign_cell_types(args["n"], args["k"]), bad)
        if out is not None:
            assert out.shape == (n,) and set(out.tolist()) == set(range(k))
    elif which == "counts":
        args, bad = draw_args(
            data.draw,
            {"shape": st.just((n, 3)), "types": st.just((k, 2))},
            {
                "shape": st.sampled_from([(n,), (0, 3), (2.5, 3), None, "n3"]),
                "types": st.sampled_from([(n + 1, 2), (k, 0), (k,), None, (k, 2.5)]),
            },
        )
        out = expect(lambda: block_counts(args["shape"], args["types"]), bad)
        if out is not None:
            assert out.sum() == 3 * n
    elif which == "sum_blocks":
        args, bad = draw_args(
            data.draw,
            {"x": st.just(jnp.ones((n, 3))), "types": st.just((k, 3))},
            {
                "x": st.sampled_from([None, [1.0, 2.0]]),
                "types": st.sampled_from([(n + 1, 3), (k,), (k, 0), None, (k, 2.5)]),
            },
        )
        out = expect(lambda: sum_blocks(args["x"], args["types"]), bad)
        if out is not None:
            assert float(out.sum()) == 3 * n
    else:
        args, bad = draw_args(
            data.draw,
            {
                "kernel": st.just(jnp.ones((n, 2))),
                "types": st.just((k, 2)),
                "pair": st.just((k - 1, 1)),
            },
            {
                "kernel": st.sampled_from([None, "kernel"]),
                "types": st.sampled_from([(n + 1, 2), (k,), (0, 2), None]),
                "pair": st.sampled_from([(k, 0), (-1, 0), (0,), (0.5, 0), None]),
            },
        )
        expect(lambda: type_pair_block(args["kernel"], args["types"], args["pair"]), bad)


@settings(FUZZ, max_examples=60)
@given(x=st.floats(-30, 88, width=32), big=st.floats(88, 3.3999999521443642e38, width=32))
def test_softplus_is_todays_in_the_normal_range_and_never_overflows(x, big):
    from sgb.genome import softplus

    x32 = jnp.float32(x)
    assert softplus(x32) == jnp.log1p(jnp.exp(x32))  # bit for bit the kernels' former one
    assert np.isfinite(float(softplus(jnp.float32(big))))
    assert float(softplus(jnp.float32(big))) >= float(softplus(x32))


@FUZZ
@given(st.data())
def test_labels_and_evaluation_inputs(data):
    from sgb.classifiers import DenseClassifier
    from sgb.elbo import cross_entropy
    from sgb.supervised import dense_accuracy

    which = data.draw(st.sampled_from(["cross_entropy", "dense_accuracy"]))
    x = jnp.linspace(-1.0, 1.0, 12).reshape(4, 3)
    if which == "cross_entropy":
        args, bad = draw_args(
            data.draw,
            {"labels": st.lists(st.integers(0, 2), min_size=4, max_size=4).map(jnp.array)},
            {
                "labels": st.sampled_from(
                    [
                        jnp.array([0, 1, 3, 0]),
                        jnp.array([-1, 0, 0, 0]),
                        jnp.zeros(4),
                        jnp.zeros(3, int),
                        None,
                    ]
                )
            },
        )
        expect(lambda: cross_entropy(x, args["labels"]), bad)
    else:
        model = DenseClassifier((3,), input_shape=(3,))
        params = model.init(jax.random.key(0), x)
        args, bad = draw_args(
            data.draw,
            {
                "x": st.just(x),
                "y": st.lists(st.integers(0, 2), min_size=4, max_size=4).map(np.array),
            },
            {
                "x": st.sampled_from(
                    [x.at[1, 1].set(jnp.nan), x.at[0, 0].set(jnp.inf), x[:0], None]
                ),
                "y": st.sampled_from(
                    [np.array([0, 1, 3, 0]), np.array([0, -1, 0, 0]), np.zeros(4), np.zeros(3, int)]
                ),
            },
        )
        out = expect(lambda: [dense_accuracy(model, params, args["x"], args["y"])], bad)
        if out is not None:
            assert 0.0 <= out[0] <= 1.0


@settings(FUZZ, max_examples=40)
@given(st.data())
def test_data_loader_arguments(data):
    from sgb import data as datasets

    which = data.draw(st.sampled_from(["digits", "mnist1d", "load"]))
    seeds = st.integers(0, 2**32 - 1)
    bad_seeds = st.one_of(BAD_INTEGERS.filter(lambda v: v != 0), st.just(2**32), st.just(-1))
    if which == "digits":
        args, bad = draw_args(
            data.draw,
            {"seed": seeds, "test_fraction": st.floats(0.05, 0.95)},
            {
                "seed": bad_seeds,
                "test_fraction": st.one_of(st.floats(1, 2), st.floats(-1, 0), BAD_REAL),
            },
        )
        expect(lambda: datasets.digits(**args).x_train, bad)
    elif which == "mnist1d":
        args, bad = draw_args(
            data.draw,
            {"seed": seeds, "num_samples": st.integers(10, 60)},
            {"seed": bad_seeds, "num_samples": st.one_of(BAD_INTEGERS, st.integers(1, 9))},
        )
        expect(lambda: datasets.mnist1d(**args).x_test, bad)
    else:
        args, bad = draw_args(
            data.draw,
            {"name": st.sampled_from(["digits"]), "seed": seeds},
            {"name": st.sampled_from(["imagenet", None, 3]), "seed": bad_seeds},
        )
        expect(lambda: datasets.load(**args).x_test, bad)


@settings(FUZZ, max_examples=40)
@given(st.data())
def test_population_and_ppo_entry_points(data):
    from reach import SPEC, reach_config

    from sgb.rl import ppo
    from sgb.rl.normalizer import Normalizer
    from sgb.rl.population import population_returns

    network = NetworkConfig(hidden=(4,), cell_types=2)
    actor = ppo.initial_params(reach_config(network=network), 0).actor
    good = Normalizer(jnp.asarray(3.0), jnp.zeros(2), jnp.ones(2))
    args, bad = draw_args(
        data.draw,
        {
            "actor_params": st.just(actor),
            "normalizer": st.just(good),
            "n_individuals": st.just(2),
            "episodes": st.just(1),
            "episode_length": st.just(3),
            "seed": st.integers(0, 2**32 - 1),
        },
        {
            "actor_params": st.sampled_from(
                [None, {"w": 1}, jax.tree_util.tree_map(lambda p: p * jnp.nan, actor)]
            ),
            "normalizer": st.sampled_from(
                [
                    None,
                    good._replace(mean=jnp.zeros(3)),
                    good._replace(m2=jnp.full(2, jnp.nan)),
                    good._replace(count=jnp.asarray(-1.0)),
                ]
            ),
            "n_individuals": BAD_INTEGERS,
            "episodes": BAD_INTEGERS,
            "episode_length": BAD_INTEGERS,
            "seed": st.one_of(st.sampled_from([2.5, -1, 2**32, "0", None])),
        },
    )
    expect(lambda: population_returns(SPEC, network, **args), bad)
    if bad is None:
        with pytest.raises(TypeError, match="seed"):
            ppo.initial_params(reach_config(network=network), float(args["seed"]) + 0.5)
