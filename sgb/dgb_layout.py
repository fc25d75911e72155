"""A DGB's layout: which p-net parameters its g-nets generate, through which g-nets.

Each generated parameter has its own g-net (``GNetSpec``): a layer's kernel, generated
from the concatenated codes of each synapse's pre- and postsynaptic neurons, or a layer's
biases, from the codes of its neurons. Every other parameter is stored directly. Neuron
codes are the binary digits of the index for every layer but the output, which is
one-hot (``code_dims``).

- ``"ours"``: every kernel through a g-net code -> (width, 10) -> 1; every bias stored.
  The g-nets are fitted together, ``gnet_steps`` steps a round.
- ``"authors"``, as in ``supervised_learning/DGB/003_MNIST_automatic_2.py`` and
  ``geneNets2_0.py`` of the authors' repository: the hidden layers' kernels through
  (width, 10) and their biases through (10,) (``GDN3`` and ``GDN2`` in ``GNetList``); the
  output layer's kernel through (30,) at every width (``updateParameter("fc2.weight", ...,
  numGDNLayers=2, hidden=(30, 10))``) and its biases stored (``numGDNLayers=-1``). Each
  g-net is fitted on its own, a round being one epoch of its entries for a kernel and
  three for biases (``trainGNets(..., (1, 3))``), in minibatches of up to 1000.
"""

import math
from collections.abc import Sequence
from typing import NamedTuple

from sgb import validation

LAYOUTS = ("ours", "authors")
GNET_SECOND_HIDDEN = 10  # the second hidden layer of a kernel's g-net, in both layouts
AUTHORS_OUTPUT_GNET = (30,)
AUTHORS_BIAS_GNET = (10,)
AUTHORS_EPOCHS = {"kernel": 1, "bias": 3}


class GNetSpec(NamedTuple):
    """One g-net: what it generates (``"kernel"`` or ``"bias"`` of dense layer ``layer``),
    its hidden widths, and (authors' layout) how many epochs of its entries a round fits;
    ``None`` under ours, where every g-net fits ``gnet_steps`` steps together."""

    target: str
    layer: int
    hidden: tuple[int, ...]
    epochs: int | None


def code_dims(sizes: Sequence[int]) -> list[int]:
    """Length of each neuron layer's code: binary digits, one-hot at the output."""
    validation.integers("sizes", sizes)
    if len(sizes) < 2:
        raise ValueError(f"sizes needs at least an input and an output layer, got {sizes}")
    return [max(1, math.ceil(math.log2(n))) for n in sizes[:-1]] + [int(sizes[-1])]


def gnet_specs(sizes: Sequence[int], width: int, layout: str = "ours") -> list[GNetSpec]:
    """The g-nets of a DGB of the dense stack ``sizes`` whose kernels' g-nets have a first
    hidden layer of ``width``, in the order they are initialised and fitted."""
    validation.integer("width", width)
    validation.choice("layout", layout, LAYOUTS)
    layers = len(sizes) - 1
    kernel = (int(width), GNET_SECOND_HIDDEN)
    if layout == "ours":
        return [GNetSpec("kernel", i, kernel, None) for i in range(layers)]
    specs = []
    for i in range(layers - 1):
        specs.append(GNetSpec("kernel", i, kernel, AUTHORS_EPOCHS["kernel"]))
        specs.append(GNetSpec("bias", i, AUTHORS_BIAS_GNET, AUTHORS_EPOCHS["bias"]))
    specs.append(GNetSpec("kernel", layers - 1, AUTHORS_OUTPUT_GNET, AUTHORS_EPOCHS["kernel"]))
    return specs


def input_dim(spec: GNetSpec, dims: Sequence[int]) -> int:
    """A g-net's input length: pre + post code for a kernel, the neuron's code for biases."""
    post = dims[spec.layer + 1]
    return dims[spec.layer] + post if spec.target == "kernel" else post


def entries(spec: GNetSpec, sizes: Sequence[int]) -> int:
    """How many values the g-net generates: synapses of its layer, or its neurons."""
    post = int(sizes[spec.layer + 1])
    return int(sizes[spec.layer]) * post if spec.target == "kernel" else post


def stored_bias_layers(sizes: Sequence[int], specs: Sequence[GNetSpec]) -> list[int]:
    """The dense layers whose biases no g-net generates (they are stored directly)."""
    generated = {s.layer for s in specs if s.target == "bias"}
    return [i for i in range(len(sizes) - 1) if i not in generated]
