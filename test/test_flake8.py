"""Style gate with ament_flake8's settings (setup.cfg [flake8])."""
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.linter
def test_flake8():
    names = ('digital_actor_planner', 'test', 'bench', 'launch', 'scripts', 'setup.py')
    targets = [p for p in names
               if os.path.exists(os.path.join(ROOT, p))]
    result = subprocess.run([sys.executable, '-m', 'flake8', *targets], cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == 0, 'flake8 found problems:\n' + result.stdout + result.stderr
