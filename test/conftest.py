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

"""Shared pytest configuration."""
import os

import pytest

ARTIFACTS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                         'test-artifacts')


def pytest_configure(config):
    config.addinivalue_line('markers', 'linter: style checks')
    config.addinivalue_line('markers', 'ros: starts real rclpy node processes')
    config.addinivalue_line('markers', 'browser: drives headless chromium')
    config.addinivalue_line('markers', 'slow: takes more than a few seconds')


@pytest.fixture(scope='session')
def skeleton():
    """Read the actor model from the package URDF (shared by the planner tests)."""
    from digital_actor_planner.core.skeleton import Skeleton
    return Skeleton()


@pytest.fixture
def artifacts_dir():
    """Return a folder for files a person may want to look at after the run (screenshots, logs)."""
    os.makedirs(ARTIFACTS, exist_ok=True)
    return ARTIFACTS
