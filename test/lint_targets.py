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

"""What the linter tests check: the package's Python sources and the files not yet clean."""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The folders and files of Python source the linters read, relative to ROOT.
TARGETS = ('digital_actor_planner', 'test', 'bench', 'launch', 'scripts', 'setup.py')

# Files that do not pass the linters yet (docstring format, import order, quotes, the
# copyright header). They are left out of every linter test until they are fixed; the list
# must shrink to empty, and no file may be added to it.
NOT_YET_CLEAN = ()


def targets() -> list:
    """
    Return the linted folders and files that exist, as absolute paths.

    Returns
    -------
    list of str
        Absolute paths of the entries of ``TARGETS`` present in this checkout.

    """
    return [os.path.join(ROOT, name) for name in TARGETS
            if os.path.exists(os.path.join(ROOT, name))]


def excluded() -> list:
    """
    Return the absolute paths of ``NOT_YET_CLEAN``.

    Returns
    -------
    list of str
        One absolute path per file of ``NOT_YET_CLEAN``.

    """
    return [os.path.join(ROOT, name) for name in NOT_YET_CLEAN]
