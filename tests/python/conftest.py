"""Shared fixtures of the lexdyn package's tests: the files the harness wrote in this ctest run
(LEXDYN_TEST_OUTPUTS, tests/python/write_outputs.sh) and copies of them to damage."""
import os
import shutil

import pytest


@pytest.fixture(scope="session")
def outputs():
    base = os.environ.get("LEXDYN_TEST_OUTPUTS")
    if not base or not os.path.isdir(base):
        pytest.fail("LEXDYN_TEST_OUTPUTS names the harness's outputs of this ctest run (fixture lexdyn_outputs: "
                    "tests/python/write_outputs.sh)")
    return base


@pytest.fixture
def copy_of(outputs, tmp_path):
    """copy_of("runs/x/trace.csv", name=None): a copy in a temporary folder of a file (or folder)
    the harness wrote, to be damaged by the test."""
    def make(rel, name=None):
        src = os.path.join(outputs, rel)
        dst = os.path.join(str(tmp_path), name or os.path.basename(rel))
        if os.path.isdir(src):
            shutil.copytree(src, dst)
        else:
            shutil.copyfile(src, dst)
        return dst
    return make
