"""The committed results as data: a file's payload, its provenance in one line, tidy tables.

``name`` is a results file's path under ``results_dir`` (default
``sgb.paths.committed_results()``), e.g. ``"rl/fig3_ant_cpu.json"``. Each table is a
``pandas.DataFrame`` with one row per run, cell or record and the file's values
unchanged (returns in reward units, accuracies as fractions, times in seconds).

``load`` is the one door: it refuses (``sgb.validation.CorruptFile``, naming the file) a
file that is not a results file, that is not as its run wrote it (``sgb.provenance``'s
checksum, ``sgb.manifest``), or that does not parse under its schema (``sgb.schemas``).
"""

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from sgb import manifest, schemas
from sgb.paths import committed_results
from sgb.provenance import read_results, verify_checksum

Payload = dict[str, Any]  # a results file: {"results": ..., "provenance": ...}


def path(name: str, results_dir: str | Path | None = None) -> Path:
    """Where the results file ``name`` lies under ``results_dir``."""
    return Path(committed_results() if results_dir is None else results_dir) / name


def load(
    name: str, results_dir: str | Path | None = None, missing_ok: bool = False
) -> Payload | None:
    """The payload of results file ``name``, once it is checked: strict JSON, matching the
    checksum its run embedded (``sgb.provenance.verify_checksum``), its entry in the
    manifest of ``results_dir`` (``sgb.manifest.verify``) and its schema
    (``sgb.schemas.check``), else a ``CorruptFile`` naming it. ``None`` if it is absent and
    ``missing_ok``, else ``FileNotFoundError`` naming it."""
    root = Path(committed_results() if results_dir is None else results_dir)
    file = root / name
    if not file.exists():
        if missing_ok:
            return None
        raise FileNotFoundError(f"no results file {file}: run `python -m sgb reproduce` for it")
    payload = read_results(file, schemas.REWRITE)
    verify_checksum(file, payload, schemas.REWRITE)
    manifest.verify(file, root)
    schemas.check(name, payload, file)
    return payload


class Records:
    """The results files of ``results_dir`` (default: the committed ones), each named by
    its experiment (a key of the registry ``sgb.experiments.EXPERIMENTS``) and part (a
    body, a dataset, or ``""`` for an experiment of one file), read once each through
    ``load``. ``files`` maps experiment -> part -> file name, as the registry declares them.

        records("fig3", "ant")        # the payload, or FileNotFoundError naming the file
        records.get("regime_peer")    # the payload, or None where it was never run
    """

    def __init__(
        self, files: dict[str, dict[str, str]], results_dir: str | Path | None = None
    ) -> None:
        self.files = files
        self.results_dir = Path(committed_results() if results_dir is None else results_dir)
        self._read: dict[str, Payload | None] = {}

    def name(self, experiment: str, part: str = "") -> str:
        """The file name of ``experiment``'s ``part``."""
        parts = self.files.get(experiment, {})
        if part not in parts:
            raise ValueError(
                f"experiment {experiment!r} declares no results file {part!r}: {sorted(parts)}"
            )
        return parts[part]

    def get(self, experiment: str, part: str = "") -> Payload | None:
        """The payload of ``experiment``'s ``part``, or None if it is absent."""
        name = self.name(experiment, part)
        if name not in self._read:
            self._read[name] = load(name, self.results_dir, missing_ok=True)
        return self._read[name]

    def __call__(self, experiment: str, part: str = "") -> Payload:
        """The payload of ``experiment``'s ``part``; FileNotFoundError if it is absent."""
        payload = self.get(experiment, part)
        if payload is None:
            file = self.results_dir / self.name(experiment, part)
            raise FileNotFoundError(
                f"no results file {file}: run `python -m sgb reproduce {experiment}` for it"
            )
        return payload


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 2 * 3600:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def provenance_line(payload: Payload) -> str:
    """One line of where a results file comes from: profile, seeds, the commits that ran
    it (10 hex digits each, ``+dirty`` kept), date and wall time on its backend."""
    record = payload["provenance"]
    shown = (c[:10] + c[40:] for c in record.get("git_commits", [record["git_commit"]]))
    commits = ", ".join(dict.fromkeys(shown))  # in order, each once
    return (
        f"profile {record['profile']}, seeds {record['seeds']}, commit {commits}, "
        f"{record['date'][:10]}, {_duration(record['wall_time_s'])} on {record['backend']}"
    )


def fig3_summary(payload: Payload) -> list[dict]:
    """A Figure 3 sweep's summary rows (one per settings and cell types), scored by the
    mean of the last two evaluations where the file has that score, else by the last."""
    results = payload["results"]
    return results.get("summary_last_two", results["summary"])


def fig3_seeds(payload: Payload) -> list[dict]:
    """Each SGB run of a Figure 3 sweep as a fraction of the mean vanilla return, scored as
    ``fig3_summary`` scores it (the mean of the last two evaluations where the file has that
    summary): settings, cell types, seed and fraction; their means are the summary's."""
    results = payload["results"]
    score = "last_two_return" if "summary_last_two" in results else "final_return"
    vanilla = next(r["mean_return"] for r in fig3_summary(payload) if r["cell_types"] is None)
    return [
        {
            "settings": r["settings"],
            "cell_types": r["cell_types"],
            "seed": r["seed"],
            "fraction": r[score] / vanilla,
        }
        for r in results["runs"]
        if r["cell_types"] is not None
    ]


FIG3_COLUMNS = {
    "env": "body",
    "settings": "genome",
    "cell_types": "cell types",
    "mean_return": "mean return",
    "sem_return": "SEM of return",
    "fraction": "fraction of vanilla",
    "sem_fraction": "SEM of fraction",
    "n_seeds": "seeds",
}
FIG3_GENOMES = {
    "ours": "ours",
    "authors": "the authors'",
    "ours_typed_inputs": "ours, inputs typed",
    "authors_untyped_inputs": "the authors', inputs untyped",
}


def fig3_table(payloads: list[Payload]) -> pd.DataFrame:
    """Figure 3 sweeps, one row per body, genome settings (``FIG3_GENOMES``) and cell types
    ("vanilla" for PPO), each run scored as the verdicts score it (``fig3_summary``: the
    mean of its last two evaluations where the file has it); columns named as
    ``FIG3_COLUMNS`` maps the files' keys."""
    tables = []
    for payload in payloads:
        table = pd.DataFrame(fig3_summary(payload)).assign(env=payload["results"]["env"])
        tables.append(table)
    table = pd.concat(tables, ignore_index=True)
    table["cell_types"] = ["vanilla" if pd.isna(k) else f"{k:.0f}" for k in table["cell_types"]]
    table["settings"] = [FIG3_GENOMES.get(s, s) for s in table["settings"]]
    return table[list(FIG3_COLUMNS)].rename(columns=FIG3_COLUMNS)


REGIME_COLUMNS = {
    "cell_types": "cell types",
    "seed": "seed",
    "final_return": "final return",
    "last_two_return": "mean of last two returns",
    "authors_scale": "final, authors' scale",
    "train_steps_per_s": "env steps/s",
    "wall_time_s": "wall time (s)",
}


def regime_table(payload: Payload) -> pd.DataFrame:
    """The authors' regime (``sgb.experiments.regime``), one row per run: final and
    last-two evaluation returns, the final one on the authors' Figure 3 scale, training
    env-steps/s and wall time; columns named as ``REGIME_COLUMNS`` maps the files' keys."""
    runs = pd.DataFrame(payload["results"]["runs"])[list(REGIME_COLUMNS)]
    return runs.rename(columns=REGIME_COLUMNS)


def spread_table(payload: Payload) -> pd.DataFrame:
    """The spread sweep (``sgb.experiments.rl_spread``), one row per run: initial and
    trained sigma, mean returns of the individuals and the mean network, the SD of the
    individuals' returns, and the paired t over individuals with its p."""
    return pd.DataFrame(
        {
            "sigma start": r["sigma_init"],
            "seed": r["seed"],
            "sigma trained": r["sigma_trained"],
            "individuals": r["individuals_mean"],
            "mean network": r["mean_network_mean"],
            "SD of individuals": r["individuals_sd"],
            "paired t(99)": r["paired_test"]["t"],
            "p": r["paired_test"]["p"],
        }
        for r in payload["results"]["runs"]
    )


def fig45_statistics(fig4: Payload, fig5: Payload) -> pd.DataFrame:
    """Figures 4E/F and 5 in numbers, one row per test: Pearson r between bodies and
    between niches; our paired t and the authors' one-sample t, with the mean returns of
    the individuals and of the mean network (the centres of their 99 % intervals)."""
    legs, niches = fig4["results"]["legs"], fig4["results"]["niches"]
    paired, authors = fig5["results"]["mean_network"], fig5["results"]["authors_protocol"]
    rows = [
        {"figure": "4E", "test": "Pearson r, normal body vs long legs", **legs},
        {"figure": "4F", "test": "Pearson r, slippery vs low gravity", **niches},
        {"figure": "5", "test": "paired t (our protocol)", **paired},
        {"figure": "5", "test": "one-sample t (the authors' protocol)", **authors},
    ]
    return pd.DataFrame(
        {
            "figure": row["figure"],
            "test": row["test"],
            "statistic": row["r"] if "r" in row else row["t"],
            "p": row["p"],
            "individuals' mean return": row.get("individuals_ci99", [math.nan])[0],
            "mean network's return": row.get("mean_network_ci99", [math.nan])[0],
        }
        for row in rows
    )


def figure2_table(results: dict) -> pd.DataFrame:
    """A Figure 2 sweep (``sgb.experiments.fig2``), one row per model and setting: its
    compression counted both ways, and innate test accuracy (%) mean and SEM over seeds
    (NaN with one seed)."""
    ours, theirs = results["ours"]["summary"], results["authors"]["summary"]
    rows = []
    for model in ("dense", "sgb", "dgb"):
        authors_compression = dict(
            zip(theirs[model]["setting"], theirs[model]["compression"], strict=True)
        )
        for i, setting in enumerate(ours[model]["setting"]):
            sem = ours[model]["sem"][i]
            rows.append(
                {
                    "model": model,
                    "setting": setting,
                    "compression (ours)": ours[model]["compression"][i],
                    "compression (authors')": authors_compression[setting],
                    "accuracy %": 100 * ours[model]["mean"][i],
                    "SEM %": float("nan") if sem is None else 100 * sem,
                    "seeds": ours[model]["n"][i],
                }
            )
    return pd.DataFrame(rows)


def dgb_budget_table(results: dict) -> pd.DataFrame:
    """The DGB budget run (``sgb.experiments.dgb_budget``), one row per recorded round:
    best validation accuracy, its network's test accuracy and the generated network's (%)."""
    return pd.DataFrame(
        {
            "rounds": r["rounds"],
            "best validation %": 100 * r["best_validation_accuracy"],
            "its test %": 100 * r["test_accuracy"],
            "generated test %": 100 * r["generated_test_accuracy"],
        }
        for r in results["records"]
    )


def evolution_table(payload: Payload) -> pd.DataFrame:
    """Evolution without gradients (``sgb.experiments.evolution``), one row per cell:
    hidden types, compression (ours), genome, seed, the last generation's mean fitness,
    the test accuracy (%) of the evolved genome's individuals (their mean and SD, in
    points) and of its mean network, the evolved spreads' mean sigma and the wall time."""
    return pd.DataFrame(
        {
            "hidden types": r["hidden_types"],
            "compression": r["compression"],
            "genome": "stochastic" if r["stochastic"] else "deterministic",
            "seed": r["seed"],
            "last fitness": r["mean_fitness"][-1],
            "individuals (% accuracy)": 100 * float(np.mean(r["individuals"])),
            "SD of individuals (points)": 100 * float(np.std(r["individuals"], ddof=1)),
            "mean network (% accuracy)": 100 * r["mean_network"],
            "sigma": r["sigma_mean"],
            "wall time (s)": r["wall_time_s"],
        }
        for r in payload["results"]["records"]
    )


def hedging_table(payload: Payload, q: str = "0.5") -> pd.DataFrame:
    """Bet-hedging (``sgb.experiments.bet_hedging``), one row per genome and population:
    the trained sigma, the fitness scale (the mean network's mean return at home), the
    geometric and arithmetic mean fitness, and P(at least k survive) at threshold ``q``
    for every k."""
    rows = []
    for g in payload["results"]["genomes"]:
        for population, score in g["scores"].items():
            rows.append(
                {
                    "rho start": g["rho_init"],
                    "seed": g["training_seed"],
                    "sigma trained": g["sigma_trained"],
                    "population": population,
                    "home return": g["scale"],
                    "geometric fitness": score["geometric_fitness"],
                    "mean fitness": score["mean_fitness"],
                    **{f"P(>= {k} survive)": p for k, p in score["p_at_least"][q].items()},
                }
            )
    return pd.DataFrame(rows)


def _mean_sem(mean: float, sem: float, scale: float = 1.0, decimals: int = 0) -> str:
    """``mean ± sem`` as text (``sem`` omitted where NaN: one seed)."""
    if math.isnan(sem):
        return f"{scale * mean:.{decimals}f}"
    return f"{scale * mean:.{decimals}f} ± {scale * sem:.{decimals}f}"


def mean_gap_table(results: dict) -> pd.DataFrame:
    """The mean network's gap (``sgb.experiments.mean_gap``), one row per cell (hidden
    types, rho start): compression both ways, seeds, and means ± SEM over seeds of the test
    accuracy (%) of the individuals, their mean network and the moment-matched network, the
    gap individuals minus mean network (points), the trained sigma and the moment-matched
    network's recovery of that gap (a ratio)."""
    return pd.DataFrame(
        {
            "hidden types": s["setting"],
            "rho start": s["rho_init"],
            "compression (ours)": s["compression"],
            "compression (authors')": s["compression_authors"],
            "seeds": s["n"],
            "individuals %": _mean_sem(s["accuracy"], s["accuracy_sem"], 100.0, 1),
            "mean network %": _mean_sem(s["mean_network"], s["mean_network_sem"], 100.0, 1),
            "moment-matched %": _mean_sem(s["moment_network"], s["moment_network_sem"], 100.0, 1),
            "gap (points)": _mean_sem(s["gap"], s["gap_sem"], 100.0, 1),
            "trained sigma": _mean_sem(s["sigma_end"], s["sigma_end_sem"], 1.0, 4),
            "recovery": _mean_sem(s["moment_recovery"], s["moment_recovery_sem"], 1.0, 2),
        }
        for s in results["summary"]
    )


def innate_start_table(payload: Payload) -> pd.DataFrame:
    """Learning from an innate start, one row per genome and start, means ± SEM over seeds:
    for the Ant (``sgb.experiments.innate_start``) the return per episode at 0, 1/4, 1/2 and
    all of the fine-tuning, the mean return over it (area under the curve over its steps) and
    that less the fresh network's; for Fashion-MNIST
    (``sgb.experiments.innate_start_supervised``) the test accuracy (%) at each recorded
    step."""
    rows = []
    for s in payload["results"]["summary"]:
        row = {"start": s["start"]}
        if "genome" in s:
            row["genome"] = s["genome"] or "none (fresh network)"
        row["seeds"] = s["n_seeds"]
        if "steps" in s:
            for step, mean, sem in zip(s["steps"], s["accuracy"], s["accuracy_sem"], strict=True):
                row[f"step {step} (% accuracy)"] = _mean_sem(mean, sem, 100.0, 1)
        else:
            for at in ("0", "0.25", "0.5", "1"):
                row[f"return at {at}"] = _mean_sem(s[f"return_at_{at}"], s[f"return_at_{at}_sem"])
            row["mean return over fine-tuning"] = _mean_sem(s["auc"], s["auc_sem"])
            row["less the fresh network's"] = _mean_sem(
                s["auc_minus_fresh"], s["auc_minus_fresh_sem"]
            )
        rows.append(row)
    return pd.DataFrame(rows)


def dgb_full_table(payload: Payload) -> pd.DataFrame:
    """Figure 2's DGB at the authors' budget (``sgb.experiments.dgb_full``), one row per
    cell: target ratio, seed, g-net width, compression under both conventions beside the
    paper's nominal ratio for that width, rounds trained and the test accuracy (%) of the
    network of best validation accuracy so far."""
    return pd.DataFrame(
        {
            "target ratio": c["ratio"],
            "seed": c["seed"],
            "g-net width": c["gnet_width"],
            "compression (ours)": c["compression_ours"],
            "compression (authors')": c["compression_authors"],
            "nominal ratio (paper's axis)": c["nominal_ratio"],
            "rounds": c["records"][-1]["rounds"] if c["records"] else 0,
            "test accuracy %": 100 * c["records"][-1]["test_accuracy"]
            if c["records"]
            else float("nan"),
        }
        for c in payload["results"]["cells"].values()
    ).sort_values(["target ratio", "seed"], ignore_index=True)


def sgb_full_table(payload: Payload) -> pd.DataFrame:
    """Figure 2's SGB as the paper and the authors train it (``sgb.experiments.sgb_full``),
    one row per variant and number of hidden types, over the seeds finished: compression
    under both conventions, the seeds, the test accuracy (%) of the individuals (mean over
    seeds of each seed's mean, and its SD over seeds, in points) and of the mean network, the
    trained sigma of each layer (its synapses' mean, mean over seeds)."""
    cells = pd.DataFrame(
        {
            "variant": r["variant"],
            "hidden types": r["setting"],
            "compression (ours)": r["compression"],
            "compression (authors')": r["compression_authors"],
            "seed": r["seed"],
            "individuals %": 100 * r["accuracy"],
            "mean network %": 100 * r["mean_network"],
            **{f"sigma, layer {i}": layer["mean_sigma"] for i, layer in enumerate(r["layers"])},
        }
        for r in payload["results"]["cells"].values()
    )
    sigmas = [c for c in cells.columns if c.startswith("sigma")]
    how = {
        "compression (ours)": ("compression (ours)", "mean"),
        "compression (authors')": ("compression (authors')", "mean"),
        "seeds": ("seed", "count"),
        "individuals %": ("individuals %", "mean"),
        "SD of individuals (points)": ("individuals %", "std"),
        "mean network %": ("mean network %", "mean"),
        **{c: (c, "mean") for c in sigmas},
    }
    return (
        cells.groupby(["variant", "hidden types"])
        .agg(**how)
        .sort_values(["variant", "compression (ours)"])
        .reset_index()
    )
