"""The authors' regime beside their own code at a peer budget: does their single run lie
within the spread of ours?

Their ``RL/training_torch.py``, run on this machine at seed 0 (``shared/AUTHORS-SETTINGS.md``,
"Their RL code run beside the authors' regime"), recorded its window return on 256
environments at step 0, after 819,200 and after 1,638,400 steps (10 updates of 2048 x 5 x
16): ``THEIRS``. This experiment trains the regime (``sgb.rl.regime_runs``) for the same
1,638,400 steps, evaluated on 256 environments at the same three points, three seeds each
of vanilla and of their aliased layer at 64 types, and puts their value beside the 95 %
prediction interval of one more run of ours (mean +- t(n - 1) SD sqrt(1 + 1/n) over our
seeds): one run of theirs inside it is what runs of one regime would give.
"""

import functools
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import stats as scipy_stats

from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import NOT_RUN, Card
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.rl.regime_runs import RUNS, RegimeRun, RegimeRuns, finished_runs, train_regime
from sgb.rl.runs import CHECKPOINT_DIR
from sgb.schemas import (
    Finite,
    List,
    MaybeEmpty,
    NonNegative,
    Record,
    ResultsFile,
    Return,
    Steps,
    Training,
)

STEPS = 1_638_400  # 10 updates of 2048 environments x 5 steps x 16 unrolls
EVAL_ENVS = 256  # the size of their recorded evaluations
SEEDS = (0, 1, 2)
# Their window returns at THEIR_STEPS (seed 0; vanilla: the last only).
THEIR_STEPS = (0, STEPS // 2, STEPS)
THEIRS = {"vanilla": (None, None, 279.8), "k64_aliased": (-549.6, -496.4, -351.2)}
THEIR_RUNS = ((None, "authors"), (64, "authors_aliased"))  # (cell types, genome) of THEIRS
PEER_DIR = CHECKPOINT_DIR / "peer"  # apart from the regime's own checkpoints of the same name


def peer_config(profile: str) -> RegimeRuns:
    """Vanilla and the aliased 64 types, seeds 0-2, at ``STEPS`` with every evaluation on
    ``EVAL_ENVS`` environments; at smoke, the regime's smoke settings for one seed each."""
    check_profile(profile)
    base = RUNS[profile].ppo
    if profile == "smoke":
        runs = (RegimeRun(None, 0), RegimeRun(64, 0, "authors_aliased"))
        return RegimeRuns(runs, base)
    ppo = replace(
        base,
        total_steps=STEPS,
        num_evals=2,
        eval_individuals=EVAL_ENVS,
        interim_eval_individuals=EVAL_ENVS,
    )
    runs = tuple(RegimeRun(k, s, g) for k, g in THEIR_RUNS for s in SEEDS)
    return RegimeRuns(runs, ppo)


PROFILES = {p: peer_config(p) for p in PROFILE_NAMES}


def run(profile: str, out_dir: Path) -> Path:
    """Train every run not yet trained (each resumable), writing the results after each."""
    recording = start(PROFILES, profile, Path(out_dir) / "rl", "regime_peer_ant")
    checkpoints = Path(out_dir) / PEER_DIR
    write = functools.partial(write_peer, recording, Path(out_dir))
    return train_regime(recording.config, profile, checkpoints, "regime peer", write)


def prediction_interval(values) -> tuple[float, float]:
    """The 95 % interval of one more draw from the normal sample ``values`` (at least 2):
    mean +- t(n - 1) SD sqrt(1 + 1/n)."""
    x = np.asarray(values, dtype=np.float64)
    half = scipy_stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) * np.sqrt(1 + 1 / x.size)
    return float(x.mean() - half), float(x.mean() + half)


def compare(runs: list[dict]) -> list[dict]:
    """Per run label and evaluation point: our seeds' returns, their mean and SD, the
    prediction interval of one more run (2 seeds or more), and the authors' value where
    they evaluated at that step (``THEIR_STEPS``) and whether it lies inside."""
    out = []
    for label, theirs in THEIRS.items():
        mine = [r for r in runs if r["label"] == label]
        for i, recorded in enumerate(theirs):
            ours = [r["eval_returns"][i] for r in mine if len(r["eval_returns"]) > i]
            if not ours:
                continue
            step = mine[0]["eval_steps"][i]
            value = recorded if step == THEIR_STEPS[i] else None
            row = {
                "label": label,
                "step": step,
                "ours": ours,
                "mean": float(np.mean(ours)),
                "sd": float(np.std(ours, ddof=1)) if len(ours) > 1 else None,
                "theirs": value,
                "interval": None,
                "inside": None,
            }
            if len(ours) > 1:
                row["interval"] = prediction_interval(ours)
                if value is not None:
                    row["inside"] = bool(row["interval"][0] <= value <= row["interval"][1])
            out.append(row)
    return out


def write_peer(recording: Recording, out_dir: Path) -> Path:
    """Write every finished run's learning curve and the comparison with the authors' run."""
    config = recording.config
    runs = [
        {"label": r.label, "cell_types": r.cell_types, "seed": r.seed, **record}
        for r, record in finished_runs(config, recording.profile, out_dir / PEER_DIR)
    ]
    results = {"env": "ant", "runs": runs, "comparison": compare(runs)}
    return recording.write(results, sorted({r["seed"] for r in runs}), parts=runs)


def regime_peer(results: "RegimePeerResults | None") -> dict[str, str]:
    """The regime beside the authors' own code at their peer budget (the results of
    ``sgb.experiments.regime_peer``), at the last step of each run label (``vanilla``,
    ``aliased``): our seeds' returns and the interval of one more run
    (``peer_{label}_ours``), the authors' return (``peer_{label}_theirs``) and whether it
    lies inside (``peer_{label}_inside``)."""
    out = {}
    rows = [] if results is None else results.comparison
    for name, label in (("vanilla", "vanilla"), ("aliased", "k64_aliased")):
        mine = [r for r in rows if r.label == label and r.theirs is not None]
        last = mine[-1] if mine else None
        if last is None or last.interval is None:
            out |= {f"peer_{name}_{part}": NOT_RUN for part in ("ours", "theirs", "inside")}
            continue
        returns = ", ".join(f"{r:.0f}" for r in last.ours)
        low, high = last.interval
        out[f"peer_{name}_ours"] = (
            f"{returns} at {last.step:,} steps (mean {last.mean:.0f}; one more run "
            f"within [{low:.0f}, {high:.0f}], 95 %)"
        )
        out[f"peer_{name}_theirs"] = f"{last.theirs:.1f}"
        out[f"peer_{name}_inside"] = "inside" if last.inside else "outside"
    return out


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of the regime beside the authors' code (``regime_peer``)."""
    payload = records.get("regime_peer")
    return regime_peer(None if payload is None else payload.results)


class PeerRun(Training):
    label: str


class PeerComparison(Record):
    """One evaluation point: our seeds' returns beside the authors' one run."""

    label: str
    step: Steps
    ours: List[Return]
    mean: Return
    sd: NonNegative | None
    theirs: Return | None
    interval: List[Finite] | None
    inside: bool | None


class RegimePeerResults(Record):
    env: str
    runs: MaybeEmpty[PeerRun]
    comparison: MaybeEmpty[PeerComparison]


class RegimePeer(ResultsFile):
    results: RegimePeerResults
