"""Look-up tables: the λ(, η) → (k1, k2) table of Li 2018 and the conveyor table of Yang 2022, their builders,
file formats and executors (process pool, Dask). Imports ``curves`` and ``model``."""
