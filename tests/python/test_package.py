"""The package as the build and the scripts use it: one copy in the build tree equal to the
source, imported by the scripts without path edits or readers of their own."""
import filecmp
import os
import re

import pytest

import lexdyn

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SOURCE = os.path.join(ROOT, "python", "lexdyn")


def test_the_build_tree_holds_the_package():
    build = os.environ.get("LEXDYN_BUILD_DIR")
    if not build:
        pytest.fail("LEXDYN_BUILD_DIR names the build directory (set by ctest)")
    copy = os.path.join(build, "python", "lexdyn")
    names = sorted(n for n in os.listdir(SOURCE) if n.endswith(".py"))
    assert names and sorted(n for n in os.listdir(copy) if n.endswith(".py")) == names
    for n in names:
        assert filecmp.cmp(os.path.join(SOURCE, n), os.path.join(copy, n), shallow=False), n


def test_the_package_is_this_checkouts():
    assert os.path.dirname(os.path.abspath(lexdyn.__file__)) == SOURCE
    assert issubclass(lexdyn.FormatError, ValueError)
    for name in lexdyn.__all__:
        assert hasattr(lexdyn, name), name


SCRIPTS = ["harness/scripts/report.py", "harness/scripts/plot_traces.py", "harness/scripts/second_order_table.py",
           "harness/scripts/lib/sim_accuracy.py"] + sorted(
    os.path.join("harness/scripts/lexdyn_report", n) for n in os.listdir(os.path.join(ROOT, "harness/scripts/lexdyn_report"))
    if n.endswith(".py"))


@pytest.mark.parametrize("script", SCRIPTS)
def test_scripts_read_through_the_package(script):
    with open(os.path.join(ROOT, script)) as f:
        text = f.read()
    assert "sys.path" not in text
    # No reader of a trace's rows of their own: no skipping of '#' lines, no CSV parsing.
    assert not re.search(r"startswith\(\"#\"\)|np\.loadtxt|np\.genfromtxt|csv\.reader|np\.fromstring", text), script
