"""Experiments behind the book's figures, run by ``python -m sgb reproduce``.

Each experiment is registered once, in ``EXPERIMENTS``, by the module that holds
it, its run function ``run(profile: str, out_dir: Path, **options) -> Path`` (which
writes a results file with provenance and returns its path), its profiles
(a dict profile name -> the config that ``run`` uses at that profile), the chapter of
the book it belongs to (``CHAPTERS``), and what ``python -m sgb reproduce --help`` says
of it: the paper figure, the datasets or environments, and the cost of each profile.
"""

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

# The book's chapters that run experiments (book/0N_*.ipynb), by number.
CHAPTERS = {
    2: "Bayes by backprop",
    3: "The Jensen gap",
    4: "DGB versus SGB under compression",
    5: "Populations of walkers: SGB agents in Brax",
    6: "Beyond the paper",
}


@dataclass(frozen=True)
class Experiment:
    """Where an experiment lives (a module under sgb.experiments and two of its names), its
    chapter (a key of ``CHAPTERS``) and what ``--help`` says of it: its paper figure, its
    inputs and its cost per profile."""

    module: str
    run_name: str = "run"
    profiles_name: str = "PROFILES"
    chapter: int = field(kw_only=True)
    figure: str = ""  # the paper figure it reproduces, or what it adds to the paper
    inputs: str = ""  # its datasets or environments, and the option that picks one
    costs: dict[str, str] = field(default_factory=dict)  # profile -> what a run costs
    shares_runs: bool = False  # its runs take locks, so several workers can share it
    # part ("" for one file, else a body) -> the committed results file the book reads
    results: dict[str, str] = field(default_factory=dict)
    record_name: str = ""  # the model of its results files (a pydantic class in its module)
    evidence_name: str = "evidence"  # its scorecard rows: evidence(records) -> list[Row]
    queued_name: str = "queued"  # its runs for the background queue (``sgb.grid``)

    def _module(self):
        return importlib.import_module(f"sgb.experiments.{self.module}")

    @property
    def run(self) -> Callable[..., Path]:
        """``run(profile, out_dir, **options) -> Path`` of the results file."""
        return getattr(self._module(), self.run_name)

    @property
    def profiles(self) -> dict[str, Any]:
        """Profile name -> the config ``run`` uses at that profile."""
        return getattr(self._module(), self.profiles_name)

    @property
    def record(self) -> type | None:
        """The model of its results files (``sgb.schemas.ResultsFile``), or None."""
        return getattr(self._module(), self.record_name) if self.record_name else None

    @property
    def evidence(self) -> Callable[..., list] | None:
        """``evidence(records) -> list[claims.Row]``, its rows of the scorecard, or None."""
        return getattr(self._module(), self.evidence_name, None)

    @property
    def texts(self) -> Callable[..., dict[str, str]] | None:
        """``texts(records, card) -> dict[str, str]``, what its chapter glues (its module's,
        shared by the experiments of one module), or None."""
        return getattr(self._module(), "texts", None)


# Costs: cpu wall times from the provenance of the committed results (results/*_cpu.json,
# results/rl/*_cpu.json and the checkpoints' own), on a machine of 2 CPU cores; smoke
# times are of one `.ci/smoke-keeps-results` run on the same machine while two training
# runs held its cores (on idle cores they are shorter). "Not measured" is said where no
# run was ever made.
_TWO_CORES = "on 2 CPU cores"
_SHARED = "on 2 CPU cores busy with other runs"
EXPERIMENTS: dict[str, Experiment] = {
    "bbb": Experiment(
        "bayes_by_backprop",
        chapter=2,
        figure="Bayes by backprop (the method; no paper figure)",
        inputs="a toy 1-D regression and the digits data (both offline)",
        costs={
            "smoke": f"41 s {_SHARED}",
            "cpu": "not measured (3 seeds, 40 epochs; no committed run)",
            "paper": "the cpu run (the same config)",
        },
    ),
    "theory": Experiment(
        "theory",
        chapter=3,
        figure="Fig. 6, the Jensen gap on 1-D toy losses, and on trained SGB classifiers",
        inputs="toy losses and the digits data (offline)",
        costs={
            "smoke": f"2 min {_SHARED}",
            "cpu": f"34 s {_TWO_CORES}",
            "paper": "not measured (10,000 noise draws per gap, an 81 x 50 start grid)",
        },
        results={"": "theory_cpu.json"},
        record_name="Theory",
    ),
    "saddle": Experiment(
        "saddle",
        chapter=3,
        figure="beyond Fig. 6: Appendix A.2's saddle points, the whole Hessian at the means of "
        "chapter 3's digits classifiers",
        inputs="the digits data (offline); chapter 3's two classifiers, 5 seeds each",
        costs={
            "smoke": "2 classifiers x 2 seeds of 2 epochs, not measured",
            "cpu": "10 networks, each about 5 s to train and 4-8 s for its 2,368 x 2,368 "
            "Hessian and eigenvalues on one core",
            "paper": "the cpu run (the same config)",
        },
        results={"": "saddle_cpu.json"},
        record_name="Saddle",
    ),
    "fig2": Experiment(
        "fig2",
        chapter=4,
        figure="Fig. 2, innate accuracy of the DGB and the SGB across compression",
        inputs="--dataset digits or mnist1d (offline, every profile), fashion-mnist or "
        "mnist (cpu and paper; the Debian package or a download), cifar10 (paper; download)",
        costs={
            "smoke": f"39 s (digits) {_SHARED}",
            "cpu": f"fashion-mnist 22 min {_TWO_CORES}; digits, mnist1d and mnist (the "
            "fashion-mnist sweep) not measured at the present config; resumable",
            "paper": "not measured (50 epochs, 5 seeds; cifar10 200 epochs); needs a GPU",
        },
        results={"": "fig2_fashion-mnist_cpu.json"},
        record_name="Fig2",
    ),
    "dgb_budget": Experiment(
        "dgb_budget",
        chapter=4,
        figure="beyond Fig. 2: the DGB at the lowest compression trained for "
        "the authors' budget, and the uncompressed network at the same budget",
        inputs="fashion-mnist (cpu and paper), digits (smoke)",
        costs={
            "smoke": f"16 s {_SHARED}",
            "cpu": f"51 min {_TWO_CORES}; resumable",
            "paper": "the cpu run (the same config)",
        },
        results={"": "dgb_budget_fashion-mnist_cpu.json"},
        record_name="DgbBudget",
    ),
    "dgb_full": Experiment(
        "dgb_full",
        chapter=4,
        figure="Fig. 2's DGB as the authors ran it (their g-net layout, 500 rounds, best "
        "validation) at 200x, 400x and 700x, 3 seeds",
        inputs="fashion-mnist (cpu and paper), digits (smoke)",
        costs={
            "smoke": "one cell of 4 rounds, not measured",
            "cpu": "9 cells, each about 45 minutes of 2 CPU cores (not yet measured); "
            "resumable, and several processes share it",
            "paper": "the cpu run (the same config)",
        },
        shares_runs=True,
        results={"": "dgb_full_fashion-mnist_cpu.json"},
        record_name="DgbFull",
    ),
    "sgb_full": Experiment(
        "sgb_full",
        chapter=4,
        figure="Fig. 2's SGB as the paper and the authors train it (50 epochs, 3 weight "
        "draws, rho from -7), also with the KL per type pair and with rho from -5, at all "
        "7 ratios x 3 seeds",
        inputs="fashion-mnist (cpu and paper), digits (smoke)",
        costs={
            "smoke": "3 cells of one epoch, not measured",
            "cpu": "63 cells, each about 10-15 minutes of one core (one epoch took 19-20 s "
            "on a core shared with other runs); resumable, and several processes share it",
            "paper": "105 cells (5 seeds), not measured",
        },
        shares_runs=True,
        results={"": "sgb_full_fashion-mnist_cpu.json"},
        record_name="SgbFull",
    ),
    "dgb_high": Experiment(
        "dgb_full",
        "run_high",
        "HIGH_PROFILES",
        chapter=4,
        figure="Fig. 2's high end, the DGB: dgb_full's cells at the g-net widths the authors' "
        "script builds for the paper's nominal 1,500x and 3,000x, 5 seeds",
        inputs="fashion-mnist (cpu and paper), digits (smoke)",
        costs={
            "smoke": "dgb_full's smoke cell",
            "cpu": "10 cells, each about 5 minutes of one core (dgb_full's at 700x); "
            "resumable, and several processes share it",
            "paper": "the cpu run (the same config)",
        },
        shares_runs=True,
        results={"": "dgb_high_fashion-mnist_cpu.json"},
        record_name="DgbFull",
        evidence_name="",
        queued_name="queued_high",
    ),
    "sgb_high": Experiment(
        "sgb_full",
        "run_high",
        "HIGH_PROFILES",
        chapter=4,
        figure="Fig. 2's high end, the SGB: sgb_full's authors' SGB at 3, 5, 10 and 20 hidden "
        "types, 5 seeds",
        inputs="fashion-mnist (cpu and paper), digits (smoke)",
        costs={
            "smoke": "sgb_full's smoke cell, the authors' variant",
            "cpu": "20 cells, each about 10-15 minutes of one core (sgb_full's at 400x); "
            "several processes share it",
            "paper": "the cpu run (the same config)",
        },
        shares_runs=True,
        results={"": "sgb_high_fashion-mnist_cpu.json"},
        record_name="SgbFull",
        evidence_name="",
        queued_name="queued_high",
    ),
    "width": Experiment(
        "width",
        chapter=4,
        figure="beyond Fig. 2: the abstract's greater benefit in large networks, the authors' "
        "SGB (10 hidden types) against their DGB at the same compression, hidden widths "
        "200, 800 and 3,200",
        inputs="fashion-mnist (cpu and paper), digits (smoke)",
        costs={
            "smoke": "2 widths x 2 models, 1 epoch or 2 rounds, not measured",
            "cpu": "18 cells, about 5.4 hours of one core (estimated from sgb_full's and "
            "dgb_full's cells at width 800, scaled by the width); several processes share it",
            "paper": "the cpu run (the same config)",
        },
        shares_runs=True,
        results={"": "width_fashion-mnist_cpu.json"},
        record_name="Width",
    ),
    "fig3": Experiment(
        "fig3",
        "run_fig3",
        "FIG3_PROFILES",
        chapter=5,
        figure="Fig. 3, return against the number of cell types (Brax PPO)",
        inputs="--env ant (default) or halfcheetah",
        costs={
            "smoke": f"3 runs of 4096 steps, 3.5 min {_SHARED}",
            "cpu": "ant 80 runs, halfcheetah 37 runs, of 2M steps each; an Ant run took "
            "3 to 8 minutes (the committed checkpoints); resumable, and several processes "
            "share a sweep",
            "paper": "55 runs of 50M steps per environment, not measured; needs a GPU",
        },
        shares_runs=True,
        results={"ant": "rl/fig3_ant_cpu.json", "halfcheetah": "rl/fig3_halfcheetah_cpu.json"},
        record_name="Fig3",
    ),
    "fig4": Experiment(
        "fig4_5",
        "run_fig4",
        "FIG4_PROFILES",
        chapter=5,
        figure="Fig. 4E/F, individuals of one genome on normal and long legs, on two niches",
        inputs="--env ant (Ant bodies and worlds); evaluates Fig. 3's 64-type seed-0 "
        "checkpoint (the committed cpu one at smoke and cpu)",
        costs={
            "smoke": f"71 s {_SHARED}",
            "cpu": f"169 s {_TWO_CORES}",
            "paper": "not measured; needs fig3's paper checkpoint and a GPU",
        },
        results={"": "rl/fig4_ant_cpu.json"},
        evidence_name="fig4_evidence",
        record_name="Fig4",
    ),
    "fig5": Experiment(
        "fig4_5",
        "run_fig5",
        "FIG5_PROFILES",
        chapter=5,
        figure="Fig. 5, sampled individuals against the mean network",
        inputs="--env ant; the same checkpoint as fig4",
        costs={
            "smoke": f"75 s {_SHARED}",
            "cpu": f"279 s {_TWO_CORES}",
            "paper": "not measured; needs fig3's paper checkpoint and a GPU",
        },
        results={"": "rl/fig5_ant_cpu.json"},
        evidence_name="fig5_evidence",
        record_name="Fig5",
    ),
    "bet_hedging": Experiment(
        "bet_hedging",
        chapter=6,
        figure="bet-hedging: a genome's individuals against clones of its mean "
        "network and against a deterministic lineage, in a world that changes among four "
        "conditions (the abstract's 'at least some individuals will survive')",
        inputs="the Ant on normal, long legs, slippery and low gravity; 64-type genomes "
        "trained with Figure 3's PPO from rho -5 (Figure 3's own at seeds 0-4) and -3 (the "
        "spread sweep's at seeds 0-2), and the sigma = 0 lineage (rho -30), trained if missing",
        costs={
            "smoke": "2 genomes trained at smoke, 50 members x 2 + 2 episodes of 50 steps; "
            "about 3 CPU-minutes, most of it compiling",
            "cpu": "45 genomes (37 to train, about 5 CPU-minutes each) x 8M env-steps "
            "(4M for the lineage), about 8 hours of one CPU core; resumable, shared by "
            "the background queue's workers",
            "paper": "the same genomes trained at paper, 16 + 16 episodes; not measured",
        },
        results={"": "rl/bet_hedging_ant_cpu.json"},
        record_name="BetHedging",
    ),
    "evolution": Experiment(
        "evolution",
        chapter=6,
        figure="evolution without gradients: genomes whose spread is held at sigma = 0 "
        "(deterministic) and at three levels, their means evolved by OpenAI-ES from innate "
        "fitness alone, with equal fitness evaluations",
        inputs="digits (Fashion-MNIST at paper); 8 hidden types, 4 spreads, 5 seeds",
        costs={
            "smoke": "2 cells of 20 generations, seconds",
            "cpu": "20 cells of 10,000 generations, about 70 min of one CPU core (1,267 "
            "CPU-seconds measured at 3000 generations); resumable, in the background queue",
            "paper": "Fashion-MNIST, 64 hidden neurons, 40,000 generations; not measured",
        },
        results={"": "evolution_digits_cpu.json"},
        record_name="Evolution",
    ),
    "innate_start": Experiment(
        "innate_start",
        chapter=6,
        figure="innate start then learning: Ant genomes' mean network, best of 100 "
        "and a random individual, fine-tuned with PPO on the long-legged Ant, against a fresh "
        "network",
        inputs="--env ant; Fig. 3's 64-type seed-0 checkpoints (ours, the authors' settings, "
        "and rho -3 of spread; the committed cpu ones at smoke and cpu)",
        costs={
            "smoke": f"4 runs of 4096 steps and a selection of 8 x 2 episodes, 77 CPU-seconds "
            f"(102 s {_SHARED})",
            "cpu": "30 runs of 5M steps (3 genomes x 3 starts x 3 seeds, 3 fresh) and 3 "
            "selections of 100 x 16 episodes, about 2.8 hours of one CPU core (estimated from "
            "16,600 env-steps per CPU-second); resumable",
            "paper": "50 runs of 5 x 10^7 steps, not measured; needs fig3's paper checkpoints "
            "and a GPU",
        },
        results={"": "rl/innate_start_ant_cpu.json"},
        record_name="InnateStart",
    ),
    "innate_start_supervised": Experiment(
        "innate_start_supervised",
        chapter=6,
        figure="innate start then learning a new task, supervised: an SGB trained on five "
        "classes; its 10 individuals, its mean network (their hidden layers, a fresh output "
        "layer each) and 10 fresh networks learn the other five as plain MLPs",
        inputs="Fashion-MNIST (digits at smoke), classes 0-4 then 5-9; Fig. 2's cpu SGB at "
        "10x, 5 seeds",
        costs={
            "smoke": "about 20 CPU-seconds",
            "cpu": "5 seeds, about a minute of one CPU core each; resumable",
            "paper": "the cpu design on Fig. 2's paper SGB (50 epochs), 5 seeds; not measured",
        },
        results={"": "innate_start_supervised_fashion-mnist_cpu.json"},
        record_name="InnateStartSupervised",
    ),
    "mean_gap": Experiment(
        "mean_gap",
        chapter=4,
        figure="why Fig. 2's SGB individuals beat their mean network: the moment-matched "
        "mean network beside both",
        inputs="Fashion-MNIST (digits at smoke); fig2's cells at 10x and 400x, and 10x from "
        "the authors' rho start",
        costs={
            "smoke": f"under a minute {_TWO_CORES}",
            "cpu": f"9 cells, 408 s {_TWO_CORES} (shared with other runs)",
            "paper": "the cpu cells at the paper's 50 epochs, not measured",
        },
        results={"": "mean_gap_fashion-mnist_cpu.json"},
        record_name="MeanGap",
    ),
    "regime": Experiment(
        "regime",
        chapter=5,
        figure="Fig. 3C at the paper's 5 x 10^7 steps under the authors' own training "
        "regime, 3 seeds per point, and the genomes of Figs. 4E and 5",
        inputs="the Ant (spring)",
        costs={
            "smoke": f"2 runs of 320 steps, 76 s {_TWO_CORES}",
            "cpu": "18 runs of 5 x 10^7 steps (vanilla, 128, 64, 32 and 16 types, and 16 "
            "types with the authors' aliased pairs; seeds 0-2), each about 1.3 hours of "
            "one idle CPU core with its 11 evaluations (benchmarks/bench_regime.py); "
            "resumable, and several processes share it",
            "paper": "the cpu runs; not measured on a GPU",
        },
        shares_runs=True,
        results={"": "rl/regime_ant_cpu.json"},
        record_name="Regime",
    ),
    "regime_peer": Experiment(
        "regime_peer",
        chapter=5,
        figure="the authors' regime beside their own code at 1,638,400 steps: vanilla and "
        "their aliased 64 types, 3 seeds each, against the one run of theirs",
        inputs="the Ant (spring)",
        costs={
            "smoke": "2 runs of 320 steps, not measured",
            "cpu": "6 runs of 1,638,400 steps with 3 evaluations on 256 environments, "
            "not yet measured; resumable",
            "paper": "the cpu runs",
        },
        shares_runs=True,
        results={"": "rl/regime_peer_ant_cpu.json"},
        record_name="RegimePeer",
    ),
    "regime_gait": Experiment(
        "regime_gait",
        chapter=5,
        figure="whether the agents of Fig. 3C at 5 x 10^7 steps walk: each regime run's "
        "forward velocity on the authors' evaluation window",
        inputs="the regime's checkpoints (at smoke, of `reproduce regime --profile smoke` "
        "in the same results directory)",
        costs={
            "smoke": "2 windows of 4 x 64 steps, not measured",
            "cpu": "256 x 1000 env-steps per finished regime run, 15-24 s of one core each "
            "(11 runs: 200 s); resumable; in the background queue, which plays the runs landed "
            "since it last started",
            "paper": "the cpu runs; not measured on a GPU",
        },
        results={"": "rl/regime_gait_ant_cpu.json"},
        record_name="RegimeGait",
    ),
    "populations": Experiment(
        "populations",
        chapter=5,
        figure="beyond Fig. 4E and 5: individuals of 6 genomes (ours and the authors', 64 "
        "types), 32 episodes each, on normal and long legs, against their mean networks",
        inputs="--env ant; evaluates Fig. 3's 64-type checkpoints, seeds 0 to 2 of both "
        "settings (the committed cpu ones at smoke and cpu)",
        costs={
            "smoke": f"about a minute {_TWO_CORES}",
            "cpu": "57.6M env-steps, about an hour of one CPU core; resumable",
            "paper": "not measured; needs fig3's paper checkpoints and a GPU",
        },
        results={"": "rl/populations_ant_cpu.json"},
        record_name="Populations",
    ),
    "regime_populations": Experiment(
        "populations",
        "run_regime",
        "REGIME_PROFILES",
        chapter=5,
        figure="Fig. 4E and 5 and the title's claim on every SGB genome of the authors' regime "
        "at 5e7 steps (128, 16, 64 and 32 types, seeds 0-2, as each lands): 100 individuals "
        "x 64 episodes on both bodies with sampled actions (their protocol; their one-sample "
        "t beside Welch's), and for the 64 types with deterministic actions too (ours)",
        inputs="the Ant; the regime's checkpoints (at smoke, of `reproduce regime "
        "--profile smoke` in the same results directory); a genome whose run has not landed "
        "waits",
        costs={
            "smoke": "6 parts of 4 x 3 episodes, not measured",
            "cpu": "19.2M env-steps a genome (38.4M for the 64 types), about 20 min (40) of "
            "one CPU core each; resumable",
            "paper": "the cpu design on the paper's checkpoints; not measured",
        },
        results={"": "rl/regime_populations_ant_cpu.json"},
        evidence_name="regime_evidence",
        record_name="RegimePopulations",
    ),
    "spread": Experiment(
        "rl_spread",
        chapter=5,
        figure="beyond Fig. 5: individuals against the mean network across initial spreads",
        inputs="--env ant",
        costs={
            "smoke": f"2 runs of 4096 steps, 2.5 min {_SHARED}",
            "cpu": f"9 runs of 2M steps (the 3 at the default spread are fig3's), "
            f"42 min {_TWO_CORES}; resumable",
            "paper": "15 runs of 50M steps, not measured; needs a GPU",
        },
        results={"": "rl/spread_ant_cpu.json"},
        record_name="Spread",
    ),
}


def results_files() -> dict[str, tuple[dict[str, str], type]]:
    """Experiment -> (part -> the committed results file the book reads of it, the model
    of its files)."""
    return {name: (e.results, e.record) for name, e in EXPERIMENTS.items() if e.results}


def get_experiment(name: str) -> Experiment:
    """The registered experiment ``name``."""
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; available: {sorted(EXPERIMENTS)}")
    return EXPERIMENTS[name]
