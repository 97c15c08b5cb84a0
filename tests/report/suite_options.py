"""The command line of the report's test programs: their required options, then unittest's own
arguments."""
import argparse
import sys
import unittest


def main(module, *options):
    """Reads the required options (--name VALUE) into module.ARGS, then runs the module's tests
    with the other arguments."""
    ap = argparse.ArgumentParser()
    for option in options:
        ap.add_argument(option, required=True)
    module.ARGS, rest = ap.parse_known_args()
    unittest.main(module=module, argv=[sys.argv[0]] + rest, verbosity=2)
