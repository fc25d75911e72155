"""``sgb.experiments.rl_spread``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

from committed import RECORDS, raw

from sgb.experiments import rl_spread


def test_the_spread_table_is_the_runs_of_its_file():
    spread = raw("rl/spread_ant_cpu.json")
    table = rl_spread.spread_table(RECORDS("spread"))
    runs = spread["results"]["runs"]
    assert table["sigma trained"].tolist() == [r["sigma_trained"] for r in runs]
    assert table["paired t(99)"].tolist() == [r["paired_test"]["t"] for r in runs]
