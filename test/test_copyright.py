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
