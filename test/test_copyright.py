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
Copyright and license headers as ament_python packages check them: ament_copyright.

ament_copyright is not published on PyPI, so the test runs where ROS 2 installs it
(``rosdep install`` of the test dependencies) and is skipped elsewhere.
"""
from lint_targets import excluded, ROOT, targets
import pytest

copyright_main = pytest.importorskip('ament_copyright.main').main


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright(monkeypatch):
    monkeypatch.chdir(ROOT)
    rc = copyright_main(argv=[*targets(), '--exclude', *excluded()])
    assert rc == 0, 'files without a copyright notice and license (listed above)'
