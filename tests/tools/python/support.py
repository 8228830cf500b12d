"""Shared by the Python tests (ctest label python, tests/tools/python.cmake): the runner and
bitwise float helpers. The module under test is found through PYTHONPATH (ctest sets it to the
build's tools/python directory)."""
import sys
import unittest

import numpy as np

SKIPPED = 77  # ctest SKIP_RETURN_CODE: every test of the file skipped (e.g. no data set)


def main():
    """unittest.main() whose exit code tells ctest 'skipped' when nothing ran."""
    program = unittest.main(exit=False, verbosity=2)
    result = program.result
    if not result.wasSuccessful():
        return 1
    if result.testsRun > 0 and len(result.skipped) == result.testsRun:
        return SKIPPED
    return 0


def f32_from_bits(hex_bits):
    """The float32 whose IEEE-754 bit pattern is the 8-hex-digit string."""
    return np.array([int(hex_bits, 16)], dtype=np.uint32).view(np.float32)[0]


def bits(values):
    """uint32 bit patterns of float32 values (scalars, sequences or arrays). A Python float must
    be exactly a float32 (asserted), so that comparing bits compares the values themselves."""
    a = np.asarray(values, dtype=np.float64)
    narrowed = a.astype(np.float32)
    exact = (narrowed.astype(np.float64) == a) | (np.isnan(a) & np.isnan(narrowed))
    if not np.all(exact):
        raise AssertionError(f"not float32 values: {a[~exact][:5]}")
    return narrowed.view(np.uint32)


if __name__ == "__main__":
    sys.exit("support.py is imported by the tests, not run")
