# Copyright 2026 digital_actor_planner developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
Compiled kernels: numba's ``njit`` when numba is installed, plain Python otherwise.

A kernel is written as plain loops over NumPy arrays, with an explicit signature, so numba
compiles it once when its module is imported (cached on disk next to the module, or in the
user's cache when that is read-only) and never while the actor is walking. Without numba the
same function runs as Python: the same results, many times slower. ``COMPILED`` says which.

A numba that is installed but cannot compile a kernel (a distribution's older release that
lacks a NumPy feature the kernel uses) must not stop the planner: that kernel, and any that
calls it (numba cannot call Python from compiled code, so they fail likewise), runs as Python
instead, and the first such failure is reported once as a :class:`KernelCompileWarning`.
:func:`compile_failures` names them. A numba that fails on import with any error (one built
against another NumPy) leaves every kernel in Python, with one such warning.
"""
from __future__ import annotations

from typing import Callable, List, Tuple
import warnings

import numpy as np


class KernelCompileWarning(RuntimeWarning):
    """numba is installed but could not import or compile a kernel: it runs as plain Python."""


try:  # pragma: no cover - which branch runs depends on the installation
    import numba
except ImportError:  # pragma: no cover
    numba = None
except Exception as error:  # noqa: B902 - a numba that breaks on import leaves Python
    # (one built against another NumPy can fail with any error): plan in Python, say so once.
    numba = None
    warnings.warn(f'numba could not be imported ({type(error).__name__}: {error}); the '
                  'kernels run as plain Python: the same motion, planned more slowly. A numba '
                  'release that works here: see requirements.txt.', KernelCompileWarning)

#: Whether numba is installed (a kernel it failed to compile still runs as Python: see
#: :func:`compile_failures`).
COMPILED = numba is not None

# Kernels numba failed to compile, (qualified name, numba's first line), in import order: one
# record for the process, since the warning is given once for all of them.
_FAILURES: List[Tuple[str, str]] = []


def compile_failures() -> Tuple[Tuple[str, str], ...]:
    """Return the kernels numba could not compile in this process, as (name, reason) pairs."""
    return tuple(_FAILURES)


def kernel(signature: str, inline: bool = False) -> Callable:
    """
    Compile ``function`` for ``signature`` if numba is installed, else return it unchanged.

    Decorator: compile ``function`` for ``signature`` if numba is installed, else return it
    unchanged. The plain function stays reachable as ``py_func`` either way (the tests compare the
    two).

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
        try:
            return _compile(function, signature, inline)
        except Exception as error:  # noqa: B902 - any failure of numba's leaves Python
            return _as_python(function, error)
    return wrap


def _compile(function: Callable, signature: str, inline: bool) -> Callable:
    """Return ``function`` compiled by numba for ``signature`` (raises what numba raises)."""
    options = {'nogil': True, 'inline': 'always' if inline else 'never'}
    try:
        return numba.njit(_parse(signature), cache=True, **options)(function)
    except RuntimeError as error:
        if 'cache' not in str(error):
            raise
        # numba found nowhere writable to cache it (a read-only install and home):
        # compiled for this process alone.
        return numba.njit(_parse(signature), **options)(function)


def _as_python(function: Callable, error: Exception) -> Callable:
    """Return ``function`` as the plain-Python kernel, the failure recorded and warned of once."""
    name = f'{function.__module__}.{function.__qualname__}'
    # numba's first line names only the pipeline stage; the cause and place come after it.
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    causes = [line for line in lines if not line.startswith('Failed in')] or lines or ['']
    places = [line for line in lines if line.startswith('File "')]
    reason = f'{type(error).__name__}: {causes[0]}' + (f' at {places[-1]}' if places else '')
    _FAILURES.append((name, reason))
    if len(_FAILURES) == 1:
        warnings.warn(
            f'numba {numba.__version__} could not compile {name} ({reason}); it and any '
            'kernel that fails likewise run as plain Python: the same motion, planned more '
            'slowly. A numba release that compiles them: see requirements.txt.',
            KernelCompileWarning, stacklevel=3)
    function.py_func = function
    return function


def direct(function: Callable) -> Callable:
    """
    Return kernel ``function``'s compiled code as Python calls it without numba's dispatch.

    Kernel ``function``'s compiled code as Python calls it without numba's dispatch: no typing of
    the arguments to choose among signatures (a measurable share of a call as short as the footstep
    search's, more in a walk, where that code is out of the processor's caches). Only for a caller
    that passes exactly the signature's types and array layouts: it converts numbers and refuses
    what is not an array of the element type, but reads an array of another layout (not
    C-contiguous where the signature says ``::1``) as if it were one. Without numba, or with more
    than one signature, ``function`` itself.
    """
    overloads = getattr(function, 'overloads', None)
    if not overloads or len(overloads) != 1:
        return function
    return next(iter(overloads.values())).entry_point


def _parse(signature: str):
    """Return numba's signature string with ``readonly`` added to its type names."""
    names = dict(vars(numba.types))
    names['readonly'] = lambda array: array.copy(readonly=True)
    return eval(signature, {'__builtins__': {}}, names)


def float_array(array) -> np.ndarray:
    """
    Return ``array`` as float64 that a compiled kernel accepts.

    ``array`` as float64 that a compiled kernel accepts: a read-only or non-float one is copied,
    any other passed as it is.
    """
    array = np.asarray(array, dtype=np.float64)
    return array if array.flags.writeable else array.copy()
