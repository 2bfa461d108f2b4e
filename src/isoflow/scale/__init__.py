"""Where volumes live and how big work runs: host or GPU arrays (the array
API), compiled kernels, blocks of dask and zarr arrays, the memory budget.

The bottom floor: it imports nothing of isoflow but :mod:`isoflow.errors`.
See docs/architecture.md.
"""
