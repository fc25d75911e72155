"""Figures of chapter 5: cell-type sweeps (Fig. 3C/D), population scatters (4E/F), mean network (5),
the initial-spread sweep, the HalfCheetah backends, and rendered frames of the bodies."""

import numpy as np

from sgb import stats
from sgb.plots import PALETTE, subplots

SETTINGS_STYLE = {
    "ours": ("sgb", "o", "SGB, our settings"),
    "authors": ("authors", "s", "SGB, the authors' settings"),
    # the typing ablation (16 types only): each settings with the other's input typing
    "ours_typed_inputs": ("sgb", "D", "ours, observation entries typed"),
    "authors_untyped_inputs": ("authors", "v", "the authors', one type per entry"),
}


def plot_sweep(summary: list[dict], env: str, ax=None):
    """Innate return as a fraction of vanilla PPO against the number of cell types (SEM
    bars), one line per genome settings."""
    if ax is None:
        _, ax = subplots()
    types = set()
    for settings, (color, marker, label) in SETTINGS_STYLE.items():
        rows = sorted(
            (r for r in summary if r["cell_types"] is not None and r["settings"] == settings),
            key=lambda r: r["cell_types"],
        )
        if not rows:
            continue
        k = [r["cell_types"] for r in rows]
        types.update(k)
        ax.errorbar(
            k,
            [r["fraction"] for r in rows],
            yerr=[np.nan if r["sem_fraction"] is None else r["sem_fraction"] for r in rows],
            marker=marker,
            capsize=3,
            color=PALETTE[color],
            mfc="none" if len(rows) == 1 else PALETTE[color],
            ls="none" if len(rows) == 1 else "-",
            label=f"{label} (innate, mean of individuals)",
        )
    ax.axhline(1.0, color=PALETTE["baseline"], ls="--", label="vanilla PPO (width 128)")
    ax.set_xscale("log", base=2)
    ax.set_xticks(sorted(types), [str(v) for v in sorted(types)])
    ax.set_xlabel("cell types per hidden layer")
    ax.set_ylabel("return / vanilla return")
    ax.set_title(env)
    ax.legend(loc="best", fontsize=8)
    return ax


def plot_pair(returns: dict, a: str, b: str, ax=None):
    """Each individual's mean return on condition ``a`` vs ``b``, SEM over episodes as bars."""
    if ax is None:
        _, ax = subplots()
    x, y = np.asarray(returns[a]["individuals"]), np.asarray(returns[b]["individuals"])
    ax.errorbar(
        x.mean(1),
        y.mean(1),
        xerr=stats.sem(x, axis=1),
        yerr=stats.sem(y, axis=1),
        fmt="o",
        ms=3,
        alpha=0.6,
        elinewidth=0.6,
        color=PALETTE["individuals"],
        label="individuals",
    )
    if "mean_network" in returns[a] and "mean_network" in returns[b]:
        ax.plot(
            np.mean(returns[a]["mean_network"]),
            np.mean(returns[b]["mean_network"]),
            "*",
            ms=14,
            color=PALETTE["mean_network"],
            label="mean network",
        )
    r = stats.pearson(x.mean(1), y.mean(1))
    ax.set_xlabel(f"return, {a.replace('_', ' ')}")
    ax.set_ylabel(f"return, {b.replace('_', ' ')}")
    ax.set_title(f"Pearson r = {r.statistic:.2f} (p = {r.p_value:.2g}, n = {x.shape[0]})")
    ax.legend(loc="upper left")
    return ax


def plot_mean_network(returns: dict, condition: str = "normal", ax=None):
    """Figure 5, our protocol: sorted mean returns of the individuals against the mean
    network's on the same initial states, with 99% CI bands and the paired t-test."""
    ind = np.asarray(returns[condition]["individuals"]).mean(1)
    mean_net = np.asarray(returns[condition]["mean_network"]).mean(1)
    t = stats.paired_t(ind, mean_net)
    title = f"paired t({t.dof}) = {t.statistic:.1f}, p = {t.p_value:.2g}"
    return _population_and_mean_network(ind, mean_net, title, "innate return", ax)


def plot_authors_protocol(protocol: dict, ax=None):
    """Figure 5, the authors' protocol (``sgb.experiments.rl.authors_protocol``): sorted
    mean returns of the individuals (sampled actions) against the mean network's episodes,
    with 99% CI bands and the one-sample t-test."""
    ind = np.asarray(protocol["individuals"]).mean(1)
    title = f"one-sample t({protocol['dof']}) = {protocol['t']:.1f}, p = {protocol['p']:.2g}"
    mean_net = np.asarray(protocol["mean_network"])
    return _population_and_mean_network(ind, mean_net, title, "return, sampled actions", ax)


def _population_and_mean_network(ind, mean_net, title: str, ylabel: str, ax):
    if ax is None:
        _, ax = subplots()
    rank = np.arange(1, ind.size + 1)
    ax.plot(rank, np.sort(ind), ".", color=PALETTE["individuals"], label="individuals (sorted)")
    for values, name in ((ind, "individuals"), (mean_net, "mean_network")):
        mean, low, high = stats.mean_ci(values, 0.99)
        label = "population mean" if name == "individuals" else "mean network"
        ax.axhline(mean, color=PALETTE[name], label=f"{label}, 99% CI")
        ax.axhspan(low, high, color=PALETTE[name], alpha=0.25)
    ax.set_xlabel("individual (rank)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.legend(loc="lower right", fontsize=8)
    return ax


def plot_spread(summary: list[dict], axes=None):
    """Against the initial sigma (log axis): the individuals' mean return minus the mean
    network's (left) and the standard deviation of the individuals' returns (right);
    bars are the SEM over seeds."""
    if axes is None:
        _, axes = subplots(1, 2, figsize=(10, 3.8))
    sigma = [r["sigma_init"] for r in summary]
    panels = (
        ("advantage", "individuals - mean network (return)", PALETTE["individuals"]),
        ("individuals_sd", "SD of individuals' returns", PALETTE["sgb"]),
    )
    for ax, (key, label, color) in zip(axes, panels, strict=True):
        values, errors = [r[key] for r in summary], [r[f"sem_{key}"] for r in summary]
        ax.errorbar(sigma, values, yerr=errors, marker="o", capsize=3, color=color)
        ax.set_xscale("log")
        ax.set_xlabel(r"initial $\sigma$ of every type pair")
        ax.set_ylabel(label)
    axes[0].axhline(0.0, color=PALETTE["mean_network"], ls="--", label="mean network")
    axes[0].legend(loc="best", fontsize=8)
    return axes


def plot_backends(bench: dict, axes=None):
    """``benchmarks/bench_backends.py``'s results: training env-steps/s per Brax backend
    (left) and the learning curve of vanilla PPO on the fastest one (right)."""
    if axes is None:
        _, axes = subplots(1, 2, figsize=(10, 3.8))
    speeds = bench["throughput"]
    axes[0].bar(list(speeds), [s["train_steps_per_s"] for s in speeds.values()])
    axes[0].set_xlabel("Brax backend")
    axes[0].set_ylabel("training env-steps/s")
    axes[0].set_title(f"{bench['env']}: vanilla PPO, {bench['throughput_steps']:,} steps")
    reach = bench["reach"]
    axes[1].plot(np.array(reach["eval_steps"]) / 1e6, reach["eval_returns"], marker="o")
    axes[1].set_xlabel("training env steps (millions)")
    axes[1].set_ylabel("evaluation return")
    axes[1].set_title(f"vanilla PPO on {reach['backend']}")
    return axes


def show_images(images: dict[str, np.ndarray], axes=None):
    """Rendered frames (height, width, 3) side by side, titled by their keys."""
    if axes is None:
        _, axes = subplots(1, len(images), figsize=(4.0 * len(images), 3.2), squeeze=False)
        axes = axes[0]
    for ax, (title, image) in zip(axes, images.items(), strict=True):
        ax.imshow(image)
        ax.set_title(title)
        ax.set_axis_off()
    return axes
