"""Under CI=true a test that skips fails, saying why; elsewhere it is reported as skipped."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

SKIPPING = """
import pytest

@pytest.mark.skipif(True, reason="qemu-i386 not installed")
def test_marked():
    pass

def test_inline():
    pytest.skip("clang not installed")

@pytest.mark.xfail(reason="known")
def test_expected_failure():
    assert False
"""


@pytest.fixture
def suite(pytester: pytest.Pytester) -> pytest.Pytester:
    pytester.makeconftest((Path(__file__).parent / "conftest.py").read_text())
    pytester.makepyfile(test_skipping=SKIPPING)
    return pytester


def test_a_skip_fails_under_ci_and_names_the_missing_tool(suite, monkeypatch):
    monkeypatch.setenv("CI", "true")
    result = suite.runpytest("-ra")
    result.assert_outcomes(failed=1, errors=1, xfailed=1)
    result.stdout.fnmatch_lines(["*skipped under CI=true*qemu-i386 not installed*",
                                 "*skipped under CI=true*clang not installed*"])


def test_a_skip_is_reported_with_its_reason_off_ci(suite, monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    result = suite.runpytest("-ra")
    result.assert_outcomes(skipped=2, xfailed=1)
    result.stdout.fnmatch_lines(["SKIPPED*qemu-i386 not installed",
                                 "SKIPPED*clang not installed"])
