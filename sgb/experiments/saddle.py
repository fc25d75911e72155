"""Appendix A.2's conjecture that an SGB's means converge to saddle points of the loss,
"thereby leading to a better mean performance of sampled networks", on chapter 3's digits
classifiers: the whole Hessian of the mean network's training cross-entropy at the
trained means, and how much of Theorem A.1's second-order term its negative curvature
makes.

Per classifier (chapter 3's two: one type per neuron, and 16/8/10 types) and seed, the
dense Hessian H over the 2,368 weights at the trained means mu (``sgb.theory.
second_order_eigen``), its eigenvalues lambda_i, and each one's share of the spread,
rho2_i = sum_j sigma_j^2 nu_ij^2. Theorem A.1's term 1/2 sum_i lambda_i rho2_i splits into a
positive part P (lambda_i > 0) and a negative part N (minus the lambda_i < 0 terms): the
population beats its mean network, to second order, where N > P. The record keeps N, P,
the negative share N / (N + P), the extreme eigenvalues, the count of negative ones, and
the norm of the gradient at mu (a saddle point is a critical point: the ELBO's means need
not be one of the loss alone), and the whole spectrum of the first seed.

``run`` writes ``saddle_cpu.json`` (``saddle_smoke.json`` at smoke) with provenance.
"""

import dataclasses
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from sgb import stats, theory, verdicts
from sgb.claims import CLAIMS, Row, judge
from sgb.data import digits
from sgb.profiles import PROFILE_NAMES
from sgb.prose import NOT_RUN, Card, row_texts
from sgb.recording import start
from sgb.results import Records
from sgb.schemas import (
    Count,
    Finite,
    List,
    MaybeEmpty,
    NonNegative,
    Probability,
    Record,
    ResultsFile,
    Seed,
    Steps,
)
from sgb.supervised import DIGITS_CLASSIFIERS, ClassifierConfig, train_and_evaluate


@dataclasses.dataclass(frozen=True)
class SaddleConfig:
    """Chapter 3's digits ``classifiers``, each trained from every seed of ``seeds``."""

    classifiers: tuple[ClassifierConfig, ...] = DIGITS_CLASSIFIERS
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)
    data_seed: int = 0  # the digits split, chapter 3's


PROFILES = {
    "smoke": SaddleConfig(
        classifiers=tuple(dataclasses.replace(c, epochs=2) for c in SaddleConfig().classifiers),
        seeds=(0, 1),
    ),
    **{p: SaddleConfig() for p in PROFILE_NAMES[1:]},
}


def curvature_split(eigenvalues: np.ndarray, rho2: np.ndarray) -> tuple[float, float]:
    """Theorem A.1's second-order term 1/2 sum_i lambda_i rho2_i split by the sign of the
    curvature: (P, N), the positive eigenvalues' part and minus the negative ones' (both
    >= 0, in loss units; the term is P - N). ``eigenvalues``, ``rho2``: (P,) each."""
    half = 0.5 * np.asarray(eigenvalues) * np.asarray(rho2)
    return float(half[half > 0].sum()), float(-half[half < 0].sum())


def curvature_record(classifier: ClassifierConfig, seed: int, data) -> dict[str, Any]:
    """Train ``classifier`` from ``seed`` on ``data`` and measure the Hessian of its mean
    network's training cross-entropy at the trained means (the module docstring)."""
    trained = train_and_evaluate(dataclasses.replace(classifier, seed=seed), data, progress=False)
    view = theory.synapse_view(trained["model"], trained["params"], data.x_train)
    loss = theory.network_loss(view, data.x_train, data.y_train, "cross_entropy")
    eigen = theory.second_order_eigen(loss, view.mean, view.sigma)
    eigenvalues, rho2 = np.asarray(eigen.eigenvalues, float), np.asarray(eigen.rho2, float)
    positive, negative = curvature_split(eigenvalues, rho2)
    gradient = jax.tree_util.tree_leaves(jax.grad(loss)(view.mean))
    return {
        "cell_types": list(classifier.cell_types),
        "seed": seed,
        "weights": int(eigenvalues.size),
        "positive": positive,
        "negative": negative,
        "negative_share": negative / (positive + negative),
        "lambda_min": float(eigenvalues[0]),
        "lambda_max": float(eigenvalues[-1]),
        "negative_eigenvalues": int((eigenvalues < 0).sum()),
        "gradient_norm": float(jnp.sqrt(sum(jnp.sum(g**2) for g in gradient))),
        "mean_network_accuracy": trained["accuracy"]["mean_network"],
        "population_accuracy": trained["accuracy"]["population_average"],
        "eigenvalues": [float(f"{v:.6g}") for v in eigenvalues] if seed == 0 else [],
    }


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Measure every classifier at every seed and write the results file."""
    recording = start(PROFILES, profile, out_dir, "saddle")
    config = recording.config
    data = digits(config.data_seed)
    cells = [(c, s) for c in config.classifiers for s in config.seeds]
    records = [
        curvature_record(c, s, data)
        for c, s in tqdm(cells, desc="Hessians at the means", disable=not progress)
    ]
    return recording.write({"networks": records}, config.seeds)


def _kind(cell_types: list) -> str:
    return "no types" if all(k is None for k in cell_types) else "/".join(map(str, cell_types))


def saddle_table(results: "SaddleResults") -> pd.DataFrame:
    """Per classifier (its types) and seed: the Hessian's extreme eigenvalues, its share
    of negative eigenvalues, the second-order term's parts P and N and N's share, and the
    gradient's norm at the means."""
    return pd.DataFrame(
        {
            "types": _kind(n.cell_types),
            "seed": n.seed,
            "lambda min": n.lambda_min,
            "lambda max": n.lambda_max,
            "negative eigenvalues %": 100 * n.negative_eigenvalues / n.weights,
            "P (positive part)": n.positive,
            "N (negative part)": n.negative,
            "N / (N + P)": n.negative_share,
            "|gradient| at mu": n.gradient_norm,
        }
        for n in results.networks
    )


def saddle_rows(results: "SaddleResults") -> list[Row]:
    """Per classifier with 2 seeds or more: the negative curvature's share of Theorem
    A.1's second-order term, one-sample t over seeds against 0 (a minimum has none)."""
    rows = []
    for kind in dict.fromkeys(_kind(n.cell_types) for n in results.networks):
        shares = [n.negative_share for n in results.networks if _kind(n.cell_types) == kind]
        if len(shares) < 2:
            continue
        setting = (
            f"digits classifier, {kind}{' types' if kind != 'no types' else ''}, "
            "training cross-entropy at the trained means"
        )
        budget = f"{len(shares)} seeds, chapter 3's training"
        if not any(shares):  # no negative curvature at any seed: a minimum every time
            claim = CLAIMS["theorem.A.2.saddle"]
            reason = "no negative eigenvalue at any seed: each mean sits at a minimum"
            rows.append(
                Row(
                    claim,
                    setting,
                    claim.paper_effect,
                    claim.basis,
                    None,
                    budget,
                    verdicts.CONTRADICTED,
                    reason,
                )
            )
            continue
        rows.append(judge("theorem.A.2.saddle", setting, stats.one_sample(shares, 0.0), budget))
    return rows


def evidence(records: Records) -> list[Row]:
    """The saddle rows (``saddle_rows``); none before the file is run."""
    payload = records.get("saddle")
    return [] if payload is None else saddle_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 3 glues of the saddle rows: each classifier's row (``saddle_none_*``,
    ``saddle_typed_*``), and the ranges over its seeds of the negative eigenvalues' share
    and of the gradient's norm (``saddle_none_spectrum``, ``saddle_typed_spectrum``)."""
    rows = card.get("theorem.A.2.saddle", [])
    payload = records.get("saddle")
    out = {}
    for name, typed in (("none", False), ("typed", True)):
        row = next((r for r in rows if ("no types" not in r.setting) == typed), None)
        out |= row_texts(f"saddle_{name}", row)
        mine = (
            []
            if payload is None
            else [
                n for n in payload.results.networks if (_kind(n.cell_types) != "no types") == typed
            ]
        )
        if not mine:
            out[f"saddle_{name}_spectrum"] = NOT_RUN
            continue
        share = [100 * n.negative_eigenvalues / n.weights for n in mine]
        ratio = [n.lambda_min / n.lambda_max for n in mine]
        norm = [n.gradient_norm for n in mine]
        out[f"saddle_{name}_spectrum"] = (
            f"{min(share):.0f} to {max(share):.0f} % of the eigenvalues negative, the most "
            f"negative {min(ratio):.2f} to {max(ratio):.2f} of the largest, the gradient's "
            f"norm {min(norm):.2f} to {max(norm):.2f} over {len(mine)} seeds"
        )
    return out


class Network(Record):
    cell_types: List[Count | None]
    seed: Seed
    weights: Count
    positive: NonNegative
    negative: NonNegative
    negative_share: Probability
    lambda_min: Finite
    lambda_max: Finite
    negative_eigenvalues: Steps
    gradient_norm: NonNegative
    eigenvalues: MaybeEmpty[Finite]  # the first seed's, ascending


class SaddleResults(Record):
    networks: List[Network]


class Saddle(ResultsFile):
    results: SaddleResults
