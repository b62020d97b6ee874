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
The warm-up that set-up ends with.

It says what it does, stage by stage, and a second one returns at once while the sources are
unchanged.
"""
import subprocess
import sys

from digital_actor_planner import warmup


def test_warm_up_reports_every_stage_and_then_is_current(tmp_path, monkeypatch):
    stamp = tmp_path / 'stamp'
    monkeypatch.setattr(warmup, 'stamp_path', lambda: str(stamp))
    lines = []
    warmup.warm_up(lines.append, force=True)
    stages = [line for line in lines if '/' in line and '] ' in line]
    assert len(stages) == len(warmup.KERNEL_MODULES) + 2
    assert any('footstep_search kernels' in line for line in stages)
    assert stages[-1].split('] ', 1)[1].startswith('one step planned')
    assert all(line.rstrip().endswith(' s') for line in stages), 'each stage says how long'
    assert warmup.is_warm()
    again = []
    assert warmup.warm_up(again.append) == 0.0
    assert len(again) == 1 and 'already compiled' in again[0]


def test_changed_sources_make_the_cache_stale(tmp_path, monkeypatch):
    stamp = tmp_path / 'stamp'
    monkeypatch.setattr(warmup, 'stamp_path', lambda: str(stamp))
    stamp.write_text(warmup.cache_key() + '\n')
    assert warmup.is_warm()
    monkeypatch.setattr(warmup, 'cache_key', lambda: 'another source')
    assert not warmup.is_warm()


def test_the_command_line_says_whether_the_cache_is_current():
    result = subprocess.run([sys.executable, '-m', 'digital_actor_planner.cli', 'warm-up',
                             '--check'], capture_output=True, text=True, timeout=120)
    assert result.returncode in (0, 1), result.stderr
    assert 'kernel cache is' in result.stdout
    bad = subprocess.run([sys.executable, '-m', 'digital_actor_planner.cli', 'warm-up',
                          '--no-such-option'], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and 'no-such-option' in bad.stderr
