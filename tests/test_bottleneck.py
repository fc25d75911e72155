import math

import pytest

from sgb.bottleneck import cell_type_rule_bits, connectome_bits, genome_bits, max_cell_types


def test_human_scale_gap_is_about_six_orders_of_magnitude():
    gap = connectome_bits(1e11, 1e14) / genome_bits()
    assert 5.5 < math.log10(gap) < 6.5  # the paper's "about six orders of magnitude"


def test_max_cell_types_is_the_largest_rule_that_fits():
    for bits in (1e3, 1e6, 6.2e9):
        k = max_cell_types(bits)
        assert cell_type_rule_bits(k) <= bits < cell_type_rule_bits(k + 1)


@pytest.mark.parametrize(
    "call",
    [
        lambda: connectome_bits(0, 1),
        lambda: genome_bits(-1),
        lambda: max_cell_types(1e6, bits_per_parameter=0),
    ],
)
def test_bad_arguments_raise(call):
    with pytest.raises(ValueError, match="must be > 0"):
        call()
