"""The DOP853 tableau of the compiled analytic path: scipy's coefficient table
(``scipy/integrate/_ivp/dop853_coefficients.py``, Hairer's Dormand-Prince 8(5,3) with its
dense output), the scheme the reference path integrates with ``solve_ivp``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["dop853_tableau"]


def _scipy_dop853():
    """scipy's module of DOP853 coefficients (plain numpy arrays), loaded from its file without
    importing ``scipy.integrate`` as a package, whose start-up (scipy.optimize, scipy.linalg:
    ~0.6 CPU s) a map command does not otherwise need; the package's import when the file is
    not where scipy keeps it."""
    import importlib.util

    import scipy

    path = Path(scipy.__file__).parent / "integrate" / "_ivp" / "dop853_coefficients.py"
    spec = importlib.util.spec_from_file_location("rockbench._scipy_dop853", path)
    if spec is None or spec.loader is None or not path.is_file():
        from scipy.integrate._ivp import dop853_coefficients as c
        return c
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def dop853_tableau() -> tuple:
    """(A, B, C, E3, E5, D, number of stages): the tableau as contiguous float64 arrays."""
    c = _scipy_dop853()
    return (np.ascontiguousarray(c.A, dtype=np.float64), np.ascontiguousarray(c.B, np.float64),
            np.ascontiguousarray(c.C, np.float64), np.ascontiguousarray(c.E3, np.float64),
            np.ascontiguousarray(c.E5, np.float64), np.ascontiguousarray(c.D, np.float64),
            c.N_STAGES)
