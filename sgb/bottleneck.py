"""The genomic-bottleneck arithmetic: bits to list a connectome, bits a genome holds,
and how many cell types a genome could afford under a cell-type wiring rule."""

import math


def _positive(name: str, value: float) -> None:
    if not value > 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")


def connectome_bits(neurons: float, synapses: float) -> float:
    """Bits to list every synapse by naming its target neuron: synapses * log2(neurons)."""
    _positive("neurons", neurons)
    _positive("synapses", synapses)
    return synapses * math.log2(neurons)


def genome_bits(base_pairs: float = 3.1e9, bits_per_base: float = 2.0) -> float:
    """Information capacity of a genome of ``base_pairs``, at most 2 bits per base."""
    _positive("base_pairs", base_pairs)
    _positive("bits_per_base", bits_per_base)
    return base_pairs * bits_per_base


def cell_type_rule_bits(cell_types: int, bits_per_parameter: float = 16.0) -> float:
    """Bits for a wiring rule of ``cell_types`` types: a mean and a spread per type pair."""
    _positive("cell_types", cell_types)
    _positive("bits_per_parameter", bits_per_parameter)
    return 2.0 * cell_types**2 * bits_per_parameter


def max_cell_types(available_bits: float, bits_per_parameter: float = 16.0) -> int:
    """The most cell types whose wiring rule fits in ``available_bits``."""
    _positive("available_bits", available_bits)
    _positive("bits_per_parameter", bits_per_parameter)
    return math.isqrt(int(available_bits / (2.0 * bits_per_parameter)))
