"""Compiled kernels: numba's ``njit`` when numba is installed, plain Python otherwise.

A kernel is written as plain loops over NumPy arrays, with an explicit signature, so numba
compiles it once when its module is imported (cached on disk next to the module, or in the
user's cache when that is read-only) and never while the actor is walking. Without numba the
same function runs as Python: the same results, many times slower. ``COMPILED`` says which.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

try:  # pragma: no cover - which branch runs depends on the installation
    import numba
except ImportError:  # pragma: no cover
    numba = None

#: Whether kernels are compiled (numba is installed).
COMPILED = numba is not None


def kernel(signature: str, inline: bool = False) -> Callable:
    """Decorator: compile ``function`` for ``signature`` if numba is installed, else return it
    unchanged. The plain function stays reachable as ``py_func`` either way (the tests compare
    the two).

    ``signature`` is numba's type string (``'f8(f8[::1], i8)'``), where ``readonly(T)`` is
    the array type T that also accepts read-only arrays (shared tables).
    ``inline``: numba compiles the kernel into every kernel that calls it (``inline='always'``)
    instead of calling it: for small helpers called many times from one kernel, whose call
    would cost more than their work (each array argument is reference counted at a call).
    """
    def wrap(function: Callable) -> Callable:
        if numba is None:
            function.py_func = function
            return function
        options = dict(nogil=True, inline='always' if inline else 'never')
        try:
            return numba.njit(_parse(signature), cache=True, **options)(function)
        except RuntimeError:
            # numba found nowhere writable to cache it (a read-only install and home):
            # compiled for this process alone.
            return numba.njit(_parse(signature), **options)(function)
    return wrap


def direct(function: Callable) -> Callable:
    """Kernel ``function``'s compiled code as Python calls it without numba's dispatch: no
    typing of the arguments to choose among signatures (a measurable share of a call as
    short as the footstep search's, more in a walk, where that code is out of the processor's
    caches). Only
    for a caller that passes exactly the signature's types and array layouts: it converts
    numbers and refuses what is not an array of the element type, but reads an array of
    another layout (not C-contiguous where the signature says ``::1``) as if it were one.
    Without numba, or with more than one signature, ``function`` itself.
    """
    overloads = getattr(function, 'overloads', None)
    if not overloads or len(overloads) != 1:
        return function
    return next(iter(overloads.values())).entry_point


def _parse(signature: str):
    """numba's signature string with ``readonly`` added to its type names."""
    names = dict(vars(numba.types))
    names['readonly'] = lambda array: array.copy(readonly=True)
    return eval(signature, {'__builtins__': {}}, names)


def float_array(array) -> np.ndarray:
    """``array`` as float64 that a compiled kernel accepts: a read-only or non-float one is
    copied, any other passed as it is."""
    array = np.asarray(array, dtype=np.float64)
    return array if array.flags.writeable else array.copy()
