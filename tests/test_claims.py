"""``sgb.claims``: rows computed from synthetic results with known effects get the verdict
the rule gives those effects, and the committed scorecard gives every claim one verdict."""

import json

import numpy as np
import pytest

from sgb import claims, verdicts
from sgb.experiments import (
    fig3,
)
from sgb.experiments import populations as population_runs
from sgb.provenance import jsonable
from sgb.reliability import (
    detectable_between_sd,
    variance_split,
)


def _sweep(
    fall: float, seeds: int, rng, level: float = 3000.0, middle: float | None = None
) -> list:
    """Synthetic Figure 3 runs: vanilla at 4000, 128 types at ``level``, 16 at ``level`` -
    fall x 4000, and with ``middle`` 32 types there; seed SD 400."""
    runs = []
    arms = ((None, 4000.0), (128, level), (16, level - fall * 4000))
    for k, mean in arms + (((32, middle),) if middle is not None else ()):
        for seed in range(seeds):
            value = float(rng.normal(mean, 400))
            runs.append(
                {
                    "settings": "ours",
                    "cell_types": k,
                    "seed": seed,
                    "final_return": value,
                    "last_two_return": value,
                    "eval_steps": [0, 1, 2],
                    "eval_returns": [value / 2, value, value],
                }
            )
    return [fig3.Fig3Run.model_validate(r) for r in runs]


def test_figure3_verdicts_on_sweeps_with_known_falls():
    rng = np.random.default_rng(6)
    verdict = {
        (fall, seeds): {
            r.key: r.verdict for r in claims.figure3_rows(_sweep(fall, seeds, rng), "ant", 2e6)
        }["fig3.fall_16.ant"]
        for fall, seeds in ((0.5, 10), (0.0, 40), (0.3, 3))
    }
    assert verdict[(0.5, 10)] in verdicts.IN_DIRECTION
    assert verdict[(0.0, 40)] == verdicts.CONTRADICTED
    assert verdict[(0.3, 3)] in (verdicts.INCONCLUSIVE, verdicts.REPRODUCED)
    # where vanilla stands on the authors' scale, in every row's budget
    runs = _sweep(0.5, 10, rng)
    vanilla = claims.run_returns(runs, "ours", None, "last_two_return").mean()
    rows = claims.figure3_rows(runs, "ant", 2e6, on_authors_scale=lambda r: r / 8000)
    assert {r.budget.split(", 128")[0] for r in rows} == {
        f"2M steps, seeds: vanilla 10 (at {vanilla / 8000:.2f} of the authors' scale)"
    }


def test_the_falls_shape_on_sweeps_with_a_known_bend():
    """The drop from 32 to 16 types less the drop from 128 to 32, in fractions of vanilla:
    0.4 where the 32-type agents stay near the 128's and 0 for a straight decline."""
    rng = np.random.default_rng(8)

    def shape(middle: float, seeds: int) -> claims.Row:
        runs = _sweep(0.5, seeds, rng, middle=middle)
        (row,) = [r for r in claims.figure3_rows(runs, "ant", 2e6) if "shape" in r.key]
        return row

    bent = shape(2800.0, 10)  # (2800 - 1000) - (3000 - 2800) = 1600, 0.4 of vanilla
    assert bent.key == "fig3.shape_32.ant" and bent.verdict in verdicts.IN_DIRECTION
    assert bent.test.low < 0.4 < bent.test.high
    assert bent.budget.endswith("128 types 10, 16 types 10, 32 types 10")
    assert shape(2000.0, 40).verdict == verdicts.CONTRADICTED  # a straight line
    assert not [
        r for r in claims.figure3_rows(_sweep(0.5, 10, rng), "ant", 2e6) if "shape" in r.key
    ]


def test_a_fall_from_an_arm_near_the_floor_has_no_room_to_show_the_papers():
    """A sweep whose 128-type agents reach 0.2 of vanilla: a fall of 0.3 cannot show there
    (the 16-type agents would score below an agent that goes nowhere), so no outcome
    decides and the row says the room; the same sweep at 0.75 of vanilla has room, and
    its null fall is contradicted."""
    rng = np.random.default_rng(7)

    def fall_row(level: float) -> tuple[claims.Row, float]:
        runs = _sweep(0.0, 20, rng, level)
        (row,) = [r for r in claims.figure3_rows(runs, "ant", 2e6) if "fall" in r.key]
        top = claims.run_returns(runs, "ours", 128, "last_two_return").mean()
        return row, top / claims.run_returns(runs, "ours", None, "last_two_return").mean()

    floored, room = fall_row(800.0)
    assert floored.verdict == verdicts.NO_ROOM and floored.test is not None
    assert floored.decide.startswith(f"the largest effect possible here is {room:.2f} (")
    assert fall_row(3000.0)[0].verdict == verdicts.CONTRADICTED


def test_a_crossover_counts_only_the_sgb_overtaking_the_dgb():
    """The SGB above the DGB at low compression and below at high crosses the wrong way:
    no crossover (contradicted); curves whose simulated crossings come and go are
    inconclusive."""
    seeds = np.array([-0.01, 0.0, 0.01])
    ratios = (10.0, 100.0, 1000.0)
    sgb = {r: a + seeds for r, a in zip(ratios, (0.8, 0.7, 0.5), strict=True)}
    dgb = {r: a + seeds for r, a in zip(ratios, (0.7, 0.75, 0.6), strict=True)}
    wrong_way = claims.crossover_row(sgb, dgb, "toy", "fig2.crossover", "b", None)
    assert wrong_way.verdict == verdicts.CONTRADICTED and wrong_way.test is None
    right_way = claims.crossover_row(dgb, sgb, "toy", "fig2.crossover", "b", None)
    assert right_way.verdict == verdicts.REPRODUCED
    close = {r: v + 0.06 * (r == 1000.0) for r, v in sgb.items()}  # 0.56 vs 0.6: unsure
    wide = {r: v * 0 + v.mean() + np.array([-0.1, 0.0, 0.1]) for r, v in dgb.items()}
    unsure = claims.crossover_row(close, wide, "toy", "fig2.crossover", "b", None)
    assert unsure.verdict == verdicts.INCONCLUSIVE and unsure.decide.startswith("more seeds")


def _population_summary(rng, mean: float, between_sd: float, within_sd: float, k: int):
    """A populations summary's normal body of 100 simulated individuals x k episodes."""
    x = mean + rng.normal(0, between_sd, (100, 1)) + rng.normal(0, within_sd, (100, k))
    split = variance_split(x)
    normal = {
        "mean_return": float(x.mean()),
        "variance_split": split._asdict(),
        "between_sd": float(np.sqrt(split.between_var)),
    }
    stored = json.loads(json.dumps(jsonable(normal)))
    return population_runs.PopulationNormal.model_validate(stored)


def test_the_variability_row_finds_individuals_that_differ_and_rules_out_clones():
    """Against about 1 % of the return: individuals 5 % apart are a larger variability;
    clones measured closely contradict it; clones measured with noisy episodes leave it
    open, naming the episodes that would decide."""
    rng = np.random.default_rng(11)
    differ = claims.variability_row(_population_summary(rng, 1000, 50, 100, 32), "s")
    assert differ.verdict == verdicts.LARGER and differ.test.low > 1.0
    clones = claims.variability_row(_population_summary(rng, 1000, 0, 20, 64), "s")
    assert clones.verdict == verdicts.CONTRADICTED and clones.test.high < 1.0
    noisy = claims.variability_row(_population_summary(rng, 1000, 0, 1000, 4), "s")
    assert noisy.verdict == verdicts.INCONCLUSIVE
    episodes = int(noisy.decide.split()[0])
    assert episodes > 4 and detectable_between_sd(100, episodes, 1000) <= 10.0 * 1.02


def test_the_monotone_row_finds_a_steady_decline_and_rules_out_a_rise():
    """Four ratios, 3 seeds each: a decline of 5 points a step is monotone (its weakest
    step's interval above 0); a curve that climbs 5 points at one step is not (that step,
    the weakest, lies below 0); two steps of one point are no trend to judge."""
    rng = np.random.default_rng(0)
    noise = 0.002  # 0.2 points between seeds

    def curve(means):
        return {
            r: m + noise * rng.standard_normal(3)
            for r, m in zip((10, 50, 200, 700), means, strict=False)
        }

    steady = claims.monotone_row(curve([0.9, 0.85, 0.8, 0.75]), "toy", "b", None)
    assert steady.verdict in (verdicts.REPRODUCED, verdicts.LARGER)
    assert (
        steady.test.estimate == pytest.approx(5, abs=1) and "weakest of 3 steps" in steady.setting
    )
    rise = claims.monotone_row(curve([0.9, 0.85, 0.9, 0.8]), "toy", "b", None)
    assert rise.verdict == verdicts.CONTRADICTED and "50x to 200x" in rise.setting
    assert claims.monotone_row(curve([0.9, 0.89]), "toy", "b", None) is None
