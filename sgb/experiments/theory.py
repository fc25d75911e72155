"""Chapter 3: the Jensen gap on 1-D toy losses and on a trained SGB digits classifier.

``compute(config)`` returns every number the chapter shows; ``run`` writes them
to ``results/theory_cpu.json`` with provenance.
"""

import dataclasses
import functools
import time
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from tqdm.auto import tqdm

from sgb import theory
from sgb.data import digits
from sgb.experiments import check_profile
from sgb.provenance import provenance, results_file, write_results
from sgb.supervised import ClassifierConfig, train_and_evaluate


@dataclasses.dataclass(frozen=True)
class TheoryConfig:
    """What chapter 3 computes.

    Toys: ``starts`` maps each toy loss to its (mu0, sigma0) for Figure 6;
    every toy run takes ``steps`` gradient steps of ``learning_rate`` with
    ``train_samples`` noise draws per step and measures Delta L with
    ``gap_samples`` draws. ``map_mu0``/``map_sigma0``: the grid of starts of the
    non-convex sign map. ``breakdown_mu``/``breakdown_sigma``: where Delta L is
    measured against the second-order prediction.
    Network: ``classifiers`` (SGB MLPs on digits), Delta L over
    ``network_individuals`` sampled individuals at each spread scale of
    ``sigma_scales``; ``hutchinson_probes`` Rademacher probes next to the exact trace.
    """

    steps: int = 100
    learning_rate: float = 0.05
    train_samples: int = 8
    gap_samples: int = 2000
    starts: tuple[tuple[str, float, float], ...] = (
        ("convex", 1.5, 0.6),
        ("concave", 0.3, 0.2),
        ("nonconvex", 0.15, 0.25),
    )
    map_mu0: tuple[float, float, int] = (-1.5, 1.5, 41)
    map_sigma0: tuple[float, float, int] = (0.05, 0.8, 20)
    breakdown_mu: tuple[float, ...] = (0.0, 0.4, 1.0)
    breakdown_sigma: tuple[float, float, int] = (0.02, 1.5, 25)
    classifiers: tuple[ClassifierConfig, ...] = (
        ClassifierConfig(
            hidden=(32,), cell_types=(None, None, None), epochs=20, learning_rate=3e-3
        ),
        ClassifierConfig(hidden=(32,), cell_types=(16, 8, 10), epochs=20, learning_rate=3e-3),
    )
    network_individuals: int = 1000
    sigma_scales: tuple[float, ...] = (0.5, 1.0, 2.0, 4.0, 8.0)
    hutchinson_probes: int = 100
    seed: int = 0


def _smoke_classifier(config: ClassifierConfig) -> ClassifierConfig:
    return dataclasses.replace(config, epochs=5)


PROFILES: dict[str, TheoryConfig] = {
    "smoke": TheoryConfig(
        gap_samples=1000,
        map_mu0=(-1.5, 1.5, 21),
        map_sigma0=(0.05, 0.8, 10),
        breakdown_sigma=(0.02, 1.5, 15),
        classifiers=tuple(_smoke_classifier(c) for c in TheoryConfig().classifiers),
        network_individuals=200,
        hutchinson_probes=30,
    ),
    "cpu": TheoryConfig(),
    "paper": TheoryConfig(
        gap_samples=10_000,
        map_mu0=(-1.5, 1.5, 81),
        map_sigma0=(0.02, 0.8, 50),
        network_individuals=5000,
    ),
}


def _grid(spec: tuple[float, float, int]) -> np.ndarray:
    low, high, n = spec
    return np.linspace(low, high, int(n))


def toy_runs(config: TheoryConfig) -> dict[str, Any]:
    """Train (mu, sigma) on each toy loss from many starts, one vmapped batch per loss.

    Returns ``trajectories`` (Figure 6: the full run from each loss's configured
    start), ``sign_scan`` (Delta L at the start and end of training over a
    line of mu0, sigma0 as configured, for every loss) and ``sign_map`` (the
    non-convex loss over a (mu0, sigma0) grid).
    """
    line = _grid(config.map_mu0)
    grid_mu0, grid_sigma0 = np.meshgrid(line, _grid(config.map_sigma0), indexing="ij")
    trajectories, scan, sign_map = {}, {}, {}
    for i, (name, mu0, sigma0) in enumerate(config.starts):
        mus = [np.array([mu0]), line]
        sigmas = [np.array([sigma0]), np.full_like(line, sigma0)]
        if name == "nonconvex":
            mus.append(grid_mu0.ravel())
            sigmas.append(grid_sigma0.ravel())
        runs = _train_many(config, name, np.concatenate(mus), np.concatenate(sigmas), seed=i)
        trajectories[name] = {"mu0": mu0, "sigma0": sigma0, **{k: v[0] for k, v in runs.items()}}
        on_line = {k: v[1 : 1 + line.size] for k, v in runs.items()}
        scan[name] = {
            "mu0": line,
            "sigma0": sigma0,
            **{f"{k}_start": v[:, 0] for k, v in on_line.items()},
            **{f"{k}_end": v[:, -1] for k, v in on_line.items()},
        }
        if name == "nonconvex":
            on_grid = {k: v[1 + line.size :, -1].reshape(grid_mu0.shape) for k, v in runs.items()}
            sign_map = {
                "mu0": line,
                "sigma0": _grid(config.map_sigma0),
                "gap_start": runs["gap"][1 + line.size :, 0].reshape(grid_mu0.shape),
                **{f"{k}_end": v for k, v in on_grid.items()},
            }
    return {"trajectories": trajectories, "sign_scan": scan, "sign_map": sign_map}


def _train_many(
    config: TheoryConfig, name: str, mu0: np.ndarray, sigma0: np.ndarray, seed: int
) -> dict[str, np.ndarray]:
    """``theory.train_toy`` vmapped over starts: mu0, sigma0 (B,) -> fields (B, steps + 1)."""
    loss = theory.toy_loss(name)
    keys = jax.random.split(jax.random.key(config.seed + seed), mu0.shape[0])

    @jax.jit
    @jax.vmap
    def run(m, s, k):
        return theory.train_toy(
            loss,
            m,
            s,
            k,
            steps=config.steps,
            learning_rate=config.learning_rate,
            num_samples=config.train_samples,
            gap_samples=config.gap_samples,
        )

    trajectory = run(jnp.asarray(mu0, jnp.float32), jnp.asarray(sigma0, jnp.float32), keys)
    return {k: np.asarray(v) for k, v in trajectory._asdict().items()}


def breakdown(config: TheoryConfig) -> dict[str, Any]:
    """Non-convex loss at fixed mu: measured Delta L, its second-order prediction, and the
    exact value sigma^2 (3 mu^2 - 1)/2 + 3 sigma^4/4, against sigma."""
    sigmas = _grid(config.breakdown_sigma)
    loss = theory.nonconvex_loss
    rows = []
    key = jax.random.key(config.seed + 200)
    measure = jax.jit(
        jax.vmap(
            lambda m, s, k: theory.jensen_gap(loss, m, s, k, config.gap_samples),
            in_axes=(None, 0, 0),
        )
    )
    for mu in config.breakdown_mu:
        key, sub = jax.random.split(key)
        gap = measure(
            jnp.float32(mu), jnp.asarray(sigmas, jnp.float32), jax.random.split(sub, len(sigmas))
        )
        curvature = float(jax.grad(jax.grad(loss))(jnp.float32(mu)))
        rows.append(
            {
                "mu": mu,
                "curvature": curvature,
                "measured": np.asarray(gap.gap),
                "stderr": np.asarray(gap.stderr),
                "predicted": 0.5 * curvature * sigmas**2,
                "exact": sigmas**2 * (3 * mu**2 - 1) / 2 + 3 * sigmas**4 / 4,
            }
        )
    return {"sigma": sigmas, "rows": rows}


def network_gap(config: TheoryConfig, progress: bool = True) -> list[dict[str, Any]]:
    """Delta L of trained SGB digits classifiers, per synapse, with the Hessian-trace prediction.

    Cross-entropy and error rate on the training set (the loss the theorems
    are about) and error rate on the test set; spreads scaled by each of
    ``sigma_scales``.
    """
    data = digits(config.seed)
    out = []
    for classifier in tqdm(config.classifiers, desc="classifiers", disable=not progress):
        trained = train_and_evaluate(classifier, data, progress=False)
        view = theory.synapse_view(trained["model"], trained["params"], data.x_train)
        losses = {
            "train_cross_entropy": theory.network_loss(
                view, data.x_train, data.y_train, "cross_entropy"
            ),
            "train_error_rate": theory.network_loss(view, data.x_train, data.y_train, "error_rate"),
            "test_error_rate": theory.network_loss(view, data.x_test, data.y_test, "error_rate"),
        }
        key = jax.random.key(config.seed + 300)
        # the prediction is quadratic in sigma: one exact Hessian diagonal, rescaled by scale^2
        diagonal = theory.hessian_diagonal(losses["train_cross_entropy"], view.mean)
        per_layer = {
            name: 0.5 * float(jnp.sum(view.sigma[name] ** 2 * diagonal[name])) for name in diagonal
        }
        predicted = sum(per_layer.values())
        hutchinson = theory.second_order_trace(
            losses["train_cross_entropy"],
            view.mean,
            view.sigma,
            jax.random.fold_in(key, 1),
            config.hutchinson_probes,
        )
        measures = {
            name: jax.jit(
                functools.partial(theory.jensen_gap, lf, view.mean),
                static_argnames="num_samples",
            )
            for name, lf in losses.items()
        }
        gap_key = jax.random.fold_in(key, 2)
        scales = []
        for scale in config.sigma_scales:
            sigma = jax.tree_util.tree_map(lambda s, c=scale: c * s, view.sigma)
            gaps = {
                name: measure(sigma, gap_key, num_samples=config.network_individuals)._asdict()
                for name, measure in measures.items()
            }
            scales.append({"scale": scale, "predicted": scale**2 * predicted, **gaps})
        layers = []
        for name in view.sigma:
            only = {k: v if k == name else jnp.zeros_like(v) for k, v in view.sigma.items()}
            gap = measures["train_cross_entropy"](
                only, gap_key, num_samples=config.network_individuals
            )
            layers.append({"layer": name, "predicted": per_layer[name], **gap._asdict()})
        sigmas = np.concatenate([np.ravel(s) for s in jax.tree_util.tree_leaves(view.sigma)])
        out.append(
            {
                "classifier": classifier,
                "cell_types": classifier.cell_types,
                "synapses": int(sigmas.size),
                "sigma_mean": float(sigmas.mean()),
                "sigma_min": float(sigmas.min()),
                "sigma_max": float(sigmas.max()),
                "accuracy": trained["accuracy"],
                "hutchinson": hutchinson._asdict(),
                "hutchinson_probes": config.hutchinson_probes,
                "scales": scales,
                "layers": layers,
            }
        )
    return out


def compute(config: TheoryConfig, progress: bool = True) -> dict[str, Any]:
    """Every number of chapter 3 (JSON-able after ``sgb.provenance``'s conversion)."""
    results = toy_runs(config)
    results["breakdown"] = breakdown(config)
    results["network"] = network_gap(config, progress)
    return results


def run(profile: str, out_dir: Path, **options: Any) -> Path:
    """Compute chapter 3's numbers at ``profile`` and write ``out_dir/theory_<profile>.json``."""
    check_profile(profile)
    if options:
        raise ValueError(f"theory takes no options, got {sorted(options)}")
    config = PROFILES[profile]
    path = results_file(out_dir, "theory", profile)
    start = time.time()
    results = compute(config)
    record = provenance(config, profile, [config.seed], time.time() - start)
    return write_results(path, results, record)


def network_summary(results: dict[str, Any]) -> tuple[list[dict], list[dict]]:
    """Rows for the chapter's tables, from ``compute`` output or a results file's ``results``:
    per network at the trained spread (scale 1), and per noisy layer."""
    overall, layers = [], []
    for net in results["network"]:
        types = "/".join("n" if k is None else str(k) for k in net["cell_types"])
        base = next(s for s in net["scales"] if s["scale"] == 1.0)
        overall.append(
            {
                "cell types": types,
                "mean sigma": net["sigma_mean"],
                "mean-network test accuracy": net["accuracy"]["mean_network"],
                "Delta L cross-entropy (train)": float(base["train_cross_entropy"]["gap"]),
                "+- SE": float(base["train_cross_entropy"]["stderr"]),
                "exact 1/2 tr(H diag sigma^2)": float(base["predicted"]),
                f"Hutchinson, {net['hutchinson_probes']} probes": float(net["hutchinson"]["value"]),
                "+- SE ": float(net["hutchinson"]["stderr"]),
                "Delta train error (pp)": 100 * float(base["train_error_rate"]["gap"]),
                "Delta test error (pp)": 100 * float(base["test_error_rate"]["gap"]),
                "+- SE  ": 100 * float(base["test_error_rate"]["stderr"]),
            }
        )
        for layer in net["layers"]:
            layers.append(
                {
                    "cell types": types,
                    "noisy layer": layer["layer"],
                    "measured Delta L (CE)": float(layer["gap"]),
                    "+- SE": float(layer["stderr"]),
                    "1/2 sum H_ss sigma_s^2": float(layer["predicted"]),
                    "measured / predicted": float(layer["gap"]) / float(layer["predicted"]),
                }
            )
    return overall, layers
