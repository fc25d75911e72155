"""What the chapters' prose says of the committed results: glue name -> markdown text.

Each function returns every name its part of a chapter glues (``book.glue_all``), so a
chapter cell is one call. A scorecard row missing from ``card`` (its results not yet
run) gives ``NOT_RUN`` for each of its names; a missing results file (``None``) gives
the fallback its function names.
"""

import math
from importlib import metadata

import numpy as np

from sgb import claims, stats
from sgb.claims import Row
from sgb.results import Payload
from sgb.rl.regimes import authors_scale
from sgb.supervised_sweep import figure2_records

NOT_RUN = "not yet run"
ROW_PARTS = ("verdict", "ours", "detectable", "decide")
Card = dict[str, list[Row]]  # claims.by_key(claims.scorecard(...))


def row_texts(name: str, row: Row | None, missing: str = NOT_RUN) -> dict[str, str]:
    """A scorecard row as ``{name}_verdict`` (bold), ``_ours`` (estimate with its 95 %
    interval, "no estimate" without a test), ``_detectable`` (the effect detectable at 80 %
    power, "none" without a test or power) and ``_decide`` (the budget that would decide);
    ``missing`` for each without a row. Words, not a dash, so that prose reads around them."""
    if row is None:
        return {f"{name}_{part}": missing for part in ROW_PARTS}
    detectable = math.nan if row.test is None else row.test.detectable
    return {
        f"{name}_verdict": f"**{row.verdict}**",
        f"{name}_ours": "no estimate" if row.test is None else row.ours,
        f"{name}_detectable": "none" if math.isnan(detectable) else f"{detectable:.3g}",
        f"{name}_decide": row.decide or "nothing more",
    }


def _row(card: Card, key: str, setting: str = "") -> Row | None:
    """The first row of claim ``key`` whose setting names ``setting``, or ``None``."""
    return next((r for r in card.get(key, []) if setting in r.setting), None)


GENOMES = (("our genome", "ours"), ("the authors' genome", "authors"))


# Chapter 5 --------------------------------------------------------------------------------


def backends(bench: Payload) -> dict[str, str]:
    """``mjx_vs_spring`` (MJX's training env-steps/s over spring's), ``fastest_backend`` and
    the installed ``brax_version``, from ``rl/bench_backends.json``."""
    speeds = {name: s["train_steps_per_s"] for name, s in bench["results"]["throughput"].items()}
    return {
        "mjx_vs_spring": f"{speeds['mjx'] / speeds['spring']:.2f}x",
        "fastest_backend": f"`{max(speeds, key=speeds.get)}`",
        "brax_version": metadata.version("brax"),
    }


def _seeds(n: int) -> str:
    return f"{n} seed" + ("" if n == 1 else "s")


def regime(payload: Payload) -> dict[str, str]:
    """The authors' regime (``rl/regime_ant_cpu.json``), from its summary per arm (mean
    final return over seeds): vanilla's mean with its SEM and seeds, its env steps, its mean
    on the authors' scale, its mean env-steps/s and wall time per run (``regime_*``),
    ``regime_sgb``: each SGB arm's mean as a fraction of vanilla's, with its seeds, and the
    scorecard's rows of the level at 128 types and the fall to 16 with the authors' genome
    (``regime_level``, ``regime_fall``: estimate, interval and verdict; "no row yet" while
    an arm they compare has one seed)."""
    runs, summary = payload["results"]["runs"], payload["results"]["summary"]
    steps = payload["provenance"]["config"]["ppo"]["total_steps"]
    card = claims.by_key(claims.regime_rows(payload["results"], steps))
    genome = claims.REGIME_SETTINGS["authors"]
    texts = {}
    for name, key in (("level", "fig3.level_128.regime.ant"), ("fall", "fig3.fall_16.regime.ant")):
        row = next((r for r in card.get(key, []) if r.setting.endswith(genome)), None)
        found = row_texts("row", row)
        texts[f"regime_{name}"] = (
            "no row yet (an arm it compares has one seed)"
            if row is None
            else f"{found['row_ours']}, {found['row_verdict']}"
        )
    vanilla = next(s for s in summary if s["cell_types"] is None)
    mine = [r for r in runs if r["cell_types"] is None]
    n = len(vanilla["seeds"])
    spread = "" if vanilla["sem_return"] is None else f" ± {vanilla['sem_return']:.0f} (SEM)"
    arms = [s for s in summary if s["cell_types"] is not None]
    return {
        "regime_vanilla": f"{vanilla['mean_return']:.0f}{spread} over {_seeds(n)}",
        "regime_steps": f"{mine[0]['eval_steps'][-1]:,}",
        "regime_vanilla_scale": f"{vanilla['mean_authors_scale']:.2f}",
        "regime_speed": f"{np.mean([r['train_steps_per_s'] for r in mine]):,.0f}",
        "regime_wall": f"{np.mean([r['wall_time_s'] for r in mine]) / 3600:.1f} h",
        "regime_sgb": "; ".join(
            f"{s['cell_types']} types"
            + ("" if s["genome"] == "authors" else ", pairs aliased")
            + f": {s['fraction_of_vanilla']:.2f} of vanilla ({_seeds(len(s['seeds']))})"
            for s in arms
        )
        or "none",
    } | texts


def regime_gait(payload: Payload | None) -> dict[str, str]:
    """Whether the regime's agents walk (``sgb.experiments.regime_gait``): each arm's runs'
    forward speeds by seed (``gait_runs``) and how many walk, at least the file's walking
    speed (``gait_walks``)."""
    runs = [] if payload is None else payload["results"]["runs"]
    if not runs:
        return {"gait_runs": NOT_RUN, "gait_walks": NOT_RUN}
    arms = []
    # vanilla first, then from the most cell types to the fewest
    for k in sorted({r["cell_types"] for r in runs}, key=lambda k: (k is not None, -(k or 0))):
        mine = sorted((r for r in runs if r["cell_types"] == k), key=lambda r: r["seed"])
        speeds = ", ".join(f"{r['forward_velocity']:.2f}" for r in mine)
        seeds = ", ".join(str(r["seed"]) for r in mine)
        which = f"seed{'s' * (len(mine) > 1)} {seeds}"
        arms.append(f"{'vanilla' if k is None else f'{k} types'} {speeds} m/s ({which})")
    walking = sum(r["walks"] for r in runs)
    speed = payload["results"]["walking_speed"]
    return {
        "gait_runs": "; ".join(arms),
        "gait_walks": f"{walking} of the {len(runs)} runs walk (at least {speed:g} m/s)",
    }


def regime_peer(payload: Payload | None) -> dict[str, str]:
    """The regime beside the authors' own code at their peer budget
    (``sgb.experiments.regime_peer``), at the last step of each run label (``vanilla``,
    ``aliased``): our seeds' returns and the interval of one more run
    (``peer_{label}_ours``), the authors' return (``peer_{label}_theirs``) and whether it
    lies inside (``peer_{label}_inside``)."""
    out = {}
    rows = [] if payload is None else payload["results"]["comparison"]
    for name, label in (("vanilla", "vanilla"), ("aliased", "k64_aliased")):
        mine = [r for r in rows if r["label"] == label and r["theirs"] is not None]
        last = mine[-1] if mine else None
        if last is None or last["interval"] is None:
            out |= {f"peer_{name}_{part}": NOT_RUN for part in ("ours", "theirs", "inside")}
            continue
        returns = ", ".join(f"{r:.0f}" for r in last["ours"])
        low, high = last["interval"]
        out[f"peer_{name}_ours"] = (
            f"{returns} at {last['step']:,} steps (mean {last['mean']:.0f}; one more run "
            f"within [{low:.0f}, {high:.0f}], 95 %)"
        )
        out[f"peer_{name}_theirs"] = f"{last['theirs']:.1f}"
        out[f"peer_{name}_inside"] = "inside" if last["inside"] else "outside"
    return out


def populations(payload: Payload | None) -> dict[str, str]:
    """The populations experiment (``rl/populations_ant_cpu.json``): ``pop_complete``
    (genomes summarised) and, per genome settings, its Figure 5 and 4E rows
    (``pop_fig5_{ours,authors}_*``, ``pop_fig4e_*``); without the file, "none of the
    genomes" and ``NOT_RUN``."""
    if payload is None:
        return {"pop_complete": "none of the genomes"} | populations_rows_texts([])
    genomes = payload["results"]["genomes"]
    done = sum("summary" in g for g in genomes.values())
    rows = claims.populations_rows(payload["results"])
    return {"pop_complete": f"{done} of {len(genomes)} genomes"} | populations_rows_texts(rows)


def regime_populations(payload: Payload | None) -> dict[str, str]:
    """Figures 4E and 5 on the genome of the authors' regime
    (``rl/regime_populations_ant_cpu.json``): the design (``regime_pop_design``), the
    normal body's test-retest reliability (``regime_pop_retest``: split-half r with its
    95 % interval, and the reliability of the episode mean), and the rows of
    ``claims.regime_population_rows``: Figure 4E (``regime_pop_legs_*``) and Figure 5
    under our protocol (``regime_pop_ours_*``), their one-sample t
    (``regime_pop_theirs_*``) and Welch's (``regime_pop_welch_*``); ``NOT_RUN`` for all
    without the file or its summary."""
    rows = [] if payload is None else claims.regime_population_rows(payload["results"])
    fig5 = [r for r in rows if r.key == "fig5.population_beats_mean"] + [None] * 3
    texts = {"regime_pop_design": NOT_RUN, "regime_pop_retest": NOT_RUN}
    if rows:
        genome = next(g for g in payload["results"]["genomes"].values() if "summary" in g)
        normal = genome["summary"]["normal"]
        split, anova = normal["split_half"], normal["variance_split"]
        texts["regime_pop_design"] = rows[0].budget
        texts["regime_pop_retest"] = (
            f"r = {split['r']:.2f} [{split['r_ci'][0]:.2f}, {split['r_ci'][1]:.2f}] between "
            f"the means of the even and the odd of {split['episodes']} episodes, a "
            f"reliability of {anova['reliability']:.2f} for the mean of all of them"
        )
    texts |= row_texts("regime_pop_legs", next((r for r in rows if r.key == "fig4e.r_legs"), None))
    for name, row in zip(("ours", "theirs", "welch"), fig5, strict=False):
        texts |= row_texts(f"regime_pop_{name}", row)
    return texts


def populations_rows_texts(rows: list[Row]) -> dict[str, str]:
    """``row_texts`` of the populations experiment's Figure 5 and 4E rows per settings."""
    card = claims.by_key(rows)
    texts = {}
    for who, settings in GENOMES:
        for figure, key in (("fig5", "fig5.population_beats_mean"), ("fig4e", "fig4e.r_legs")):
            texts |= row_texts(f"pop_{figure}_{settings}", _row(card, key, who))
    return texts


def _vanilla(prefix: str, payload: Payload) -> dict[str, str]:
    """A Figure 3 sweep's steps per run (``{prefix}_steps``, millions), vanilla PPO's mean
    last-two return over its seeds (``_vanilla``), their number (``_vanilla_n``) and that
    mean on the authors' scale (``_vanilla_theirs``)."""
    results = payload["results"]
    vanilla = [r for r in results["runs"] if r["cell_types"] is None]
    steps = payload["provenance"]["config"]["ppo"]["total_steps"]
    mean = float(np.mean([r["last_two_return"] for r in vanilla]))
    return {
        f"{prefix}_steps": f"{steps / 1e6:g}M",
        f"{prefix}_vanilla": f"{mean:.0f}",
        f"{prefix}_vanilla_n": str(len(vanilla)),
        f"{prefix}_vanilla_theirs": f"{authors_scale(results['env'], mean):.2f}",
    }


def _level_and_fall(prefix: str, env: str, card: Card) -> dict[str, str]:
    """Figure 3's level at 128 types and fall to 16 types on ``env``, per genome settings
    (``{prefix}level_ours_*``, ...), each with ``_power``: the power to detect 0.3."""
    texts = {}
    for who, settings in GENOMES:
        for what in ("level", "fall"):
            key = f"fig3.level_128.{env}" if what == "level" else f"fig3.fall_16.{env}"
            row = _row(card, key, who)
            name = f"{prefix}{what}_{settings}"
            texts |= row_texts(name, row)
            power = None if row is None or row.test is None else stats.power_at(row.test, 0.3)
            texts[f"{name}_power"] = NOT_RUN if power is None else f"{power:.0%}"
    return texts


def figure3(ant: Payload, cheetah: Payload, card: Card) -> dict[str, str]:
    """Figure 3 on both bodies: the sweeps' vanilla numbers (``ant_*``, ``hc_*``), the level
    and fall rows (``level_*``, ``fall_*``, ``cheetah_level_*``, ``cheetah_fall_*``) and the
    typing ablation (``typing_{authors,ours}_*``; "not yet run (fewer than 2 seeds)")."""
    texts = _vanilla("ant", ant) | _vanilla("hc", cheetah)
    texts |= _level_and_fall("", "ant", card) | _level_and_fall("cheetah_", "halfcheetah", card)
    typing = {r.setting.split(",")[0]: r for r in card.get("ch5.typing_explains_fall", [])}
    for who, settings in GENOMES:
        missing = f"{NOT_RUN} (fewer than 2 seeds)"
        texts |= row_texts(f"typing_{settings}", typing.get(who), missing)
    return texts


def figures4_5(card: Card) -> dict[str, str]:
    """Figure 4E's correlation between bodies (``legs_*``) and Figure 5's individuals
    against the mean network under our protocol and the authors' (``fig5_ours_*``,
    ``fig5_theirs_*``): the first rows of each claim, those of the one genome."""
    fig5 = card.get("fig5.population_beats_mean", []) + [None, None]
    texts = row_texts("legs", _row(card, "fig4e.r_legs"))
    return texts | row_texts("fig5_ours", fig5[0]) | row_texts("fig5_theirs", fig5[1])


def variability(card: Card) -> dict[str, str]:
    """The title's claim (``title.variability*`` rows): the genome of the authors' regime
    (``variability_regime``: estimate, interval and verdict) and, per genome settings at
    the cpu sweep's budget, each genome's verdict (``variability_ours``,
    ``variability_authors``); ``NOT_RUN`` where a setting has no row."""
    texts = {}
    regime = _row(card, "title.variability.regime")
    found = row_texts("row", regime)
    shown = f"{found['row_ours']} % of the return, {found['row_verdict']}"
    texts["variability_regime"] = NOT_RUN if regime is None else shown
    for who, settings in GENOMES:
        rows = [r for r in card.get("title.variability", []) if f", {who}, " in r.setting]
        texts[f"variability_{settings}"] = (
            "; ".join(f"{r.setting.split(', ')[-1]}: {r.ours} %, **{r.verdict}**" for r in rows)
            or NOT_RUN
        )
    return texts


# Chapter 4 --------------------------------------------------------------------------------


def _mean_sem(mean: float, sem: float | None, scale: float = 1.0) -> str:
    """``mean ± sem %`` (``sem`` times ``scale``), or the mean alone where the SEM is
    missing (``None`` or NaN: one seed)."""
    if sem is None or math.isnan(sem):
        return f"{mean:.1f} %"
    return f"{mean:.1f} ± {scale * sem:.1f} %"


def _percent(value: float) -> str:
    return f"{100 * value:.1f} %"


def figure2(results: dict, card: Card) -> dict[str, str]:
    """Figure 2 on Fashion-MNIST (``fig2_fashion-mnist_cpu.json``'s results): the
    scorecard rows (``f2_low``, ``f2_high400``, ``f2_high700``, ``f2_slow``, ``f2_cross`` and
    ``f2_cross_theirs``, the crossover under our count and the authors'),
    accuracies (``f2_dense``, ``f2_dgb_10x``, ``f2_dgb_best``, ``f2_sgb_10x``), the mean
    network's range (``f2_meannet_range``) and the crossovers of each count
    (``f2_crossing_{ours,authors}``)."""
    high = card.get("fig2.sgb_better_high", [])
    rows = {
        "f2_low": _row(card, "fig2.dgb_better_low"),
        "f2_high400": high[0] if high else None,
        "f2_high700": high[1] if len(high) > 1 else None,
        "f2_slow": _row(card, "fig2.sgb_declines_slowly"),
        "f2_cross": _row(card, "fig2.crossover", "our count"),
        "f2_cross_theirs": _row(card, "fig2.crossover", "the authors' count"),
    }
    texts = {}
    for name, row in rows.items():
        texts |= row_texts(name, row)
    summary = results["ours"]["summary"]
    means = results["ours"]["summary_mean_network"]["sgb"]["mean"]
    texts |= {
        "f2_dense": _percent(summary["dense"]["mean"][0]),
        "f2_dgb_10x": _percent(summary["dgb"]["mean"][0]),
        "f2_dgb_best": _percent(max(summary["dgb"]["mean"])),
        "f2_sgb_10x": _percent(summary["sgb"]["mean"][0]),
        "f2_meannet_range": f"{100 * min(means[:-1]):.0f}-{100 * max(means):.0f} %",
    }
    for convention in ("ours", "authors"):
        crossings = results[convention]["crossovers"]
        texts[f"f2_crossing_{convention}"] = ", ".join(f"{c:.0f}x" for c in crossings) or "none"
    return texts


def mean_gap(results: dict) -> dict[str, str]:
    """The moment-matched network (``mean_gap_fashion-mnist_cpu.json``'s results): at 10x
    and 400x from rho -5 and at 10x from rho -7 (``gap10``, ``gap400``, ``gap10_rho7``),
    each network's accuracy (% +- SEM), the recovery and the trained sigma; per rho start,
    the hidden layer's rho travel and end (``gap_travel_5``, ``gap_rho_end_7``, ...), and
    the training steps (``gap_steps``)."""
    cells = {(r["setting"], r["rho_init"]): r for r in results["summary"]}
    texts = {}
    for name, cell in (("gap10", (785, -5.0)), ("gap400", (10, -5.0)), ("gap10_rho7", (785, -7.0))):
        row = cells[cell]
        for key in ("accuracy", "mean_network", "moment_network"):
            texts[f"{name}_{key}"] = f"{100 * row[key]:.1f} ± {100 * row[key + '_sem']:.1f} %"
        texts[f"{name}_recovery"] = f"{row['moment_recovery']:.2f}"
        texts[f"{name}_sigma"] = f"{row['sigma_end']:.3f}"
    for r in results["records"]:
        if r["setting"] == 785 and r["seed"] == 0:
            layer = r["layers"][0]
            texts[f"gap_travel_{-r['rho_init']:g}"] = f"{layer['rho_travel_fraction']:.2f}"
            texts[f"gap_rho_end_{-r['rho_init']:g}"] = f"{layer['end']['mean_rho']:.2f}"
    texts["gap_steps"] = str(results["records"][0]["steps"])
    return texts


def dgb_budget(results: dict, dense_accuracy: float) -> dict[str, str]:
    """The DGB budget run (``dgb_budget_fashion-mnist_cpu.json``'s results): test accuracy
    after 25, 100, 250 and 500 rounds (``budget_25``, ...), the first round within 3 points
    of ``dense_accuracy`` (a fraction; ``budget_near_rounds``), the best validation at 500
    (``budget_val_500``) and the uncompressed network at the same budget (``budget_same``,
    ``budget_same_epochs``)."""
    records = results["records"]
    at = {r["rounds"]: r for r in records}
    near = next(r for r in records if r["test_accuracy"] >= dense_accuracy - 0.03)
    same = results["uncompressed_same_budget"]
    texts = {f"budget_{n}": _percent(at[n]["test_accuracy"]) for n in (25, 100, 250, 500)}
    return texts | {
        "budget_near_rounds": str(near["rounds"]),
        "budget_val_500": _percent(at[500]["best_validation_accuracy"]),
        "budget_same": _percent(same["accuracy"]),
        "budget_same_epochs": str(same["epochs"]),
    }


# Chapter 6 --------------------------------------------------------------------------------


def evolution(payload: Payload | None) -> dict[str, str]:
    """Evolution without gradients (``evolution_digits_cpu.json``): the design
    (``evo_design``), per number of hidden types k the two genomes' test accuracies
    (``evo_k{k}_stochastic``, ``evo_k{k}_deterministic``: mean +- SEM over seeds, %), the
    evolved spreads (``evo_sigma``) and the rows of ``claims.evolution_rows``
    (``evo_k{k}_*``); ``NOT_RUN`` for all without the file. Names for k = 2 and 8."""
    texts = {"evo_design": NOT_RUN, "evo_sigma": NOT_RUN}
    for k in (2, 8):
        texts |= {f"evo_k{k}_{g}": NOT_RUN for g in ("stochastic", "deterministic")}
        texts |= row_texts(f"evo_k{k}", None)
    if payload is None:
        return texts
    records = payload["results"]["records"]
    candidates = payload["provenance"]["config"]["base"]["candidates"]
    texts["evo_design"] = (
        f"{len(records[0]['mean_fitness'])} generations of {candidates} candidate genomes, "
        f"{len({r['seed'] for r in records})} seeds"
    )
    sigma = [r["sigma_mean"] for r in records if r["stochastic"]]
    texts["evo_sigma"] = f"{min(sigma):.2f} to {max(sigma):.2f}"
    for k in (2, 8):
        for stochastic, name in ((True, "stochastic"), (False, "deterministic")):
            values = np.array(
                [
                    100 * np.mean(r["individuals"])
                    for r in records
                    if r["hidden_types"] == k and r["stochastic"] is stochastic
                ]
            )
            if values.size > 1:
                sem = values.std(ddof=1) / math.sqrt(values.size)
                texts[f"evo_k{k}_{name}"] = f"{values.mean():.1f} ± {sem:.1f} %"
    card = claims.by_key(claims.evolution_rows(payload["results"]))
    for k in (2, 8):
        texts |= row_texts(
            f"evo_k{k}", _row(card, "ch6.evolution_stochastic_helps", f" {k} hidden")
        )
    return texts


def bet_hedging(payload: Payload | None) -> dict[str, str]:
    """Bet-hedging (``rl/bet_hedging_ant_cpu.json``): the design (``hedge_design``) and, per
    initial spread j (0 the narrowest: rho from -5, -3, -1.5), its trained sigma
    (``hedge{j}_sigma``), both populations' mean return over conditions, members and
    genomes (``hedge{j}_returns``) and the rows of ``claims.bet_hedging_rows``:
    geometric-mean fitness (``hedge{j}_geometric_*``) and survival
    (``hedge{j}_survival_*``); ``NOT_RUN`` for all without the file."""
    texts = {"hedge_design": NOT_RUN}
    for j in range(3):
        texts[f"hedge{j}_sigma"] = texts[f"hedge{j}_returns"] = NOT_RUN
        texts |= row_texts(f"hedge{j}_geometric", None) | row_texts(f"hedge{j}_survival", None)
    if payload is None:
        return texts
    genomes = payload["results"]["genomes"]
    card = claims.by_key(claims.bet_hedging_rows(payload["results"]))
    for j, rho in enumerate(dict.fromkeys(g["rho_init"] for g in genomes)):
        group = [g for g in genomes if g["rho_init"] == rho]
        texts[f"hedge{j}_sigma"] = f"{np.mean([g['sigma_trained'] for g in group]):.2g}"
        mean_return = {
            p: np.mean([np.mean(list(g["returns"][p].values())) for g in group])
            for p in ("individuals", "clones")
        }
        texts[f"hedge{j}_returns"] = (
            f"{mean_return['individuals']:.0f} for the individuals, "
            f"{mean_return['clones']:.0f} for the clones"
        )
        for kind in ("geometric", "survival"):
            row = _row(card, f"ch6.hedging_{kind}", f"rho from {rho:g} ")
            texts |= row_texts(f"hedge{j}_{kind}", row)
            texts["hedge_design"] = NOT_RUN if row is None else row.budget
    return texts


def innate_start(ant: Payload | None, supervised: Payload | None) -> dict[str, str]:
    """Innate start, then learning: what of it is committed (``innate_status``); on the
    Ant, each genome's and start's gain in learning-curve area over the fresh network
    (``innate_rl_rows``: estimate, interval and verdict of ``claims.innate_start_rows``);
    the supervised twin's rows (``innate_sup_{individual,mean}_{area,end}_*``: over the
    epoch and after it)."""
    parts = []
    texts = {"innate_rl_rows": NOT_RUN}
    if ant is None:
        parts.append(f"the Ant runs {NOT_RUN}")
    else:
        runs = ant["results"]["runs"]
        state = "complete" if ant["results"]["complete"] else "in progress"
        parts.append(f"{len(runs)} Ant fine-tuning runs committed ({state})")
        rows = claims.innate_start_rows(ant["results"])
        if rows:
            texts["innate_rl_rows"] = "; ".join(
                f"{r.setting}: {r.ours}, **{r.verdict}**" for r in rows
            )
    card: Card = {}
    if supervised is None:
        parts.append(f"the supervised twin {NOT_RUN}")
    else:
        summary = supervised["results"]["summary"]
        after = ", ".join(
            f"{r['start']} {_mean_sem(100 * r['accuracy'][-1], r['accuracy_sem'][-1], 100)}"
            for r in summary
        )
        parts.append(
            f"the supervised twin on {summary[0]['n_seeds']} seeds, test accuracy after one "
            f"epoch: {after}"
        )
        card = claims.by_key(claims.innate_supervised_rows(supervised["results"]))
    for start in ("individual", "mean"):
        for measure, name in (("over the epoch", "area"), ("after one epoch", "end")):
            row = _row(card, "ch6.innate_start_supervised", f"from {start}, {measure}")
            texts |= row_texts(f"innate_sup_{start}_{name}", row)
    return texts | {"innate_status": "; ".join(parts)}


def figure2_full(dgb_payload: Payload | None, card: Card) -> dict[str, str]:
    """Figure 2 at the authors' budgets: how many of the full-budget DGB's cells have
    finished (``full_dgb_status``) and, at each of its planned ratios r, the scorecard row
    of the SGB as the authors train it against it (``full{r}_verdict``, ``_ours``,
    ``_detectable``, ``_decide``; ``row_texts``), and the crossover's rows under our count
    of compression (``full_cross``) and the authors' (``full_cross_theirs``)."""
    if dgb_payload is None:
        return {"full_dgb_status": NOT_RUN}
    config = dgb_payload["provenance"]["config"]
    planned = len(config["ratios"]) * len(config["seeds"])
    finished = len(figure2_records(dgb_payload["results"], config["dgb"]["rounds"]))
    texts = {"full_dgb_status": f"{finished} of its {planned} cells"}
    authors = claims.SGB_VARIANTS["authors"]
    for ratio in config["ratios"]:
        row = _row(card, "fig2.full.sgb_better_high", f"(target {ratio:g}x), the SGB ({authors})")
        texts |= row_texts(f"full{ratio:.0f}", row)
    for variant in claims.SGB_VARIANTS:
        rows = [
            r
            for r in card.get("fig2.full.sgb_better_high", [])
            if f"the SGB ({claims.SGB_VARIANTS[variant]})" in r.setting
        ]
        texts[f"full_lead_{variant}"] = _leads(rows)
    ours = row_texts("full_cross", _row(card, "fig2.full.crossover", "our count"))
    theirs = _row(card, "fig2.full.crossover", "the authors' count")
    return texts | ours | row_texts("full_cross_theirs", theirs)


def _leads(rows: list[Row]) -> str:
    """Which side leads in ``rows`` (SGB minus DGB, points), in words."""
    if not rows:
        return NOT_RUN
    estimates = [r.test.estimate for r in rows]
    behind = [-e for e in estimates if e < 0]
    ahead = [e for e in estimates if e >= 0]
    parts = []
    for count, gaps, where in ((len(behind), behind, "below"), (len(ahead), ahead, "above")):
        if count:
            span = f"{gaps[0]:.1f}" if count == 1 else f"{min(gaps):.1f} to {max(gaps):.1f}"
            parts.append(f"{where} the DGB at {count} of {len(rows)} ratios (by {span} points)")
    return "; ".join(parts)


def descent(card: Card) -> dict[str, str]:
    """Theorem A.2's conclusion at the end of training (``claims.descent_rows``): the double
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


def kl_share(card: Card) -> dict[str, str]:
    """Section 2.1's KL explanation at about 10x (``claims.kl_share_row``): the row's texts
    (``kl_share_*``) and the DGB's lead it is weighed against (``kl_share_lead``)."""
    row = _row(card, "fig2.kl_explains_low")
    lead = NOT_RUN if row is None else f"{row.paper_effect:.1f} points"
    return row_texts("kl_share", row) | {"kl_share_lead": lead}


def supervised_population(card: Card) -> dict[str, str]:
    """The supervised population against its mean network at the authors' budget
    (``claims.supervised_population_rows``), per KL counting: the range of the
    individuals' lead over the ratios, and how many rows carry each verdict
    (``suppop_authors``, ``suppop_per_pair``)."""
    rows = card.get("abstract.population_beats_mean_supervised", [])
    out = {}
    for name in ("authors", "per_pair"):
        mine = [r for r in rows if f"({claims.SGB_VARIANTS[name]})" in r.setting]
        if not mine:
            out[f"suppop_{name}"] = NOT_RUN
            continue
        leads = [r.test.estimate for r in mine]
        verdicts_found = [r.verdict for r in mine]
        counts = ", ".join(
            f"**{verdicts_found.count(v)}** {v}" for v in dict.fromkeys(verdicts_found)
        )
        out[f"suppop_{name}"] = (
            f"{min(leads):+.1f} to {max(leads):+.1f} points over {len(mine)} ratios ({counts})"
        )
    return out


def _excluding_zero(table) -> int:
    """How many rows of a ``claims.sgb_variant_tests`` table have a 95 % interval without 0."""
    return int(((table["95 % CI low"] > 0) | (table["95 % CI high"] < 0)).sum())


def _variant_shift(table) -> str:
    """A ``claims.sgb_variant_tests`` table in words: the range of its differences, how many
    of its 95 % intervals exclude 0, and the largest difference detectable at 80 % power."""
    if table.empty:
        return NOT_RUN
    shift = table.iloc[:, 0]
    apart = _excluding_zero(table)
    return (
        f"{shift.min():+.1f} to {shift.max():+.1f} points over {len(table)} ratio"
        f"{'s' if len(table) > 1 else ''} ({apart} of whose 95 % intervals exclude 0; "
        f"at 80 % power a difference of {table['detectable at 80 % power'].max():.1f} points "
        "is detected at each)"
    )


def sgb_full(payload: Payload | None) -> dict[str, str]:
    """Figure 2's SGB as the paper and the authors train it (``sgb_full_*_cpu.json``): how
    many of its cells are committed (``full_status``), the authors' variant's individuals
    and mean network at its lowest compression (``full_low``: mean over its seeds, %), the
    range of the trained hidden-layer sigma over all cells of the authors' variant
    (``full_sigma``) and of our rho start (``full_rho_sigma``), and how far the individuals
    of the KL per type pair (``full_pair_shift``) and of our rho start (``full_rho_shift``;
    its mean networks, ``full_rho_mean_shift``) lie from the authors'
    (``claims.sgb_variant_tests``), and at how many ratios the rho
    start makes a difference whose 95 % interval excludes 0 (``full_rho_conclusion``)."""
    names = ("full_status", "full_low", "full_sigma", "full_rho_sigma")
    shifts = ("full_pair_shift", "full_rho_shift", "full_rho_mean_shift", "full_rho_conclusion")
    texts = dict.fromkeys(names + shifts, NOT_RUN)
    if payload is None:
        return texts
    results = payload["results"]
    cells = list(results["cells"].values())
    config = payload["provenance"]["config"]
    planned = (
        len(config["variants"]) * len(config["sweep"]["ratios"]) * len(config["sweep"]["seeds"])
    )
    texts["full_status"] = f"{len(cells)} of its {planned} cells"
    for variant, name in (("authors", "full_sigma"), ("rho_ours", "full_rho_sigma")):
        sigma = [c["layers"][0]["mean_sigma"] for c in cells if c["variant"] == variant]
        if sigma:
            texts[name] = f"{min(sigma):.3f} to {max(sigma):.3f}"
    authors = [c for c in cells if c["variant"] == "authors"]
    if authors:
        low = min(c["compression"] for c in authors)
        at_low = [c for c in authors if c["compression"] == low]
        texts["full_low"] = (
            f"{100 * np.mean([c['accuracy'] for c in at_low]):.1f} % for the individuals and "
            f"{100 * np.mean([c['mean_network'] for c in at_low]):.1f} % for the mean network "
            f"at {low:.0f}x ({len(at_low)} seed{'s' if len(at_low) > 1 else ''})"
        )
    pair, rho = (claims.sgb_variant_tests(results, v) for v in ("per_pair", "rho_ours"))
    texts["full_pair_shift"], texts["full_rho_shift"] = _variant_shift(pair), _variant_shift(rho)
    rho_mean = claims.sgb_variant_tests(results, "rho_ours", score="mean_network")
    texts["full_rho_mean_shift"] = _variant_shift(rho_mean)
    if not rho.empty:
        apart = _excluding_zero(rho)
        texts["full_rho_conclusion"] = (
            f"moves the individuals' accuracy measurably at {apart or 'none'} of the "
            f"{len(rho)} ratio{'s' if len(rho) > 1 else ''}"
        )
    return texts
