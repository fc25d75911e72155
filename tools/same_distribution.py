"""Do the individuals that today's code draws from a committed genome play as the committed
population's did? A check for changes that redraw individuals with other keys but must
keep their distribution (e.g. a new key derivation in ``sgb.genome.draw_noise``).

For one genome of ``results/rl/populations_ant_cpu.json``: draw N individuals with the
current code, play E episodes each on the normal body (the committed protocol otherwise),
and compare with the committed individuals: Welch's test of the mean of the individuals'
mean returns, the ratio of the spreads of those means after removing the episode noise
of each design, and a two-sample KS test of the pooled episode returns. Prints the numbers
and exits 1 if the means differ at p < 0.01.

    python tools/same_distribution.py [--genome ours_s0] [--individuals 100] [--episodes 4]
"""

import argparse
import sys
from dataclasses import replace

import numpy as np
from scipy import stats

from sgb.paths import committed_results
from sgb.provenance import read_results
from sgb.rl import checkpoints
from sgb.rl.population import population_returns
from sgb.verdicts import welch


def between_variance(returns: np.ndarray) -> float:
    """The variance between individuals' true mean returns, from returns (N, E): the
    variance of the individual means less the episode noise's share (one-way ANOVA)."""
    within = returns.var(axis=1, ddof=1).mean()
    return float(returns.mean(axis=1).var(ddof=1) - within / returns.shape[1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--genome", default=None, help="a key of the file's genomes (the first)")
    parser.add_argument("--individuals", type=int, default=100)
    parser.add_argument("--episodes", type=int, default=4)
    args = parser.parse_args()
    stored = read_results(committed_results() / "rl" / "populations_ant_cpu.json")
    results, length = stored["results"], stored["provenance"]["config"]["episode_length"]
    name = args.genome or next(iter(results["genomes"]))
    record = results["genomes"][name]
    committed = np.asarray(record["parts"]["normal"]["returns"], dtype=np.float64)
    ppo, params, normalizer, _ = checkpoints.load(committed_results() / record["checkpoint"])
    today = np.asarray(
        population_returns(
            replace(ppo.env, variant="normal"),
            ppo.network,
            params.actor,
            normalizer,
            args.individuals,
            args.episodes,
            length,
            seed=record["evaluation_seed"] + 1,  # other initial states than the committed
        ),
        dtype=np.float64,
    )
    test = welch(today.mean(axis=1), committed.mean(axis=1))
    ks = stats.ks_2samp(today.ravel(), committed.ravel())
    spread = np.sqrt(max(between_variance(today), 0.0) / max(between_variance(committed), 1e-12))
    print(
        f"genome {name}: (individuals, episodes) committed {committed.shape}, today {today.shape}"
    )
    print(f"mean return: committed {committed.mean():.1f}, today {today.mean():.1f}")
    interval = f"{test.estimate:.1f} [{test.low:.1f}, {test.high:.1f}]"
    print(f"Welch, today's population mean less the committed one: {interval}, p = {test.p:.3f}")
    print(f"SD between individuals, today / committed: {spread:.2f}")
    print(f"KS of the pooled episode returns: D = {ks.statistic:.3f}, p = {ks.pvalue:.3f}")
    return 1 if test.p < 0.01 else 0


if __name__ == "__main__":
    sys.exit(main())
