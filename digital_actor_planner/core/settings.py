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
One declaration per setting: name, type, default, range, description and unit.

A configuration dataclass declares each field with :func:`setting`; :func:`check_settings`
(called from the dataclass's ``__post_init__``) checks every field against its declaration and
raises :class:`ConfigError` naming the first bad one. The node's parameter descriptors and the
README's parameter table are built from the same declarations (``nodes/planner_params.py``).
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
import math
from typing import Any, Optional, Tuple

import numpy as np


class ConfigError(ValueError):
    """
    A setting's value the planner cannot run with.

    Attributes
    ----------
    name
        The setting (field or parameter) at fault.
    value
        Its bad value.

    """

    def __init__(self, name: str, value: Any, message: str):
        super().__init__(message)
        self.name = name
        self.value = value


@dataclass(frozen=True)
class Setting:
    """
    The declaration of one setting (the metadata of its dataclass field).

    ``low`` and ``high`` bound a number (None: unbounded on that side); ``low_open`` /
    ``high_open`` exclude the bound itself. ``choices`` lists the values a string may take.
    ``optional``: None is allowed too (no limit). ``kind`` is the value's type, taken from the
    default when not given. ``rule`` states a rule between this setting and another one, which
    the dataclass's ``__post_init__`` checks (e.g. ``'step_length_min < step_length_max'``).
    """

    default: Any
    low: Optional[float] = None
    high: Optional[float] = None
    doc: str = ''
    unit: str = ''
    low_open: bool = False
    high_open: bool = False
    choices: Tuple[str, ...] = ()
    optional: bool = False
    kind: type = object
    rule: str = ''

    def describe_range(self) -> str:
        """Return the allowed values in words ('' when any value of the type is)."""
        if self.choices:
            return 'one of ' + ', '.join(repr(c) for c in self.choices)
        if self.low is None and self.high is None:
            return ''
        if self.high is None:
            return f'{">" if self.low_open else ">="} {self.low:g}'
        if self.low is None:
            return f'{"<" if self.high_open else "<="} {self.high:g}'
        return (f'{"(" if self.low_open else "["}{self.low:g}, {self.high:g}'
                f'{")" if self.high_open else "]"}')

    def problem(self, value: Any) -> str:
        """Return what is wrong with ``value`` for this setting ('' when nothing is)."""
        if value is None and self.optional:
            return ''
        if self.kind is bool:
            return '' if isinstance(value, (bool, np.bool_)) else 'must be true or false'
        if self.kind is str:
            if not isinstance(value, str):
                return 'must be a string'
            if self.choices and value not in self.choices:
                return f'must be {self.describe_range()}'
            return ''
        if self.kind is tuple:
            return '' if isinstance(value, (tuple, list)) else 'must be a sequence'
        if self.kind is int:
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
                return self._expected('an integer')
        elif self.kind is float:
            if (isinstance(value, (bool, np.bool_))
                    or not isinstance(value, (int, float, np.integer, np.floating))
                    or not math.isfinite(value)):
                return self._expected('a finite number')
        else:
            return ''
        return '' if self._in_range(value) else self._expected(
            'an integer' if self.kind is int else 'a number')

    def _in_range(self, value) -> bool:
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            return False
        return self.high is None or (value < self.high if self.high_open else value <= self.high)

    def _expected(self, what: str) -> str:
        bounds = self.describe_range()
        unit = f' {self.unit}' if self.unit and bounds else ''
        return f'must be {what}' + (f' {"in " if bounds[:1] in "[(" else ""}{bounds}{unit}'
                                    if bounds else '')


def setting(default: Any, low: Optional[float] = None, high: Optional[float] = None,
            doc: str = '', unit: str = '', **options: Any):
    """
    Declare a dataclass field as a setting: its default, range, description and unit.

    Parameters
    ----------
    default
        The default value (its type is the setting's, unless ``kind`` is given).
    low, high
        The bounds of a number, inclusive unless ``low_open`` / ``high_open``; None: none.
    doc
        What the setting does, for a user (the node's parameter description).
    unit
        The unit of a number ('m', 's', 'rad', 'm/s', 'Hz', ...), '' for none.
    options
        ``low_open``, ``high_open``, ``choices``, ``optional``, ``kind``, ``rule`` of
        :class:`Setting`.

    Returns
    -------
    dataclasses.Field
        The field, with the :class:`Setting` as ``metadata['setting']``.

    """
    kind = options.pop('kind', None)
    if kind is None:
        kind = type(default) if not isinstance(default, (tuple, list)) else tuple
    declaration = Setting(default, low, high, doc, unit, kind=kind, **options)
    if isinstance(default, list):
        raise TypeError('a setting default must not be mutable; use a tuple')
    return field(default=default, metadata={'setting': declaration})


def declared_settings(config_class) -> dict:
    """Return ``{name: Setting}`` of a configuration dataclass (or instance), in field order."""
    return {f.name: f.metadata['setting'] for f in fields(config_class)
            if 'setting' in f.metadata}


def check_settings(config) -> None:
    """
    Check every declared field of ``config`` against its declaration.

    Raises
    ------
    ConfigError
        Naming the first field whose value has the wrong type or lies outside its range.

    """
    for name, declaration in declared_settings(config).items():
        value = getattr(config, name)
        problem = declaration.problem(value)
        if problem:
            raise ConfigError(name, value, f'{name} {problem}, got {value!r}')


def require(condition: bool, name: str, value: Any, message: str) -> None:
    """Raise :class:`ConfigError` naming ``name`` when a cross-field rule does not hold."""
    if not condition:
        raise ConfigError(name, value, message)
