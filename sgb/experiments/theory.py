"""Chapter 3: the Jensen gap on 1-D toy losses and on a trained SGB digits classifier, and
where the ELBO's spreads settle (on a 1-D toy and on the digits classifiers).

``compute(config)`` returns every number the chapter shows; ``run`` writes them
to ``results/theory_cpu.json`` with provenance.
"""

import dataclasses
import functools
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from tqdm.auto import tqdm

from sgb import stats, theory
from sgb.claims import Row, judge
from sgb.data import Dataset, digits
from sgb.genome import softplus
from sgb.prose import NOT_RUN, Card
from sgb.provenance import jsonable
from sgb.recording import start
from sgb.results import Records
from sgb.schemas import (
    Accuracy,
    Correlation,
    Count,
    Each,
    Finite,
    List,
    NonNegative,
    Positive,
    Record,
    ResultsFile,
    Steps,
)
from sgb.supervised import DIGITS_CLASSIFIERS, ClassifierConfig, train_and_evaluate


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
    The ELBO's spread: on the convex toy, ``elbo_steps`` steps of plain gradient
    descent of ``elbo_learning_rate`` from ``elbo_start`` for each KL weight of
    ``elbo_kl_weights`` (prior N(0, ``elbo_prior_sigma``^2)), in both parameterisations,
    kept every ``elbo_record_every`` steps. Every classifier's learned spreads against
    the fixed point c / (H + c lambda), as trained and once more trained for each of
    ``settle_epochs``; H at the trained means and averaged over
    ``population_hessians`` sampled individuals.
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
    classifiers: tuple[ClassifierConfig, ...] = DIGITS_CLASSIFIERS
    network_individuals: int = 1000
    sigma_scales: tuple[float, ...] = (0.5, 1.0, 2.0, 4.0, 8.0)
    hutchinson_probes: int = 100
    elbo_kl_weights: tuple[float, ...] = (0.0, 0.01, 0.05, 0.2)
    elbo_prior_sigma: float = 1.0
    elbo_start: tuple[float, float] = (1.5, 0.6)
    elbo_steps: int = 3000
    elbo_learning_rate: float = 0.1
    elbo_record_every: int = 10
    settle_epochs: tuple[int, ...] = (300,)
    population_hessians: int = 8
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
        # no settling runs and one sampled Hessian: the book shows the committed cpu
        # fixed points, and each exact Hessian diagonal costs P = 2,368 Hessian-vector products
        settle_epochs=(),
        population_hessians=1,
    ),
    "cpu": TheoryConfig(),
    "paper": TheoryConfig(
        gap_samples=10_000,
        map_mu0=(-1.5, 1.5, 81),
        map_sigma0=(0.02, 0.8, 50),
        network_individuals=5000,
        settle_epochs=(300, 1000),
        population_hessians=32,
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
    theory.guard_toy(trajectory)  # vmapped and jitted, train_toy cannot check them itself
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
        fixed_point = fixed_point_record(config, classifier, data, trained, diagonal)
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
                "fixed_point": fixed_point,
            }
        )
    return out


def _compact(x) -> np.ndarray:
    """A flat float64 copy rounded to 6 significant digits, so the results file stays small."""
    return np.asarray([float(f"{v:.6g}") for v in np.ravel(np.asarray(x, dtype=float))])


def fixed_point_summary(sigma2: np.ndarray, predicted: np.ndarray) -> dict[str, float]:
    """How close learned sigma^2 lies to the predicted c / (H + c lambda), over type pairs.

    ``median_ratio``: median of sigma^2 / predicted; ``ratio_q10``/``ratio_q90``: its
    10th and 90th percentiles; ``log_correlation``: Pearson correlation of log sigma^2
    and log predicted; ``within_2x``: fraction of pairs whose ratio lies in [1/2, 2].
    Pairs without a finite positive prediction are left out (``pairs`` counts the rest).
    """
    sigma2, predicted = np.ravel(sigma2), np.ravel(predicted)
    keep = np.isfinite(predicted) & (predicted > 0)
    ratio = sigma2[keep] / predicted[keep]
    log_s, log_p = np.log(sigma2[keep]), np.log(predicted[keep])
    spread = log_s.std() > 0 and log_p.std() > 0
    return {
        "pairs": int(keep.sum()),
        "median_ratio": float(np.median(ratio)),
        "ratio_q10": float(np.quantile(ratio, 0.1)),
        "ratio_q90": float(np.quantile(ratio, 0.9)),
        "log_correlation": float(np.corrcoef(log_s, log_p)[0, 1]) if spread else float("nan"),
        "within_2x": float(np.mean((ratio >= 0.5) & (ratio <= 2.0))),
    }


def fixed_point_record(
    config: TheoryConfig,
    classifier: ClassifierConfig,
    data: Dataset,
    trained: dict[str, Any],
    diagonal: dict | None = None,
) -> dict[str, Any]:
    """A trained classifier's learned spreads per type pair against c / (H + c lambda).

    H: the diagonal of the Hessian of the mean training cross-entropy (nats per example
    per weight^2, the data term of the ELBO the book trains, whose KL weight is
    c = kl_scale / n_train), summed over each type pair's synapses and divided by the
    KL's count of the pair (``theory.genome_fixed_point``); once at the trained means
    (``diagonal`` when given) and once averaged over ``config.population_hessians``
    sampled individuals. Per layer, flat arrays over type pairs: ``sigma2``, ``count``,
    ``curvature`` and ``curvature_population``; the predictions follow from them with
    ``theory.elbo_fixed_point``. ``summary``: ``fixed_point_summary`` over all pairs.
    """
    model, params = trained["model"], trained["params"]
    view = theory.synapse_view(model, params, data.x_train)
    loss = theory.network_loss(view, data.x_train, data.y_train, "cross_entropy")
    if diagonal is None:
        diagonal = theory.hessian_diagonal(loss, view.mean)
    population = theory.population_hessian_diagonal(
        loss,
        view.mean,
        view.sigma,
        jax.random.key(config.seed + 400),
        config.population_hessians,
    )
    kl_weight = classifier.kl_scale / len(data.x_train)
    prior_sigma = float(classifier.prior.sigma)
    at_mean = theory.genome_fixed_point(model, params, diagonal, kl_weight)
    averaged = theory.genome_fixed_point(model, params, population, kl_weight)
    layers = {
        name: {
            "sigma2": _compact(at_mean[name].sigma2),
            "count": np.ravel(np.asarray(at_mean[name].count, dtype=int)),
            "curvature": _compact(at_mean[name].curvature),
            "curvature_population": _compact(averaged[name].curvature),
        }
        for name in at_mean
    }
    gather = lambda fps, field: np.concatenate(  # noqa: E731
        [np.ravel(getattr(fp, field)) for fp in fps.values()]
    )
    return {
        "epochs": classifier.epochs,
        "kl_weight": kl_weight,
        "prior_sigma": prior_sigma,
        "sigma2_init": float(softplus(classifier.rho_init)) ** 2,
        "population_hessians": config.population_hessians,
        "accuracy": {
            "mean_network": trained["accuracy"]["mean_network"],
            "population_average": trained["accuracy"]["population_average"],
        },
        "layers": layers,
        "summary": {
            "at_mean": fixed_point_summary(gather(at_mean, "sigma2"), gather(at_mean, "predicted")),
            "population": fixed_point_summary(
                gather(averaged, "sigma2"), gather(averaged, "predicted")
            ),
        },
    }


def fixed_points(
    config: TheoryConfig, network: list[dict[str, Any]], progress: bool = True
) -> list[dict[str, Any]]:
    """Per classifier, its spreads against the fixed point: as trained for the chapter
    (the record ``network_gap`` kept, moved out of ``network``) and trained again for
    each of ``settle_epochs``."""
    data = digits(config.seed)
    out = []
    for classifier, net in zip(config.classifiers, network, strict=True):
        runs = [net.pop("fixed_point")]
        # no bar where there is nothing to settle (smoke): an empty bar says nothing
        shown = progress and bool(config.settle_epochs)
        for epochs in tqdm(config.settle_epochs, desc="settling", disable=not shown):
            longer = dataclasses.replace(classifier, epochs=epochs)
            trained = train_and_evaluate(longer, data, progress=False)
            runs.append(fixed_point_record(config, longer, data, trained))
        out.append({"cell_types": classifier.cell_types, "runs": runs})
    return out


def elbo_toy(config: TheoryConfig) -> dict[str, Any]:
    """The ELBO's sigma on the convex toy L = w^2/2 (H = 1) for every KL weight, in both
    parameterisations, against sigma* = sqrt(c / (1 + c / sigma_p^2)).

    ``runs[parameterisation]``: ``mu`` and ``sigma`` (kl weights, recorded steps), every
    ``elbo_record_every`` steps; ``settled_mean``/``settled_sd``: sigma over the last
    quarter of the steps (every step), per KL weight.
    """
    kl_weights = np.asarray(config.elbo_kl_weights, dtype=np.float32)
    mu0, sigma0 = config.elbo_start
    predicted = np.sqrt(
        np.asarray(theory.elbo_fixed_point(1.0, kl_weights, config.elbo_prior_sigma))
    )
    out = {
        "kl_weights": kl_weights,
        "prior_sigma": config.elbo_prior_sigma,
        "curvature": 1.0,
        "mu0": mu0,
        "sigma0": sigma0,
        "learning_rate": config.elbo_learning_rate,
        "steps": np.arange(0, config.elbo_steps + 1, config.elbo_record_every),
        "predicted_sigma": predicted,
        "runs": {},
    }
    tail = config.elbo_steps // 4
    for i, parameterisation in enumerate(theory.PARAMETERISATIONS):

        @jax.jit
        @jax.vmap
        def run(c, k, parameterisation=parameterisation):
            return theory.train_elbo_toy(
                theory.convex_loss,
                mu0,
                sigma0,
                k,
                c,
                config.elbo_prior_sigma,
                steps=config.elbo_steps,
                learning_rate=config.elbo_learning_rate,
                num_samples=config.train_samples,
                parameterisation=parameterisation,
            )

        keys = jax.random.split(jax.random.key(config.seed + 500 + i), kl_weights.size)
        trajectory = run(jnp.asarray(kl_weights), keys)
        sigma = np.asarray(trajectory.sigma)
        every = config.elbo_record_every
        out["runs"][parameterisation] = {
            "mu": np.asarray(trajectory.mu)[:, ::every],
            "sigma": sigma[:, ::every],
            "settled_mean": sigma[:, -tail:].mean(axis=1),
            "settled_sd": sigma[:, -tail:].std(axis=1),
        }
    return out


def compute(config: TheoryConfig, progress: bool = True) -> dict[str, Any]:
    """Every number of chapter 3 (JSON-able after ``sgb.provenance``'s conversion)."""
    results = toy_runs(config)
    results["breakdown"] = breakdown(config)
    results["network"] = network_gap(config, progress)
    results["fixed_point"] = fixed_points(config, results["network"], progress)
    results["elbo_toy"] = elbo_toy(config)
    return results


def as_record(results: dict[str, Any]) -> "TheoryResults":
    """``compute`` output as the record its results file would hold: converted to JSON
    data as a run writes it (``sgb.provenance``), then checked by the file's model."""
    return TheoryResults.model_validate(jsonable(results))


def run(profile: str, out_dir: Path, **options: Any) -> Path:
    """Compute chapter 3's numbers at ``profile`` and write ``out_dir/theory_<profile>.json``."""
    if options:
        raise ValueError(f"theory takes no options, got {sorted(options)}")
    recording = start(PROFILES, profile, out_dir, "theory")
    return recording.write(compute(recording.config), seeds=[recording.config.seed])


def network_summary(results: "TheoryResults") -> tuple[list[dict], list[dict]]:
    """Rows for the chapter's tables, from a results file's record (or ``compute`` output
    through ``as_record``): per network at the trained spread (scale 1), and per noisy
    layer."""
    overall, layers = [], []
    for net in results.network:
        types = "/".join("n" if k is None else str(k) for k in net.cell_types)
        base = next(s for s in net.scales if s.scale == 1.0)
        overall.append(
            {
                "cell types": types,
                "mean sigma": net.sigma_mean,
                "mean-network test accuracy": net.accuracy.mean_network,
                "Delta L cross-entropy (train)": float(base.train_cross_entropy.gap),
                "+- SE": float(base.train_cross_entropy.stderr),
                "exact 1/2 tr(H diag sigma^2)": float(base.predicted),
                f"Hutchinson, {net.hutchinson_probes} probes": float(net.hutchinson.value),
                "+- SE ": float(net.hutchinson.stderr),
                "Delta train error (pp)": 100 * float(base.train_error_rate.gap),
                "Delta test error (pp)": 100 * float(base.test_error_rate.gap),
                "+- SE  ": 100 * float(base.test_error_rate.stderr),
            }
        )
        for layer in net.layers:
            layers.append(
                {
                    "cell types": types,
                    "noisy layer": layer.layer,
                    "measured Delta L (CE)": float(layer.gap),
                    "+- SE": float(layer.stderr),
                    "1/2 sum H_ss sigma_s^2": float(layer.predicted),
                    "measured / predicted": float(layer.gap) / float(layer.predicted),
                }
            )
    return overall, layers


def fixed_point_rows(fixed_points: list["FixedPoint"]) -> list[dict[str, Any]]:
    """Rows for the chapter's table of the fixed points (a results file's record, or
    ``compute`` output through ``as_record``): per classifier and training length, accuracy
    and how close the learned sigma^2 lies to c / (H + c lambda), with H at the trained
    means and averaged over individuals."""
    rows = []
    for net in fixed_points:
        types = "/".join("n" if k is None else str(k) for k in net.cell_types)
        for run in net.runs:
            sigma2 = np.concatenate([np.asarray(x.sigma2) for x in run.layers.values()])
            at_mean, population = run.summary.at_mean, run.summary.population
            rows.append(
                {
                    "cell types": types,
                    "epochs": run.epochs,
                    "mean-network test accuracy": run.accuracy.mean_network,
                    "individuals' test accuracy": run.accuracy.population_average,
                    "median learned sigma": float(np.median(np.sqrt(sigma2))),
                    "median sigma^2 / predicted (H at mu)": at_mean.median_ratio,
                    "10-90 % range": f"{at_mean.ratio_q10:.2f}-{at_mean.ratio_q90:.2f}",
                    "log correlation (H at mu)": at_mean.log_correlation,
                    "median sigma^2 / predicted (H over individuals)": population.median_ratio,
                    "10-90 % range ": f"{population.ratio_q10:.2f}-{population.ratio_q90:.2f}",
                    "log correlation (H over individuals)": population.log_correlation,
                }
            )
    return rows


def theorem_rows(theory: "TheoryResults") -> list[Row]:
    """Theorems A.1 and A.3 on the 1-D toys: the sign of the Jensen gap E[L(w)] - L(mu)
    at the start, from its Monte Carlo estimate."""
    rows = []
    toys = theory.trajectories
    for toy, t, name in (("convex", toys.convex, "A.1"), ("concave", toys.concave, "A.3")):
        test = stats.estimate_test("Monte Carlo z", t.gap[0], t.gap_stderr[0], 1)
        rows.append(
            judge(
                f"theorem.{name}",
                f"1-D {toy} toy",
                test,
                "Monte Carlo draws of the toy (see chapter 3)",
                paper_effect=float(t.prediction[0]),
            )
        )
    rows += descent_rows(theory)
    if theory.elbo_toy is not None:
        rows += sigma_law_rows(theory.elbo_toy)
    return rows


def descent_rows(theory: "TheoryResults") -> list[Row]:
    """Theorem A.2's conclusion, that gradient descent drives the Jensen gap below 0, at the
    end of training: on the double well from chapter 3's start, and on each digits
    classifier at its trained spread (its training cross-entropy). The effect compared
    stands in for a number the appendix does not give: the size of the second-order term
    at that point, on the claim's side."""
    toy = theory.trajectories.nonconvex
    rows = []
    places = [
        (
            f"1-D double well from mu {toy.mu0:g}, sigma {toy.sigma0:g}, after "
            f"{len(toy.gap) - 1} steps",
            toy.gap[-1],
            toy.gap_stderr[-1],
            toy.prediction[-1],
            "Monte Carlo draws of the toy (see chapter 3)",
        )
    ]
    for network in theory.network:
        types = network.cell_types
        kind = "no types" if all(k is None for k in types) else "/".join(map(str, types)) + " types"
        trained = next(s for s in network.scales if s.scale == 1.0)
        loss = trained.train_cross_entropy
        places.append(
            (
                f"digits classifier, {kind}, at its trained sigma, training cross-entropy",
                loss.gap,
                loss.stderr,
                trained.predicted,
                "the trained classifier's Monte Carlo draws (see chapter 3)",
            )
        )
    for setting, gap, stderr, predicted, budget in places:
        test = stats.estimate_test("Monte Carlo z", gap, stderr, 1)
        basis = "no number given: the size of the second-order term there, on the claim's side"
        rows.append(
            judge("theorem.A.2", setting, test, budget, paper_effect=-abs(predicted), basis=basis)
        )
    return rows


def sigma_law_rows(toy: "ElboToy") -> list[Row]:
    """Theorem A.4's sigma step, as the appendix writes it (no entropy term: sigma shrinks to
    0 along positive curvature) against the ELBO the book trains (sigma settles at
    sqrt(c / (H + c lambda))), on the convex toy with the KL on. The effect is where sigma
    settles minus the full ELBO's fixed point; the appendix's step predicts minus that
    fixed point (sigma at 0). The interval is sigma's spread over the last quarter of the
    steps (its stationary SD), a conservative one."""
    rows = []
    runs = toy.runs.softplus
    for c, predicted, settled, sd in zip(
        toy.kl_weights,
        toy.predicted_sigma,
        runs.settled_mean,
        runs.settled_sd,
        strict=True,
    ):
        if c <= 0:
            continue
        test = stats.estimate_test("stationary spread", settled - predicted, sd, 1)
        rows.append(
            judge(
                "theorem.A.4",
                f"1-D convex toy, KL weight {c:g}, sigma = softplus(rho)",
                test,
                f"{int(toy.steps[-1])} gradient steps",
                paper_effect=-float(predicted),
                basis=f"sigma at 0: minus the fixed point with the entropy term ({predicted:.3f})",
            )
        )
    return rows


def descent(card: Card) -> dict[str, str]:
    """Theorem A.2's conclusion at the end of training (``descent_rows``): the double
    well's row (``a2_toy``) and the digits classifiers' (``a2_networks``), each its gap with
    its 95 % interval and verdict."""
    rows = card.get("theorem.A.2", [])
    toy = [r for r in rows if "double well" in r.setting]
    networks = [r for r in rows if r.setting.startswith("digits classifier, ")]
    if not toy:
        return {"a2_toy": NOT_RUN, "a2_networks": NOT_RUN}
    kinds = [r.setting.removeprefix("digits classifier, ").split(", at")[0] for r in networks]
    return {
        "a2_toy": f"{toy[0].setting.removeprefix('1-D double well ')}: {toy[0].ours}, "
        f"**{toy[0].verdict}**",
        "a2_networks": "; ".join(
            f"{kind}: {r.ours}, **{r.verdict}**" for kind, r in zip(kinds, networks, strict=True)
        )
        or NOT_RUN,
    }


def evidence(records: Records) -> list[Row]:
    """Theorems A.1-A.4's rows (``theorem_rows``); none before the theory file is run."""
    payload = records.get("theory")
    return [] if payload is None else theorem_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 3 glues: Theorem A.2's rows at the end of training (``descent``)."""
    return descent(card)


class Trajectory(Record):
    mu0: Finite
    sigma0: NonNegative
    gap: List[Finite]
    gap_stderr: List[NonNegative]
    prediction: List[Finite]


class Trajectories(Record):
    convex: Trajectory
    concave: Trajectory
    nonconvex: Trajectory


class Settled(Record):
    settled_mean: List[NonNegative]
    settled_sd: List[NonNegative]


class SigmaRuns(Record):
    softplus: Settled


class ElboToy(Record):
    kl_weights: List[NonNegative]
    predicted_sigma: List[NonNegative]
    steps: List[Steps]
    runs: SigmaRuns


class Gap(Record):
    gap: Finite
    stderr: NonNegative


class ScaleGap(Record):
    scale: NonNegative
    predicted: Finite
    train_cross_entropy: Gap
    train_error_rate: Gap
    test_error_rate: Gap


class LayerGap(Gap):
    layer: str
    predicted: Finite


class MeanNetworkAccuracy(Record):
    mean_network: Accuracy


class Hutchinson(Record):
    value: Finite
    stderr: NonNegative


class NetworkGap(Record):
    cell_types: List[Count | None]
    sigma_mean: NonNegative
    accuracy: MeanNetworkAccuracy
    hutchinson_probes: Count
    hutchinson: Hutchinson
    scales: List[ScaleGap]
    layers: List[LayerGap]


class Fit(Record):
    median_ratio: Finite
    ratio_q10: Finite
    ratio_q90: Finite
    log_correlation: Correlation


class Fits(Record):
    at_mean: Fit
    population: Fit


class BothAccuracies(MeanNetworkAccuracy):
    population_average: Accuracy


class Sigma2(Record):
    sigma2: List[NonNegative]
    curvature: List[Finite]
    curvature_population: List[Finite]


class FixedPointRun(Record):
    epochs: Count
    kl_weight: NonNegative
    prior_sigma: Positive
    population_hessians: Count
    sigma2_init: NonNegative
    accuracy: BothAccuracies
    layers: Each(Sigma2)
    summary: Fits


class FixedPoint(Record):
    cell_types: List[Count | None]
    runs: List[FixedPointRun]


class TheoryResults(Record):
    trajectories: Trajectories
    elbo_toy: ElboToy = None
    network: List[NetworkGap]
    fixed_point: List[FixedPoint] = None


class Theory(ResultsFile):
    results: TheoryResults
