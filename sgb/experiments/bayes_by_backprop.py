"""Chapter 2: a Bayesian MLP on 1-D regression, and SGB classifiers on the digits data."""

import dataclasses
from pathlib import Path
from typing import Any

import jax
import numpy as np

from sgb import genome
from sgb.compression import compression_ratio, dense_param_count, sgb_param_count
from sgb.data import digits
from sgb.individuals import init_params
from sgb.layers import SGBMLP
from sgb.priors import GaussianPrior
from sgb.recording import start
from sgb.regression import gaussian_nll, predictive_bands, toy_regression_data
from sgb.supervised import ClassifierConfig, train_and_evaluate
from sgb.training import fit_elbo


@dataclasses.dataclass(frozen=True)
class BBBConfig:
    """Regression: widths, prior, noise, epochs. Classifiers: a base config, the
    compressed model's cell types, and the seeds each variant is trained with."""

    regression_widths: tuple[int, ...] = (32, 32, 1)
    regression_prior_sigma: float = 1.0
    regression_noise: float = 0.1
    regression_epochs: int = 1500
    classifier: ClassifierConfig = ClassifierConfig(
        hidden=(64,), epochs=10, learning_rate=3e-3, num_samples=2
    )
    compressed_types: tuple[int | None, ...] = (None, 8, 10)
    seeds: tuple[int, ...] = (0,)


PROFILES = {
    "smoke": BBBConfig(),
    "cpu": BBBConfig(
        regression_epochs=3000,
        classifier=ClassifierConfig(hidden=(64,), epochs=40, learning_rate=3e-3, num_samples=4),
        seeds=(0, 1, 2),
    ),
}
PROFILES["paper"] = PROFILES["cpu"]


def fit_regression(config: BBBConfig, seed: int = 0, progress: bool = True) -> dict[str, Any]:
    """Train a full Bayesian MLP (one type per neuron) on the toy 1-D data.

    Returns the data, a grid on [-1.6, 1.6] and the predictive mean and std there.
    """
    x, y = toy_regression_data(noise=config.regression_noise, seed=seed)
    widths = config.regression_widths
    model = SGBMLP(
        widths=widths,
        cell_types=(None,) * (len(widths) + 1),
        prior=GaussianPrior(config.regression_prior_sigma),
        rho_init=-3.0,
        in_features=x.shape[1],
    )
    params = init_params(model, jax.random.key(seed), x)
    params, history = fit_elbo(
        model,
        params,
        x,
        y,
        data_loss=gaussian_nll(config.regression_noise),
        kl_weight=1.0 / len(x),
        num_samples=4,
        learning_rate=1e-2,
        batch_size=len(x),
        epochs=config.regression_epochs,
        seed=seed,
        progress=progress,
    )
    grid = np.linspace(-1.6, 1.6, 161, dtype=np.float32)[:, None]
    mean, std = predictive_bands(model, params, grid, jax.random.key(seed + 1))
    return {
        "x": x[:, 0],
        "y": y[:, 0],
        "grid": grid[:, 0],
        "mean": mean,
        "std": std,
        "history": history,
    }


def classifier_variants(config: BBBConfig) -> dict[str, ClassifierConfig]:
    """The classifiers compared: a plain BNN, the compressed SGB with either KL counting,
    and the last trained with the local reparameterisation."""
    base = config.classifier
    full = (None,) * (len(base.hidden) + 2)
    return {
        "BNN (k = n)": dataclasses.replace(base, cell_types=full),
        "SGB, KL per synapse": dataclasses.replace(base, cell_types=config.compressed_types),
        "SGB, KL per type pair": dataclasses.replace(
            base, cell_types=config.compressed_types, kl_counting="table"
        ),
        "SGB, KL per type pair, local": dataclasses.replace(
            base, cell_types=config.compressed_types, kl_counting="table", local_reparam=True
        ),
    }


def compare_classifiers(config: BBBConfig, progress: bool = True) -> dict[str, Any]:
    """Train every variant for every seed on digits; innate test accuracies and genome sigmas.

    Returns ``{"rows": [...], "examples": {variant: (model, params)}}``; one row per
    (variant, seed) with compression, accuracies, the mean sigma of each layer and the
    last epoch's data term and KL / n_train (nats per example).
    """
    rows, examples = [], {}
    for seed in config.seeds:
        data = digits(seed=seed)
        for name, variant in classifier_variants(config).items():
            variant = dataclasses.replace(variant, seed=seed)
            result = train_and_evaluate(variant, data, progress=progress)
            sizes = (data.x_train.shape[1], *variant.hidden, data.num_classes)
            tables = genome.of_params(result["params"])
            sigmas = {k: float(genome.sigma(g).mean()) for k, g in tables.items()}
            rows.append(
                {
                    "variant": name,
                    "seed": seed,
                    "cell_types": variant.cell_types,
                    "kl_counting": variant.kl_counting,
                    "compression": compression_ratio(
                        dense_param_count(sizes), sgb_param_count(sizes, variant.cell_types)
                    ),
                    **result["accuracy"],
                    "mean_sigma": sigmas,
                    "final_data_term": result["history"][-1]["data"],
                    "final_kl_per_example": result["history"][-1]["kl"] / len(data.x_train),
                }
            )
            examples.setdefault(name, (result["model"], result["params"]))
    return {"rows": rows, "examples": examples}


def run(profile: str, out_dir: Path) -> Path:
    """Run chapter 2's experiments at ``profile``; write ``out_dir/bbb_<profile>.json``."""
    recording = start(PROFILES, profile, out_dir, "bbb")
    regression = fit_regression(recording.config, progress=False)
    classifiers = compare_classifiers(recording.config, progress=False)
    results = {
        "regression": {k: regression[k] for k in ("grid", "mean", "std")},
        "classifiers": classifiers["rows"],
    }
    return recording.write(results, seeds=recording.config.seeds)
