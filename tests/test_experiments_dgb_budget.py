"""``sgb.experiments.dgb_budget``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import pytest
from committed import RECORDS, raw

from sgb.experiments import (
    dgb_budget,
)


def test_dgb_budget_table_has_one_row_per_record():
    budget = raw("dgb_budget_fashion-mnist_cpu.json")["results"]
    table = dgb_budget.dgb_budget_table(RECORDS("dgb_budget").results)
    assert table["rounds"].tolist() == [r["rounds"] for r in budget["records"]]
    assert table["its test %"].tolist() == pytest.approx(
        [100 * r["test_accuracy"] for r in budget["records"]]
    )
