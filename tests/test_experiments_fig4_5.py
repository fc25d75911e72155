"""``sgb.experiments.fig4_5``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import math

from committed import RECORDS, raw

from sgb import claims, gather, prose
from sgb.experiments import (
    fig4_5,
)
from sgb.paths import committed_results


def test_fig45_statistics_are_the_files_tests():
    fig4, fig5 = raw("rl/fig4_ant_cpu.json"), raw("rl/fig5_ant_cpu.json")
    table = fig4_5.fig45_statistics(RECORDS("fig4"), RECORDS("fig5")).set_index("test")
    legs = table.loc["Pearson r, normal body vs long legs"]
    assert legs["statistic"] == fig4["results"]["legs"]["r"]
    assert table.loc["Pearson r, slippery vs low gravity", "p"] == fig4["results"]["niches"]["p"]
    protocol = fig5["results"]["authors_protocol"]
    authors = table.loc["one-sample t (the authors' protocol)"]
    assert authors["statistic"] == protocol["t"]
    assert authors["mean network's return"] == protocol["mean_network_ci99"][0]
    assert math.isnan(legs["mean network's return"])


def test_the_variability_texts_are_the_rows_of_each_setting():
    """The regime's genomes, then each setting's genomes, as the scorecard's rows say."""
    card = claims.by_key(gather.scorecard(committed_results()))
    texts = fig4_5.variability(card)
    regime = card.get("title.variability.regime", [])
    assert texts["variability_regime"].count("**") == 2 * len(regime)
    for row in regime:
        assert (
            f"{prose.regime_setting(row)}: {row.ours} %, **{row.verdict}**"
            in texts["variability_regime"]
        )
    ours = [r for r in card["title.variability"] if ", our genome, " in r.setting]
    assert texts["variability_ours"].count("**") == 2 * len(ours) > 0
    assert set(fig4_5.variability({}).values()) == {prose.NOT_RUN}
