"""``sgb.experiments.bet_hedging``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import json

import numpy as np

from sgb import (
    verdicts,
)
from sgb.experiments import (
    bet_hedging,
)


def test_bet_hedging_rows_credit_diversified_individuals_and_not_clones_of_clones():
    """Three genomes per spread. Wide: each individual thrives on some conditions and
    fails on others while the mean network fails everywhere but at home. Narrow: the
    individuals are the clones, so nothing differs."""

    rng = np.random.default_rng(4)
    genomes = []
    for rho, seed in ((-1.5, 0), (-1.5, 1), (-1.5, 2), (-5.0, 0), (-5.0, 1), (-5.0, 2)):
        # the clones: good at home; on the next condition a tenth of them pass 500
        home = np.r_[[1000.0, 372.0], np.full(2, 100.0)]
        clones = home[:, None, None] + rng.normal(0, 20, (4, 100, 5))
        clones[1] += rng.normal(0, 98, (100, 5))
        if rho == -1.5:
            niche = rng.integers(0, 4, 100)  # each individual's own good condition
            good = niche[None, :] == np.arange(4)[:, None]
            individuals = np.where(good, 900.0, 100.0)[:, :, None] + rng.normal(0, 20, (4, 100, 5))
        else:
            individuals = clones
        scale = float(clones[0].mean())
        genomes.append(
            {
                "rho_init": rho,
                "training_seed": seed,
                "sigma_trained": 0.2 if rho == -1.5 else 0.007,
                "scale": scale,
                "returns": {
                    "individuals": {"normal": individuals[0].tolist()},
                    "clones": {"normal": clones[0].tolist()},
                },
                "scores": bet_hedging.scores(individuals, clones, scale),
            }
        )
    results = json.loads(json.dumps({"genomes": genomes}))
    rows = bet_hedging.bet_hedging_rows(bet_hedging.BetHedgingResults.model_validate(results))
    wide, narrow = rows[:2], rows[2:]
    clones_p = [g["scores"]["clones"]["p_at_least"]["0.5"]["10"] for g in genomes[:3]]
    assert 0.25 < min(clones_p) < max(clones_p) < 0.5  # home, and the next condition by chance
    assert [r.key for r in wide] == ["ch6.hedging_geometric", "ch6.hedging_survival"]
    assert all(r.verdict in verdicts.IN_DIRECTION for r in wide) and len(wide) == 2
    assert wide[1].test.estimate > 0.5
    assert [r.verdict for r in narrow] == [verdicts.NOT_TESTABLE] * 2
    assert all("+0.00" in r.decide and r.setting.startswith("rho from -5") for r in narrow)
