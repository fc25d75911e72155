"""``sgb.claims``: rows computed from synthetic results with known effects get the verdict
the rule gives those effects."""

import pytest

from sgb import claims, verdicts


def test_the_supervised_population_rows_pair_each_seeds_individuals_with_its_mean_network():
    """Cells with known leads: per synapse the individuals lead by 5 points, per type pair
    they trail by 3 (seed-to-seed spread 0.1); a lead shared by a seed's two numbers (its
    own level) cancels in the pairing."""
    cells = {}
    for variant, lead in (("authors", 5.0), ("per_pair", -3.0)):
        for seed, (level, wobble) in enumerate([(60.0, 0.1), (70.0, -0.1), (50.0, 0.0)]):
            mean_network = (level + wobble) / 100
            cells[f"{variant}{seed}"] = {
                "variant": variant,
                "setting": 30,
                "seed": seed,
                "compression": 198.0,
                "mean_network": mean_network,
                "accuracy": mean_network + (lead + wobble) / 100,
            }
    rows = claims.supervised_population_rows({"cells": cells}, "toy")
    assert [r.setting for r in rows] == [
        f"toy, the SGB ({claims.SGB_VARIANTS[v]}) at 198x" for v in ("authors", "per_pair")
    ]
    authors, per_pair = rows
    assert authors.test.estimate == pytest.approx(5.0) and authors.test.n == 3
    assert authors.verdict == verdicts.LARGER  # 5 points against the 1-point stand-in
    assert per_pair.test.estimate == pytest.approx(-3.0)
    assert per_pair.verdict == verdicts.CONTRADICTED


def _trajectory(gap: float, prediction: float) -> dict:
    return {
        "mu0": 0.15,
        "sigma0": 0.25,
        "gap": [-0.03, gap],
        "gap_stderr": [0.001, 0.0005],
        "prediction": [-0.03, prediction],
    }


def _network(gap: float, predicted: float) -> dict:
    trained = {
        "scale": 1.0,
        "predicted": predicted,
        "train_cross_entropy": {"gap": gap, "stderr": 1e-4},
    }
    return {"cell_types": [16, 8, 10], "scales": [{**trained, "scale": 0.5}, trained]}


def test_descent_rows_read_the_end_of_training_against_the_second_order_term():
    """A toy that ends below its mean network by about its second-order term reproduces
    Theorem A.2's conclusion; a network that ends above it contradicts it; the gap at half
    the trained sigma (scale 0.5) is not read."""
    theory = {
        "trajectories": {"nonconvex": _trajectory(-0.012, 0.0125)},
        "network": [_network(0.0115, 0.008)],
    }
    toy, network = claims.descent_rows(theory)
    assert toy.setting.startswith("1-D double well from mu 0.15, sigma 0.25, after 1 steps")
    assert toy.test.estimate == -0.012 and toy.paper_effect == -0.0125
    assert toy.verdict == verdicts.REPRODUCED
    assert network.setting.startswith("digits classifier, 16/8/10 types")
    assert network.test.estimate == 0.0115 and network.paper_effect == -0.008
    assert network.verdict == verdicts.CONTRADICTED
    with pytest.raises(ValueError, match="theorem.A.2"):
        claims.judge("theorem.A.2", "s", toy.test, "b")
