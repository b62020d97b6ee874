"""Docstring conventions as ament_python packages check them: ament_pep257."""
from ament_pep257.main import main
from lint_targets import excluded, ROOT, targets
import pytest


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257(monkeypatch):
    monkeypatch.chdir(ROOT)
    rc = main(argv=[*targets(), '--exclude', *excluded()])
    assert rc == 0, 'docstring style errors (listed above)'
