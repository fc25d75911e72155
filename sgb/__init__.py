"""The stochastic genomic bottleneck (SGB): cell-type Bayesian networks in JAX."""

__version__ = "0.1.0"
