"""Nothing escapes as a library traceback and no blown-up run is reported: damaged files
are a ``CorruptFile`` naming them, finite blow-ups stop training, widths are checked,
spreads never overflow, and inputs are checked at the door."""

import gzip
import json
import re
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import serialization
from reach import SPEC, reach_config

from sgb import data, divergence, resume, theory
from sgb.__main__ import main
from sgb.data import digits
from sgb.dgb import DGBConfig
from sgb.divergence import BLOWUP_FACTOR, FIT_BOUND, TrainingDiverged
from sgb.genome import individual_kernel, layer_kl, softplus
from sgb.priors import GaussianPrior
from sgb.provenance import read_results
from sgb.rl import checkpoints, ppo
from sgb.rl.agent import MLP, NetworkConfig
from sgb.rl.normalizer import Normalizer, init_normalizer
from sgb.rl.population import population_returns
from sgb.rl.runs import finished_run
from sgb.supervised import (
    ClassifierConfig,
    DenseConfig,
    dense_accuracy,
    train_and_evaluate,
)
from sgb.validation import CorruptFile

ROOT = Path(__file__).resolve().parents[1]


def _small_digits():
    ds = digits(seed=0)
    return ds._replace(x_train=ds.x_train[:256], y_train=ds.y_train[:256])


# ------------------------------------------------------------------------ damaged files


def _damage(path: Path, how: str) -> None:
    """Damage the file ``path`` in one of the ways a disk, a copy or a crash does."""
    good = path.read_bytes()
    if how == "flipped byte":
        flipped = bytearray(good)
        flipped[len(good) // 2] ^= 0x10
        path.write_bytes(bytes(flipped))
    elif how == "truncated":
        path.write_bytes(good[: len(good) // 3])
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "directory":
        path.unlink()
        path.mkdir()
    else:
        raise AssertionError(how)


DAMAGES = ["flipped byte", "truncated", "empty", "directory"]


@pytest.mark.parametrize("how", [*DAMAGES, "no progress", "a progress entry missing"])
def test_a_damaged_training_state_is_a_corrupt_file_that_names_it(tmp_path, how):
    state = {"w": jnp.arange(200.0), "key": jax.random.key(3)}
    path = tmp_path / "run.state.npz"
    resume.save(path, state, {"seed": 0}, {"chunks": 1, "records": []})
    if how == "no progress":
        np.savez(path, meta=np.array(json.dumps({"run": {"seed": 0}})), leaf_0=np.arange(2.0))
    elif how == "a progress entry missing":
        resume.save(path, state, {"seed": 0}, {"records": []})
    else:
        _damage(path, how)
    needs = {"progress_keys": ("chunks",)} if how == "a progress entry missing" else {}
    with pytest.raises(CorruptFile, match=f"training state {re.escape(str(path))} .*delete it"):
        resume.load(path, state, {"seed": 0}, **needs)


def test_the_command_line_reports_a_damaged_state_file_without_a_traceback(tmp_path, capsys):
    state_file = tmp_path / "dgb_budget_digits_smoke.state.npz"
    resume.save(state_file, {"w": jnp.arange(500.0)}, {"seed": 0}, {"records": []})
    _damage(state_file, "flipped byte")
    assert main(["reproduce", "dgb_budget", "--out-dir", str(tmp_path)]) == 2
    error = capsys.readouterr().err
    assert str(state_file) in error and "delete it" in error and "Traceback" not in error


def _write_fashion(directory: Path, monkeypatch) -> dict:
    """Small Fashion-MNIST files in ``directory``; the expected MD5s become theirs."""
    rng = np.random.default_rng(4)
    directory.mkdir(parents=True, exist_ok=True)
    files, arrays = {}, {}
    for split, n in (("train", 6), ("test", 3)):
        for part, array in (
            ("images", rng.integers(0, 256, (n, 28, 28))),
            ("labels", np.arange(n)),
        ):
            name = f"{split}_{part}"
            raw = bytes([0, 0, 8, array.ndim]) + b"".join(k.to_bytes(4, "big") for k in array.shape)
            raw += array.astype(np.uint8).tobytes()
            remote, _ = data.FASHION_MNIST_FILES[name]
            gz = gzip.compress(raw)
            (directory / remote.name).write_bytes(gz)
            md5s = (data.hashlib.md5(gz).hexdigest(), data.hashlib.md5(raw).hexdigest())
            files[name] = (remote._replace(md5=md5s[0]), md5s[1])
            arrays[name] = array
    monkeypatch.setattr(data, "FASHION_MNIST_FILES", files)
    return arrays


@pytest.mark.parametrize("how", [*DAMAGES, "not gzip"])
def test_a_damaged_dataset_copy_falls_through_to_a_good_one(tmp_path, monkeypatch, how):
    system, cache = tmp_path / "system", tmp_path / "cache"
    arrays = _write_fashion(system, monkeypatch)
    good = {p.name: p.read_bytes() for p in system.iterdir()}
    cache.mkdir()
    for name, content in good.items():
        (cache / name).write_bytes(content)
    monkeypatch.setattr(data, "FASHION_MNIST_SYSTEM_DIR", system)
    downloads = []

    def download(url, path):
        downloads.append(url)
        Path(path).write_bytes(good[Path(path).name])

    monkeypatch.setattr(data, "download_url", download)
    names = [remote.name for remote, _ in data.FASHION_MNIST_FILES.values()]
    for name in names:  # Debian's copy is damaged: the cache's good one is used
        if how == "not gzip":
            (system / name).write_bytes(b"\x00" * 64)
        else:
            _damage(system / name, how)
    ds = data.fashion_mnist(directory=cache)
    np.testing.assert_array_equal(ds.y_test, arrays["test_labels"])
    assert downloads == []
    if how == "directory":  # a directory in the cache is never deleted for the user: named
        _damage(cache / names[0], how)
        with pytest.raises(CorruptFile, match=re.escape(f"{cache / names[0]} is a directory")):
            data.fashion_mnist(directory=cache)
        return
    for name in names:  # now the cache's copy is damaged too: it is downloaded anew
        if how == "not gzip":
            (cache / name).write_bytes(b"\x00" * 64)
        else:
            _damage(cache / name, how)
    ds = data.fashion_mnist(directory=cache)
    np.testing.assert_array_equal(ds.y_train, arrays["train_labels"])
    assert len(downloads) == len(names)


def _result(config=None, seed=0):
    """A PPO result on the Reach environment, untrained (its initial parameters)."""
    config = config or reach_config(4)
    params = ppo.initial_params(config, seed=seed)
    norm = init_normalizer(2)._replace(count=jnp.asarray(5.0), m2=jnp.ones(2))
    return ppo.TrainResult(config, params, norm, [100, 200], [-20.5, -18.25], 1e3, 2.0)


def test_a_checkpoint_is_hashed_whole_and_refused_when_damaged_or_not_finite(tmp_path):
    result = _result()
    path = checkpoints.save(tmp_path / "agent.msgpack", result, {"git_commit": "abc"})
    sidecar = path.with_suffix(".json")
    assert checkpoints.load(path)[3]["eval_returns"] == result.eval_returns
    good_msgpack, good_sidecar = path.read_bytes(), sidecar.read_text()

    # a read-back field edited: the sidecar no longer matches its own hash
    meta = json.loads(good_sidecar)
    meta["eval_returns"][-1] = 9999.0
    sidecar.write_text(json.dumps(meta))
    with pytest.raises(CorruptFile, match=f"{sidecar} does not match the SHA-256"):
        checkpoints.load(path)
    # nan injected into the parameters, both hashes recomputed: refused as not finite
    state = serialization.msgpack_restore(good_msgpack)
    bias = np.array(state["actor"]["params"]["hidden_0"]["bias"])
    bias[0] = np.nan
    state["actor"]["params"]["hidden_0"]["bias"] = bias
    poisoned = serialization.msgpack_serialize(state)
    path.write_bytes(poisoned)
    meta = json.loads(good_sidecar)
    meta["sha256"] = checkpoints.hashlib.sha256(poisoned).hexdigest()
    meta[checkpoints.SIDECAR_HASH] = checkpoints.sidecar_hash(meta)
    sidecar.write_text(json.dumps(meta))
    with pytest.raises(CorruptFile, match=f"{path} has arrays that are not finite.*hidden_0"):
        checkpoints.load(path)
    # each damage of either file, named
    good = {path: good_msgpack, sidecar: good_sidecar.encode()}
    for damaged in good:
        for how in DAMAGES:
            for file, content in good.items():
                if file.is_dir():
                    file.rmdir()
                file.write_bytes(content)
            _damage(damaged, how)
            with pytest.raises(CorruptFile, match=re.escape(str(damaged))):
                checkpoints.load(path)
    # a sidecar of the earlier format, written before sidecars were hashed, still loads
    for file, content in good.items():
        if file.is_dir():
            file.rmdir()
        file.write_bytes(content)
    earlier = json.loads(good_sidecar)
    del earlier[checkpoints.SIDECAR_HASH]
    sidecar.write_text(json.dumps(earlier, indent=1))
    assert checkpoints.load(path)[3]["eval_returns"] == result.eval_returns


def test_committed_checkpoints_of_the_earlier_formats_still_load():
    directory = ROOT / "results" / "rl" / "checkpoints"
    committed = sorted(directory.glob("halfcheetah_*.msgpack"))[0]
    meta = json.loads(committed.with_suffix(".json").read_text())
    assert "regime" not in meta["config"]  # written before the authors' regime existed
    assert checkpoints.load(committed)[3]["eval_returns"] == meta["eval_returns"]
    # the earliest: one all_layers_sgb switch for the input typing and the SGB output layer
    oldest = json.loads(sorted(directory.glob("ant_*_authors_*.json"))[0].read_text())
    assert oldest["config"]["network"]["all_layers_sgb"] is True
    network = checkpoints.config_from_dict(oldest["config"]).network
    assert network.typed_inputs and network.sgb_output


def test_a_save_interrupted_between_the_two_writes_keeps_the_old_checkpoint(tmp_path, monkeypatch):
    config, other = reach_config(4), reach_config(4, eval_individuals=2)
    result = _result(config)
    path = tmp_path / "agent.msgpack"
    checkpoints.save(path, _result(other, seed=1))  # another run
    real, writes = checkpoints._write_synced, []

    def crash_at_the_second(file, content):
        writes.append(file)
        if len(writes) == 2:
            raise KeyboardInterrupt  # interrupted between the two writes
        return real(file, content)

    monkeypatch.setattr(checkpoints, "_write_synced", crash_at_the_second)
    with pytest.raises(KeyboardInterrupt):
        checkpoints.save(path, result)
    monkeypatch.setattr(checkpoints, "_write_synced", real)
    assert checkpoints.load(path)[0] == other  # the old checkpoint, whole
    assert finished_run(path, config) is None  # not finished: the sweep trains it again
    checkpoints.save(path, result)
    assert finished_run(path, config)["eval_returns"] == result.eval_returns


def test_a_finished_state_file_with_nan_parameters_is_refused(tmp_path):
    config = reach_config(None, total_steps=2048, num_evals=1)
    ts = ppo.init_state(config, seed=0)
    ts = ts._replace(params=jax.tree_util.tree_map(lambda p: p * np.nan, ts.params))
    done = {"chunks": 1, "eval_steps": [2048], "eval_returns": [-3.0], "timed_steps": 2048}
    done |= {"timed_s": 1.0, "wall_time_s": 1.0}
    state_file = tmp_path / "run.state.npz"
    resume.save(state_file, ts, {"config": repr(config), "seed": 0}, done)
    with pytest.raises(CorruptFile, match=f"{state_file} holds state.*nan"):
        ppo.train(config, seed=0, progress=False, state_file=state_file)


# ------------------------------------------------------------------------ divergence


@pytest.mark.parametrize(
    ("config", "message"),
    [
        (DenseConfig(hidden=(16,), learning_rate=1e8, epochs=2), r"loss = .* at step \d+ \(beyond"),
        (
            DGBConfig(
                hidden=(16,),
                gnet_width=4,
                learning_rate=1e6,
                rounds=4,
                pnet_steps=4,
                batch_size=64,
                gnet_steps=5,
                validation_size=32,
            ),
            r"p-net loss = .* at step \d+ \(beyond .*learning_rate",
        ),
        (
            DGBConfig(
                hidden=(16,),
                gnet_width=4,
                gnet_learning_rate=1e6,
                rounds=4,
                pnet_steps=4,
                batch_size=64,
                gnet_steps=5,
                validation_size=32,
            ),
            r"fit error after round 1 = .* at step 4 .*gnet_learning_rate",
        ),
        (
            ClassifierConfig(hidden=(16,), learning_rate=1e4, epochs=2, batch_size=64),
            r"at step \d+ \(beyond.*likely cause: rho overflow",
        ),
    ],
)
def test_finite_blow_ups_stop_training_and_name_the_step_and_cause(config, message):
    with pytest.raises(TrainingDiverged, match=message):
        train_and_evaluate(config, _small_digits(), progress=False)


def test_the_toy_loop_runs_under_the_guard():
    with pytest.raises(TrainingDiverged, match=r"the toy's mu = .* at step \d+"):
        theory.train_toy(theory.convex_loss, 1.0, 0.5, jax.random.key(0), learning_rate=100.0)
    batch = jax.vmap(
        lambda m: theory.train_toy(theory.convex_loss, m, 0.5, jax.random.key(0), steps=5)
    )(jnp.array([1.0, 2.0]))
    assert theory.guard_toy(batch) is batch  # vmapped, it is checked by its caller
    with pytest.raises(TrainingDiverged, match="at step 2"):
        theory.guard_toy(batch._replace(gap=batch.gap.at[1, 2].set(jnp.nan)))


def test_the_stop_message_names_the_likely_cause():
    bad_obs = Normalizer(jnp.ones(()), jnp.array([0.0, jnp.nan]), jnp.ones(2))
    holder = {"ts": type("TS", (), {"normalizer": bad_obs, "params": {}})()}
    with pytest.raises(TrainingDiverged, match="PPO loss = nan .*nan or inf in the data"):
        ppo._guard(holder).loss(float("nan"), 2048)
    cases = {
        "an empty set": {"data": {"x": np.zeros((0, 3))}},
        "labels out of range": {"labels": np.array([0, 10]), "num_classes": 10},
        "rho overflow": {"params": {"genome": {"rho": np.array([100.0])}}},
        "learning rate": {"params": {"genome": {"rho": np.array([-5.0, np.nan])}}},
    }
    for cause, checked in cases.items():
        assert cause in divergence.likely_cause(**checked)


def test_a_network_at_chance_is_flagged_in_its_result():
    ds = _small_digits()
    noise = ds._replace(y_train=np.random.default_rng(0).permutation(ds.y_train))
    config = DenseConfig(hidden=(16,), epochs=3)
    assert train_and_evaluate(config, ds, progress=False)["at_chance"] is False
    shuffled = train_and_evaluate(config, noise, progress=False)
    assert shuffled["at_chance"] is True and shuffled["chance"] == pytest.approx(0.1, abs=0.01)


def test_the_guard_thresholds_are_far_from_every_committed_run():
    # a loss can only trip the guard beyond BLOWUP_FACTOR (its start at least 1)
    losses, fits = [], []
    for path in sorted((ROOT / "results").glob("*_cpu.json")):
        results = read_results(path)["results"]
        for record in results.get("records", []) + results.get("ablation_records", []):
            losses += [record["final_loss"]] if "final_loss" in record else []
            fits += [record["fit_mse"]] if record.get("fit_mse") is not None else []
    assert len(losses) > 40 and len(fits) > 20
    assert max(map(abs, losses)) < BLOWUP_FACTOR / 10 and max(fits) < FIT_BOUND / 1e4
    trajectories = read_results(ROOT / "results" / "theory_cpu.json")["results"]["trajectories"]
    for run in trajectories.values():
        fields = {k: np.array([run[k]]) for k in theory.Trajectory._fields}
        theory.guard_toy(theory.Trajectory(**fields))


# ------------------------------------------------------------------------ widths


def test_every_model_the_package_builds_checks_its_input_width():
    ds = _small_digits()  # 64 features
    wider = jnp.ones((2, 65))
    sgb = ClassifierConfig(hidden=(16,), cell_types=(16, 8, 10), epochs=1, eval_individuals=2)
    for config, message in (
        (sgb, "in_features=64 inputs, got 65"),  # a type table fits any width: it ran on
        (DenseConfig(hidden=(16,), epochs=1), r"shape \(64,\), got an array of shape \(2, 65\)"),
    ):
        out = train_and_evaluate(config, ds, progress=False)
        with pytest.raises(ValueError, match=message):
            out["model"].apply(out["params"], wider, rngs={"sample": jax.random.key(2)})
    actor = MLP(NetworkConfig(hidden=(8,), cell_types=2, typed_inputs=True), 2, 64)
    actor_params = actor.init(
        {"params": jax.random.key(0), "sample": jax.random.key(1)}, wider[:, 1:]
    )
    with pytest.raises(ValueError, match="in_features=64 inputs, got 65"):
        actor.apply(actor_params, wider, rngs={"sample": jax.random.key(2)})


# ------------------------------------------------------------------------ softplus


def test_one_softplus_keeps_todays_values_and_never_overflows():
    rho = jnp.linspace(-30.0, 88.0, 20_001, dtype=jnp.float32)
    np.testing.assert_array_equal(softplus(rho), jnp.log1p(jnp.exp(rho)))  # the former kernels'
    np.testing.assert_allclose(softplus(rho), jax.nn.softplus(rho), rtol=2e-7)  # the former KL's
    negative = rho[rho <= 0]
    np.testing.assert_array_equal(softplus(negative), jax.nn.softplus(negative))
    huge = jnp.array([89.0, 100.0, 1e4, 1e30])
    assert jnp.all(jnp.isfinite(softplus(huge)))
    np.testing.assert_allclose(jax.vmap(jax.grad(softplus))(huge), 1.0)
    mu, noise = jnp.zeros((2, 3)), jax.random.normal(jax.random.key(0), (4, 6))

    def loss(mu, rho):
        return jnp.sum(individual_kernel(mu, rho, noise) ** 2)

    big = jnp.full((2, 3), 100.0)  # log1p(exp(100)) was inf
    assert jnp.all(jnp.isfinite(individual_kernel(mu, big, noise)))
    assert all(jnp.all(jnp.isfinite(g)) for g in jax.grad(loss, argnums=(0, 1))(mu, big))
    kl = layer_kl(GaussianPrior(0.1), mu, softplus(big), (4, 6), "synapse", jax.random.key(0))
    assert jnp.isfinite(kl)


# ------------------------------------------------------------------------ inputs


def test_evaluation_and_entry_points_check_their_inputs():
    ds = _small_digits()
    out = train_and_evaluate(DenseConfig(hidden=(8,), epochs=1), ds, progress=False)
    model, params = out["model"], out["params"]
    x_nan = ds.x_test.copy()
    x_nan[3, 5] = np.nan
    with pytest.raises(ValueError, match="x holds nan"):
        dense_accuracy(model, params, x_nan, ds.y_test)
    y_bad = ds.y_test.copy()
    y_bad[0] = -1
    with pytest.raises(ValueError, match="y must be >= 0"):
        dense_accuracy(model, params, ds.x_test, y_bad)
    with pytest.raises(ValueError, match=r"y must lie in \[0, 10\)"):
        dense_accuracy(model, params, ds.x_test, np.where(y_bad < 0, 10, y_bad))
    with pytest.raises(ValueError, match="y_train must lie in"):
        train_and_evaluate(DenseConfig(hidden=(8,)), ds._replace(y_train=ds.y_train + 1))
    with pytest.raises(ValueError, match="x_train is empty"):
        train_and_evaluate(DenseConfig(hidden=(8,)), ds._replace(x_train=ds.x_train[:0]))
    for call in (
        lambda: data.load("digits", seed=2.5),
        lambda: ppo.initial_params(reach_config(), 2.5),
    ):
        with pytest.raises(TypeError, match="seed must be an integer"):
            call()
    network = NetworkConfig(hidden=(8,))
    params = ppo.initial_params(reach_config(network=network), 0).actor
    with pytest.raises(ValueError, match=r"normalizer.mean must have shape \(2,\)"):
        population_returns(SPEC, network, params, init_normalizer(3), 2, 1, 4)
    with pytest.raises(ValueError, match="actor_params.*nan"):
        nan_params = jax.tree_util.tree_map(lambda p: p * np.nan, params)
        population_returns(SPEC, network, nan_params, init_normalizer(2), 2, 1, 4)
