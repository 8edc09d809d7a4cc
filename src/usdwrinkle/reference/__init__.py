"""Numpy oracles of the GPU passes: slow, obvious, and the tests' reference."""
