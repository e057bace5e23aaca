"""Curve mathematics: the quintic B-spline of Li 2018, the motion laws, exact polynomial peaks and the
velocity-constrained B-spline problem of Yang 2022 with its solver. Imports only ``model``."""
