"""``sgb.experiments.bet_hedging``: its rows of the scorecard on genomes with known effects,
and the deterministic lineage it rests on."""

import json
from types import SimpleNamespace

import jax
import numpy as np

from sgb import prose, verdicts
from sgb.experiments import bet_hedging
from sgb.experiments.bet_hedging import DETERMINISTIC_RHO, population_scores
from sgb.rl.agent import NetworkConfig, make_agent

EPISODES = 5  # selection episodes; as many retest


def _genome(rho: float, seed: int, individuals: np.ndarray, clones: np.ndarray | None) -> dict:
    """A genome's record from returns (C, N, 2E) of its populations."""
    home = individuals if clones is None else clones
    scale = float(home[0, :, :EPISODES].mean())
    populations = {"individuals": individuals} | ({} if clones is None else {"clones": clones})
    return {
        "rho_init": rho,
        "training_seed": seed,
        "sigma_trained": 1e-13 if clones is None else 0.05,
        "scale": scale,
        "returns": {p: {"normal": r[0].tolist()} for p, r in populations.items()},
        "scores": {p: population_scores(r, scale, EPISODES) for p, r in populations.items()},
    }


def _one_network(rng: np.random.Generator, luck: float = 0.2) -> np.ndarray:
    """Returns (4, 100, 2E) of one network's members: at home (1000) every one survives; on
    the second condition each episode passes 500 by ``luck`` alone (what passes once fails
    its retest as often as anyone); on the others none does."""
    returns = np.full((4, 100, 2 * EPISODES), 100.0) + rng.normal(0, 20, (4, 100, 2 * EPISODES))
    returns[0] += 900.0
    returns[1] = np.where(rng.random((100, 2 * EPISODES)) < luck, 600.0, 100.0)
    return returns


def test_the_rows_credit_individuals_whose_survivors_pass_again_and_not_episode_luck():
    """Middle spread: a member in eight owns a niche (every condition but home), where it
    passes every episode; the clones and the lineage pass the second condition by luck
    only, so their survivors rarely pass a retest. Narrow spread: the individuals are
    the clones, so nothing differs."""
    rng = np.random.default_rng(4)
    genomes = []
    for seed in range(4):
        clones = _one_network(rng)
        individuals = clones.copy()
        niche = rng.integers(1, 4, 100)
        owners = rng.random(100) < 1 / 8
        for c in (1, 2, 3):
            individuals[c, owners & (niche == c)] = 800.0
        genomes.append(_genome(-3.0, seed, individuals, clones))
        same = _one_network(rng)
        genomes.append(_genome(-5.0, seed, same, same))
        lineage = _one_network(rng, luck=0.03 * (seed + 1))  # twice in a row: rare
        genomes.append(_genome(DETERMINISTIC_RHO, seed, lineage, None))
    results = json.loads(json.dumps({"genomes": genomes}))
    rows = bet_hedging.bet_hedging_rows(bet_hedging.BetHedgingResults.model_validate(results))
    middle = [r for r in rows if r.setting.startswith("rho from -3 ")]
    narrow = [r for r in rows if r.setting.startswith("rho from -5 ")]
    keys = ["ch6.hedging_survival"] * 3 + ["ch6.hedging_geometric", "ch6.hedging_lineage"]
    assert [r.key for r in middle] == keys == [r.key for r in narrow]
    assert "at least 1 survive (declared in advance)" in middle[0].setting
    assert "(secondary)" in middle[1].setting and "at least 10" in middle[1].setting

    # the clones' luck: a survivor on the second condition passes its retest one time in
    # five, so about 20 x 0.2 x 0.2 = 0.8 members per generation pass both there
    clones = genomes[0]["scores"]["clones"]
    assert clones["p_at_least"]["0.5"]["10"] > 0.45  # home, and the second condition often
    assert clones["p_retested"]["0.5"]["10"] == 0.25  # home only: luck does not repeat
    individuals = genomes[0]["scores"]["individuals"]
    assert individuals["p_retested"]["0.5"]["1"] == 1.0  # some niche passes twice everywhere
    survival, lineage = middle[0], middle[4]
    assert survival.verdict in verdicts.IN_DIRECTION and survival.test.estimate > 0.3
    assert lineage.verdict in verdicts.IN_DIRECTION and lineage.test.estimate > 0.3
    # at least 50: only at home, where both populations all survive: nothing to test
    assert middle[2].verdict == verdicts.NOT_TESTABLE and "+0.00" in middle[2].decide
    for row in narrow[:4]:  # individuals are the clones
        assert row.verdict == verdicts.NOT_TESTABLE and "+0.00" in row.decide

    # chapter 6 tells each spread in one passage, its declared row first
    payload = SimpleNamespace(results=bet_hedging.BetHedgingResults.model_validate(results))
    texts = bet_hedging.bet_hedging(payload)
    assert texts["hedge_status"].startswith("genomes landed: rho from -5 4 of 15; ")
    assert "the lineage 4 of 15 (trained sigma" in texts["hedge_status"]
    passage = texts["hedge_middle"]
    assert passage.startswith("4 genomes, trained sigma ")
    declared = f"individuals minus clones: {survival.ours}, **{survival.verdict}** (would decide"
    assert declared in passage
    assert f"against the lineage: {lineage.ours}, **{lineage.verdict}**" in passage
    none = bet_hedging.bet_hedging(None)
    assert none["hedge_status"].startswith("not yet run: its 45 genomes")
    assert none["hedge_narrow"] == none["hedge_middle"] == prose.NOT_RUN


def test_the_deterministic_lineage_plays_its_mean_network_bit_for_bit():
    """From rho = DETERMINISTIC_RHO (sigma 9.4e-14) 100 individuals' kernels equal the mean
    network's exactly: the draw is below float32's resolution of every weight."""
    config = NetworkConfig(cell_types=64, rho_init=DETERMINISTIC_RHO)
    network = make_agent(config.architecture, 27, 8).actor
    params = network.init(jax.random.key(0), config)
    noise = jax.vmap(network.draw)(jax.random.split(jax.random.key(1), 100))
    individuals, mean = network.layers(params, noise), network.layers(params, None)
    drawn = 0
    for (kernel, bias), (mean_kernel, mean_bias) in zip(individuals, mean, strict=True):
        np.testing.assert_array_equal(kernel, np.broadcast_to(mean_kernel, kernel.shape))
        np.testing.assert_array_equal(bias, np.broadcast_to(mean_bias, bias.shape))
        drawn += kernel.ndim == 3
    assert drawn == 2  # both hidden layers are drawn, and draw nothing


def test_every_genome_is_queued_with_its_training_and_its_evaluation(tmp_path):
    """At cpu: 15 seeds of rho -5, -3 and the lineage, seed by seed; Figure 3's rho -5
    genomes at seeds 0-4 and the spread sweep's rho -3 at 0-2 are trained already."""
    queue = bet_hedging.queued("cpu", tmp_path)
    labels = [r.label for r in queue.runs]
    assert len(labels) == 45 and labels[:4] == [
        "rho -5 seed 0",
        "rho -3 seed 0",
        "sigma 0 seed 0",
        "rho -5 seed 1",
    ]
    trained = {r.label for r in queue.runs if r.chunks_done == r.chunks - 1}
    assert trained == {f"rho -5 seed {s}" for s in range(5)} | {
        f"rho -3 seed {s}" for s in range(3)
    }
    assert not any(r.finished for r in queue.runs)
    assert queue.results == tmp_path / "rl" / "bet_hedging_ant_cpu.json"
