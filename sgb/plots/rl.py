"""Figures of chapter 5: cell-type sweeps (the paper's Figure 3C/D), population scatters
(4E/F), the mean network (5), the initial-spread sweep, the HalfCheetah backends, and
rendered frames of the bodies (still, or walking with each tile labelled)."""

import numpy as np
import seaborn as sns

from sgb import stats
from sgb.plots import PALETTE, WIDTH, axes_or_new, panels
from sgb.rl.regimes import FIG3_SCALE, arm_name, by_arm
from sgb.schemas import BenchBackendsResults, Record, Training

SETTINGS_STYLE = {
    "ours": ("sgb", "o", "SGB, our settings"),
    "authors": ("authors", "s", "SGB, the authors' settings"),
    # the typing ablation (16 types only): each settings with the other's input typing
    "ours_typed_inputs": ("sgb", "D", "ours, observation entries typed"),
    "authors_untyped_inputs": ("authors", "v", "the authors', one type per entry"),
}


def plot_sweep(summary: list[Record], env: str, seeds: list[dict] | None = None, ax=None):
    """Innate return as a fraction of vanilla PPO against the number of cell types (SEM
    bars; each point the mean innate return of an agent's individuals), one line per genome
    settings, the legend under the axes; ``summary``: a sweep's summary rows
    (``sgb.experiments.fig3.fig3_summary``, ``Fig3Summary`` records); each seed a faint
    dot where ``seeds`` (rows of ``sgb.experiments.fig3.fig3_seeds``) are given, spread a
    little sideways by seed."""
    ax = axes_or_new(ax)
    types = set()
    for settings, (color, marker, label) in SETTINGS_STYLE.items():
        mine = [s for s in seeds or () if s["settings"] == settings]
        if mine:
            shift = 2.0 ** (0.04 * (np.array([s["seed"] for s in mine]) % 5 - 2))
            ax.scatter(
                np.array([s["cell_types"] for s in mine]) * shift,
                [s["fraction"] for s in mine],
                s=6,
                alpha=0.35,
                color=PALETTE[color],
                linewidths=0,
            )
        rows = sorted(
            (r for r in summary if r.cell_types is not None and r.settings == settings),
            key=lambda r: r.cell_types,
        )
        if not rows:
            continue
        k = [r.cell_types for r in rows]
        types.update(k)
        ax.errorbar(
            k,
            [r.fraction for r in rows],
            yerr=[np.nan if r.sem_fraction is None else r.sem_fraction for r in rows],
            marker=marker,
            capsize=3,
            color=PALETTE[color],
            mfc="none" if len(rows) == 1 else PALETTE[color],
            ls="none" if len(rows) == 1 else "-",
            label=label,
        )
    ax.axhline(1.0, color=PALETTE["baseline"], ls="--", label="vanilla PPO (width 128)")
    ax.set_xscale("log", base=2)
    ax.set_xticks(sorted(types), [str(v) for v in sorted(types)])
    ax.set_xlabel("cell types per hidden layer")
    ax.set_ylabel("return / vanilla return")
    ax.set_title(env)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, fontsize=8)
    return ax


def _arm_label(cell_types: int | None, genome: str) -> str:
    return ("" if cell_types is None else "SGB, ") + arm_name(cell_types, genome)


def _arm_colours(runs: list[Training]) -> dict[int | None, tuple]:
    """One colour per number of cell types (viridis short of its pale yellow, most types
    darkest), vanilla grey."""
    types = sorted({r.cell_types for r in runs if r.cell_types is not None}, reverse=True)
    colours = dict(zip(types, sns.color_palette("viridis", len(types) + 1), strict=False))
    return colours | {None: PALETTE["baseline"]}


def _authors_axis(ax, env: str) -> None:
    """The authors' Figure 3 scale, (R + 724) / (SOTA + 724), on ``ax``'s right."""
    low, high = FIG3_SCALE[env]
    right = ax.secondary_yaxis(
        "right", functions=(lambda r: (r - low) / (high - low), lambda f: low + f * (high - low))
    )
    right.set_ylabel("the authors' Figure 3 scale")


def plot_regime(runs: list[Training], env: str = "ant", ax=None):
    """Learning curves under the authors' regime: the training-time evaluation (their
    window return) against env steps, one line per run, one colour per number of cell
    types (vanilla grey and dashed, the aliased pairs dotted), one legend entry per arm;
    the right axis is the authors' Figure 3 scale, (R + 724) / (SOTA + 724)."""
    ax = axes_or_new(ax)
    colours = _arm_colours(runs)
    for (cell_types, genome), mine in by_arm(runs).items():
        style = "--" if cell_types is None else ("-" if genome == "authors" else ":")
        label = f"{_arm_label(cell_types, genome)} ({len(mine)} seed{'s' * (len(mine) > 1)})"
        for j, run in enumerate(mine):
            ax.plot(
                np.asarray(run.eval_steps) / 1e6,
                run.eval_returns,
                marker="o",
                ms=3,
                color=colours[cell_types],
                ls=style,
                alpha=0.85,
                label=label if j == 0 else "_nolegend_",
            )
    ax.set_xlabel("env steps (millions)")
    ax.set_ylabel("window return (their evaluation)")
    _authors_axis(ax, env)
    ax.legend(fontsize=8)
    return ax


def plot_regime_sweep(runs: list[Training], env: str = "ant", ax=None):
    """The paper's Figure 3C at its budget: each run's final return (its last evaluation)
    against the number of cell types per hidden layer (log scale), a dot per seed and the
    arm's mean with its SEM over seeds (no bar for one seed); the aliased pairs beside
    their count; vanilla PPO's mean as a dashed line with its SEM as a band; the right
    axis is the authors' Figure 3 scale."""
    ax = axes_or_new(ax)
    colours = _arm_colours(runs)
    arms = by_arm(runs)
    for (cell_types, genome), mine in arms.items():
        returns = np.array([r.final_return for r in mine])
        sem = float(stats.sem(returns)) if len(returns) > 1 else 0.0
        label = f"{_arm_label(cell_types, genome)} ({len(mine)} seed{'s' * (len(mine) > 1)})"
        if cell_types is None:
            ax.axhline(returns.mean(), color=colours[None], ls="--", label=label)
            ax.axhspan(returns.mean() - sem, returns.mean() + sem, color=colours[None], alpha=0.15)
            continue
        x = cell_types * (1.0 if genome == "authors" else 1.12)
        ax.scatter(
            np.full(len(returns), x) * 2.0 ** (0.025 * (np.arange(len(returns)) - 1)),
            returns,
            s=12,
            alpha=0.45,
            color=colours[cell_types],
            linewidths=0,
        )
        ax.errorbar(
            x,
            returns.mean(),
            yerr=sem if len(returns) > 1 else None,
            marker="o" if genome == "authors" else "s",
            mfc=colours[cell_types] if genome == "authors" else "none",
            capsize=3,
            color=colours[cell_types],
            ls="none",
            label=label,
        )
    types = sorted({k for k, _ in arms if k is not None})
    ax.set_xscale("log", base=2)
    ax.set_xticks(types, [str(k) for k in types])
    ax.minorticks_off()
    ax.set_xlabel("cell types per hidden layer")
    ax.set_ylabel("final window return")
    _authors_axis(ax, env)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=2, fontsize=8)
    return ax


def plot_sigma_courses(courses: dict[str, tuple], ax=None):
    """How the spreads moved over training: for each run (its name -> ``(env steps (n,),
    mean sigma per kernel (n, layers), the layers' names)``, as
    ``sgb.experiments.regime.sigma_course`` gives them) one colour, one line style per
    layer."""
    ax = axes_or_new(ax)
    styles = ("-", "--", ":", "-.")
    for (name, (steps, sigma, layers)), color in zip(
        courses.items(), sns.color_palette("colorblind", len(courses)), strict=True
    ):
        for j, layer in enumerate(layers):
            ax.plot(
                np.asarray(steps) / 1e6,
                np.asarray(sigma)[:, j],
                marker="o",
                ms=3,
                color=color,
                ls=styles[j % len(styles)],
                label=f"{name}, {layer}",
            )
    ax.set_xlabel("env steps (millions)")
    ax.set_ylabel("mean sigma of the layer's type pairs")
    ax.legend(fontsize=8, ncol=2)
    return ax


def plot_pair(x, y, a: str, b: str, mean_network=None, ax=None):
    """Each individual's mean return on condition ``a`` vs ``b`` (``x``, ``y``: the
    individuals' returns, individuals x episodes, on each), SEM over episodes as bars, with
    the least-squares line and its 95 % band (seaborn's bootstrap, seeded); the mean
    network's mean returns as a star where ``mean_network`` (its returns on ``a`` and on
    ``b``) is given."""
    ax = axes_or_new(ax)
    x, y = np.asarray(x), np.asarray(y)
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
    if mean_network is not None:
        ax.plot(
            np.mean(mean_network[0]),
            np.mean(mean_network[1]),
            "*",
            ms=14,
            color=PALETTE["mean_network"],
            label="mean network",
        )
    sns.regplot(
        x=x.mean(1),
        y=y.mean(1),
        scatter=False,
        ci=95,
        seed=0,
        ax=ax,
        color=PALETTE["individuals"],
        line_kws={"lw": 1, "label": "least-squares fit, 95 % band"},
    )
    r = stats.fisher_r(x.mean(1), y.mean(1))
    ax.set_xlabel(f"return, {a.replace('_', ' ')}")
    ax.set_ylabel(f"return, {b.replace('_', ' ')}")
    ax.set_title(f"Pearson r = {r.estimate:.2f} (p = {r.p:.2g}, n = {x.shape[0]})")
    ax.legend(loc="upper left")
    return ax


def plot_mean_network(individuals, mean_network, ax=None):
    """Figure 5, our protocol: the individuals' mean returns beside the mean network's on
    the same initial states (both individuals x episodes), as distributions with 99 % CIs
    of their means, and the paired t-test."""
    ind = np.asarray(individuals).mean(1)
    mean_net = np.asarray(mean_network).mean(1)
    t = stats.paired(ind, mean_net)
    title = f"paired t({t.dof}) = {t.statistic:.1f}, p = {t.p:.2g}"
    return _population_and_mean_network(ind, mean_net, title, "innate return", ax)


def plot_authors_protocol(protocol: Record, ax=None):
    """Figure 5, the authors' protocol (``sgb.rl.protocols.authors_protocol``, read back as
    ``sgb.experiments.fig4_5.AuthorsProtocol``): the
    individuals' mean returns (sampled actions) beside the mean network's episodes, as
    distributions with 99 % CIs of their means, and the one-sample t-test."""
    ind = np.asarray(protocol.individuals).mean(1)
    title = f"one-sample t({protocol.dof}) = {protocol.t:.1f}, p = {protocol.p:.2g}"
    mean_net = np.asarray(protocol.mean_network)
    return _population_and_mean_network(ind, mean_net, title, "return, sampled actions", ax)


def _population_and_mean_network(ind, mean_net, title: str, ylabel: str, ax):
    """The individuals' mean returns and the mean network's returns as two distributions
    side by side (a violin, every value a dot), each with its mean and 99 % CI in black
    beside it."""
    ax = axes_or_new(ax)
    groups = {"individuals": np.asarray(ind), "mean network": np.asarray(mean_net)}
    frame = {
        "who": [name for name, v in groups.items() for _ in v],
        "return": np.concatenate(list(groups.values())),
    }
    colors = [PALETTE["individuals"], PALETTE["mean_network"]]
    sns.violinplot(
        frame,
        x="who",
        y="return",
        hue="who",
        palette=colors,
        inner=None,
        cut=0,
        density_norm="width",
        linewidth=0,
        ax=ax,
    )
    for collection in ax.collections:
        collection.set_alpha(0.3)
    sns.stripplot(
        frame,
        x="who",
        y="return",
        hue="who",
        palette=colors,
        size=2,
        alpha=0.6,
        jitter=0.25,
        legend=False,
        ax=ax,
    )
    for i, values in enumerate(groups.values()):
        mean, low, high = stats.mean_ci(values, 0.99)
        ax.errorbar(
            i + 0.38,
            mean,
            yerr=[[mean - low], [high - mean]],
            fmt="o",
            ms=4,
            capsize=3,
            color="k",
        )
    ax.set_xlabel("")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    return ax


def plot_spread(summary: list[Record], axes=None):
    """Against the initial sigma (log axis): the individuals' mean return minus the mean
    network's (left) and the standard deviation of the individuals' returns (right);
    bars are the SEM over seeds; ``summary``: the spread sweep's, one row per spread
    (``sgb.experiments.rl_spread.SpreadSummary``)."""
    axes = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.2))
    sigma = [r.sigma_init for r in summary]
    advantage = [(r.advantage, r.sem_advantage) for r in summary]
    spread = [(r.individuals_sd, r.sem_individuals_sd) for r in summary]
    panels = (
        (advantage, "individuals - mean network (return)", PALETTE["individuals"]),
        (spread, "SD of individuals' returns", PALETTE["sgb"]),
    )
    for ax, (points, label, color) in zip(axes, panels, strict=True):
        values, errors = [v for v, _ in points], [e for _, e in points]
        ax.errorbar(sigma, values, yerr=errors, marker="o", capsize=3, color=color)
        ax.set_xscale("log")
        ax.set_xlabel(r"initial $\sigma$ of every type pair")
        ax.set_ylabel(label)
    axes[0].axhline(0.0, color=PALETTE["mean_network"], ls="--", label="mean network")
    axes[0].legend(loc="best", fontsize=8)
    return axes


def plot_backends(bench: BenchBackendsResults, axes=None):
    """``benchmarks/bench_backends.py``'s results: training env-steps/s per Brax backend
    (left) and the learning curve of vanilla PPO on the fastest one (right)."""
    axes = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.4))
    speeds = bench.throughput
    axes[0].barh(list(speeds), [s.train_steps_per_s for s in speeds.values()])
    axes[0].invert_yaxis()
    axes[0].set_ylabel("Brax backend")
    axes[0].set_xlabel("training env-steps/s")
    axes[0].set_title(f"{bench.env}: vanilla PPO,\n{bench.throughput_steps:,} steps")
    reach = bench.reach
    axes[1].plot(np.array(reach.eval_steps) / 1e6, reach.eval_returns, marker="o")
    axes[1].set_xlabel("training env steps (millions)")
    axes[1].set_ylabel("evaluation return")
    axes[1].set_title(f"vanilla PPO on {reach.backend}")
    return axes


def show_images(images: dict[str, np.ndarray], axes=None):
    """Rendered frames (height, width, 3), two a row, titled by their keys."""
    axes = panels(axes, len(images), 2.8)
    for ax, (title, image) in zip(axes, images.items(), strict=True):
        ax.imshow(image)
        ax.set_title(title)
        ax.set_axis_off()
    return axes


def _font(size: int):
    """PIL's default font at ``size`` pixels (a scalable one where Pillow has FreeType)."""
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: one small bitmap font
        return ImageFont.load_default()


def _band(width: int, height: int, texts: list[str], font_size: int) -> np.ndarray:
    """A white band (height, width, 3) with ``texts`` centred in equal columns."""
    from PIL import Image, ImageDraw

    band = Image.new("RGB", (width, height), "white")
    draw = ImageDraw.Draw(band)
    font = _font(font_size)
    column = width / len(texts)
    for i, text in enumerate(texts):
        draw.text(((i + 0.5) * column, height / 2), text, fill="black", font=font, anchor="mm")
    return np.asarray(band)


def label_tiles(
    frames: np.ndarray, labels: list[str], title: str | None = None, font_size: int = 13
) -> np.ndarray:
    """Frames (T, height, n * width, 3) of n tiles side by side (``walking_frames``), with
    each tile's label in a white band above it and, if given, ``title`` in a band above
    the row: (T, height + bands, n * width, 3), the frames themselves unchanged below."""
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[-1] != 3:
        raise ValueError(f"frames must be (T, height, width, 3), got shape {frames.shape}")
    if not labels or frames.shape[2] % len(labels):
        raise ValueError(
            f"{len(labels)} labels do not split {frames.shape[2]} pixels into equal tiles"
        )
    height = int(1.7 * font_size)
    bands = [_band(frames.shape[2], height, list(labels), font_size)]
    if title is not None:
        bands.insert(0, _band(frames.shape[2], height, [title], font_size + 1))
    top = np.concatenate(bands, axis=0).astype(frames.dtype)
    return np.concatenate([np.broadcast_to(top, (len(frames), *top.shape)), frames], axis=1)


def stack_rows(rows: list[np.ndarray], gap: int = 6) -> np.ndarray:
    """Labelled rows of frames (``label_tiles``), each (T, h_i, width, 3), one above the
    other with a white gap of ``gap`` pixels: one animation of them all. Rows of different
    lengths are cut to the shortest."""
    length = min(len(r) for r in rows)
    width = rows[0].shape[2]
    if any(r.shape[2] != width for r in rows):
        raise ValueError(f"rows must be equally wide, got {[r.shape[2] for r in rows]}")
    white = np.full((length, gap, width, 3), 255, dtype=rows[0].dtype)
    parts = []
    for i, row in enumerate(rows):
        parts.extend([white] * (i > 0) + [row[:length]])
    return np.concatenate(parts, axis=1)
