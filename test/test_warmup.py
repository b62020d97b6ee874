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
import time

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


def test_a_second_warm_up_waits_for_the_first_instead_of_compiling_too(tmp_path, monkeypatch):
    import fcntl
    import threading
    stamp = tmp_path / 'stamp'
    monkeypatch.setattr(warmup, 'stamp_path', lambda: str(stamp))
    lines = []
    result = {}
    with open(str(stamp) + '.lock', 'a') as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)   # the first warm-up, compiling
        second = threading.Thread(target=lambda: result.update(
            took=warmup.warm_up(lines.append)))
        second.start()
        deadline = time.monotonic() + 60.0
        while not any('waiting' in line for line in lines) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert any('waiting' in line for line in lines), lines
        stamp.write_text(warmup.cache_key() + '\n')   # the first one is done
        fcntl.flock(lock, fcntl.LOCK_UN)
    second.join(timeout=60.0)
    assert result.get('took') == 0.0 and 'already compiled' in lines[-1], lines
