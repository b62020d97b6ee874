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

"""Code style as ament_python packages check it: ament_flake8 with ament's configuration."""
import os

from ament_flake8.main import main_with_errors
from lint_targets import excluded, ROOT, targets
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8(monkeypatch):
    # ament_flake8 looks for AMENT_IGNORE markers from the working directory down.
    monkeypatch.chdir(ROOT)
    rc, errors = main_with_errors(argv=[*targets(), '--exclude', *excluded()])
    assert rc == 0, f'{len(errors)} code style errors / warnings:\n' + '\n'.join(errors)


def test_the_files_left_out_exist():
    # A file renamed or removed must leave the list too, or the list hides nothing real.
    missing = [path for path in excluded() if not os.path.exists(path)]
    assert not missing, f'NOT_YET_CLEAN names files that do not exist: {missing}'
