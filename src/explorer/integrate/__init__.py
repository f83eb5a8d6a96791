"""Integration layer (docs/architecture.md): compiled stepping loops that drive the kernels with
the model's field.  Imports kernels and model only.
"""
